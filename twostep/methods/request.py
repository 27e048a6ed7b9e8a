"""What every method is asked: one task, N agents and the settings they share.

A :class:`MethodRequest` replaces the long parameter lists the methods once shared; each
method reads the fields it needs and ignores the rest (SA reads no agent predicates, MA
no decomposer). It also says how the request's steps are called, so that every method
plans and scores with the same settings.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass, field

from twostep.decomposers.base import Decomposer
from twostep.makespan import DEFAULT_SEARCH_BUDGET, ParallelExecution, SearchBudget
from twostep.methods.steps import DIRECT, SA_CALL, PlanCall, Steps
from twostep.pddl import Problem
from twostep.planner import PlannerSettings, PlanResult
from twostep.tasks.benchmark import BenchmarkTask


@dataclass(frozen=True)
class MethodRequest:
    """One task for ``agents`` agents, and how to plan and score it.

    ``agent_predicates`` are the predicates each agent has its own copy of (the domain's
    config declares them). ``decomposer`` is where TwoStep's helper subgoals come from.
    ``sa_plan`` is the single-agent planner result when the caller has it already (it is
    then not planned again); ``sa_length`` is the SA plan's length to report beside the
    run (a comparison solved apart). ``fallback_if_longer``: a joint schedule longer than
    the SA plan gives way to it. ``score_mode`` and ``search_budget`` are the parallel
    scorer's; ``steps`` the functions every call goes through (:class:`Steps`).
    """

    task: BenchmarkTask
    agents: int = 1
    planner: PlannerSettings = field(default_factory=PlannerSettings)
    agent_predicates: Collection[str] = ()
    decomposer: Decomposer | None = None
    seed: int = 0
    score_mode: str = "exact"
    search_budget: SearchBudget = DEFAULT_SEARCH_BUDGET
    steps: Steps = DIRECT
    fallback_if_longer: bool = True
    sa_plan: PlanResult | None = None
    sa_length: int | None = None

    def __post_init__(self) -> None:
        # a tuple, in the order given: the MA compilation lists the predicates in it
        object.__setattr__(self, "agent_predicates", tuple(self.agent_predicates))

    @property
    def problem(self) -> Problem:
        return self.task.problem

    def plan(
        self, problem: Problem, settings: PlannerSettings | None = None, call: PlanCall = SA_CALL
    ) -> PlanResult:
        """One planner call through the request's steps (default: the request's settings);
        ``call``: which one (its role and agent, for names and logs)."""
        return self.steps.plan(problem, settings or self.planner, call)

    def score(self, plans: Sequence[Sequence[str]]) -> ParallelExecution:
        """The parallel execution of ``plans`` (hand-off order) on the whole task."""
        return self.steps.score(
            self.problem, plans, self.agent_predicates, self.score_mode, self.search_budget
        )
