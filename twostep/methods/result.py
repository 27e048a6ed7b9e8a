"""What a method returns (:class:`RunResult`, the result.json shape), and the one place for
each rule the methods share when they fill it in:

* :func:`new_run` starts a run of a request;
* :func:`adopt_schedule` makes a scored joint schedule the run's outcome;
* :func:`adopt_sa_plan` makes the single-agent plan the outcome;
* :func:`longer_than_sa` decides when a joint schedule gives way to the SA plan
  (``fallback_if_longer``);
* :func:`count_sa_time` counts the SA plan's planner time in the run's planning time
  (:attr:`RunResult.sa_time_included_s`, result.json ``sa_time_included_s``);
* :func:`adopt_execution` adds an embodied execution to the run: one that did not reach
  the goal on the floor plan fails the run (``embodied_failed``), whatever the planners
  found;
* the vocabularies, as enums serialised to stable strings: :class:`MethodName`,
  :class:`RunStatus` and :class:`FallbackReason` (:class:`Fallback` is a reason and its
  details, as result.json's ``fallback`` text).

Plans and schedules always name the task's own actions (the grounded model is Fast
Downward's grounding of the task's own files: nothing is compiled, nothing is added);
:func:`check_run` re-validates a run's schedule against the task.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from twostep.decomposers.base import SubgoalProposal
from twostep.embodied.run import embodied_failure
from twostep.makespan import ParallelExecution, check_schedule
from twostep.methods.request import MethodRequest
from twostep.pddl import Problem
from twostep.planner import PlanResult
from twostep.plans.simulate import Grounder
from twostep.util.outcome import RunStatus as RunStatus


class MethodName(StrEnum):
    """The paper's methods as result.json's ``method`` names them. plan-deal and the
    portfolios are recorded as TwoStep runs (their ``decomposer`` says which), as they
    always were; a method added since records its own name (any string: the registry's,
    :data:`twostep.methods.registry.METHODS`)."""

    SA = "sa"
    MA = "ma"
    TWOSTEP = "twostep"


# Where a run's answer depends on its seed: the LLM's answers (the seed is part of every
# request) and the embodied executor's start cells and backoffs. Every other run is
# deterministic: its seeds repeat one run (same plans, same lengths; the planner's times
# of later seeds are the first seed's, from the planner cache).
SEEDED_DECOMPOSERS: frozenset[str] = frozenset({"llm"})
SEEDED_EXECUTORS: frozenset[str] = frozenset({"embodied"})


def seed_matters(method: str | None, decomposer: str | None, executor: str | None = None) -> bool:
    """Whether runs of ``method`` (``decomposer``, ``executor``) differ by seed; False: a
    deterministic method, one distinct run whatever the seed."""
    if executor is not None and str(executor) in SEEDED_EXECUTORS:
        return True
    return method == "twostep" and str(decomposer) in SEEDED_DECOMPOSERS


class FallbackReason(StrEnum):
    """Why a run's outcome is the single-agent plan (the kinds of result.json ``fallback``;
    plan-deal's single-agent plan is the SA plan after action elimination)."""

    NO_SUBGOAL_PROPOSED = "no helper subgoal proposed"
    NO_SUBGOAL_ACCEPTED = "no helper subgoal accepted"
    MAIN_AGENT_FAILED = "main agent after helpers"
    SCHEDULE_INVALID = "joint schedule invalid"
    LONGER_THAN_SA = "joint schedule longer than SA"
    ONE_AGENT = "one agent"
    NO_SA_PLAN = "no SA plan to deal"
    NO_DEAL = "no deal to two or more agents, the cleaned SA plan"  # plan-deal
    NO_SHORTER_DEAL = "no deal shorter than the cleaned SA plan"  # plan-deal
    NO_CANDIDATE_SOLVED = "no candidate solved"
    NO_CANDIDATE = "no candidate (one agent)"

    def describe(self, detail: str = "") -> str:
        """The recorded text: the reason, and its details when there are any."""
        if not detail:
            return self.value
        if self is FallbackReason.LONGER_THAN_SA:
            return f"{self.value} ({detail})"
        return f"{self.value}: {detail}"


class Fallback(str):
    """Result.json's ``fallback`` text, knowing its :class:`FallbackReason` and details."""

    reason: FallbackReason
    detail: str

    def __new__(cls, reason: FallbackReason, detail: str = "") -> Fallback:
        fallback = super().__new__(cls, reason.describe(detail))
        fallback.reason, fallback.detail = reason, detail
        return fallback

    def __reduce__(self) -> tuple[type[Fallback], tuple[FallbackReason, str]]:
        return Fallback, (self.reason, self.detail)


@dataclass
class AgentPlan:
    """One planner call of a run: which agent, towards which goal, and what came back."""

    agent: str
    role: str  # "single", "multi", "helper" or "main"
    goal: str
    result: PlanResult

    def to_dict(self) -> dict[str, Any]:
        return {"agent": self.agent, "role": self.role, "goal": self.goal, **self.result.to_dict()}


@dataclass
class RunResult:
    """What every method returns; :meth:`to_dict` is the result.json shape."""

    domain: str
    task: int
    method: str  # a MethodName, or the registry name of a method added since
    agents: int
    seed: int = 0
    success: bool = False
    exec_length: int | None = None
    exact: bool = True  # False when the scorer hit its node budget (exec_length is an upper bound)
    lower_bound: int | None = None  # the scorer's proven lower bound on exec_length
    sa_length: int | None = None
    sa_cost: int | None = None  # the SA plan's cost (its length unless the domain has costs)
    planning_time_s: float = 0.0
    llm_time_s: float = 0.0
    plans: dict[str, list[str]] = field(default_factory=dict)
    agent_order: list[str] = field(default_factory=list)  # hand-off order: who planned after whom
    schedule: list[list[tuple[str, str]]] = field(default_factory=list)
    subgoals: list[dict[str, Any]] = field(default_factory=list)
    decomposer: str | None = None
    status: RunStatus = RunStatus.SOLVED
    message: str = ""
    fallback: Fallback | None = None
    planner_calls: list[AgentPlan] = field(default_factory=list)
    state_editing_time_s: float = 0.0
    score_time_s: float = 0.0
    wall_time_s: float = 0.0
    scripted_llm: bool = False
    # The SA plan's planner time when it counts in planning_time_s (count_sa_time)
    sa_time_included_s: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        sa_time = (
            {"sa_time_included_s": round(self.sa_time_included_s, 4)}
            if self.sa_time_included_s is not None
            else {}
        )
        return {
            "domain": self.domain,
            "task": self.task,
            "method": str(self.method),
            "agents": self.agents,
            "seed": self.seed,
            "success": self.success,
            "exec_length": self.exec_length,
            "exact": self.exact,
            "lower_bound": self.lower_bound,
            "sa_length": self.sa_length,
            "sa_cost": self.sa_cost,
            "planning_time_s": round(self.planning_time_s, 4),
            "llm_time_s": round(self.llm_time_s, 4),
            "plans": self.plans,
            "agent_order": self.agent_order,
            "schedule": [[list(pair) for pair in step] for step in self.schedule],
            "subgoals": self.subgoals,
            "decomposer": self.decomposer,
            "status": self.status.value,
            "message": self.message,
            "fallback": None if self.fallback is None else str(self.fallback),
            "planner_calls": [c.to_dict() for c in self.planner_calls],
            "state_editing_time_s": round(self.state_editing_time_s, 6),
            "score_time_s": round(self.score_time_s, 6),
            "wall_time_s": round(self.wall_time_s, 4),
            "scripted_llm": self.scripted_llm,
            **self.extra,
            **sa_time,
        }


def new_run(request: MethodRequest, method: str) -> RunResult:
    """An empty run of ``method`` (a :class:`MethodName`, or a method's registry name) on
    the request's task (a single-agent run has 1 agent)."""
    agents = 1 if method == MethodName.SA else request.agents
    task = request.task
    run = RunResult(task.domain_name, task.task_id, method, agents, request.seed)
    run.sa_length = request.sa_length if method != MethodName.SA else None
    return run


def solved_steps(result: PlanResult | None) -> tuple[str, ...] | None:
    """The plan of a planner result that solved its task, else None."""
    if result is None or not result.solved or result.plan is None:
        return None
    return tuple(result.plan)


def adopt_schedule(
    run: RunResult,
    execution: ParallelExecution,
    names: Sequence[str],
    plans: Sequence[Sequence[str]],
) -> None:
    """Make the scored joint schedule of ``plans`` (agents ``names``, in hand-off order)
    the run's outcome."""
    run.agent_order = list(names)
    run.plans = {name: list(steps) for name, steps in zip(names, plans, strict=True)}
    run.schedule = [[(names[agent], action) for agent, action in step] for step in execution.steps]
    run.exec_length = execution.length
    run.exact, run.lower_bound = execution.exact, execution.lower_bound
    run.success = True


def adopt_sa_plan(run: RunResult, result: PlanResult) -> None:
    """Make ``result`` (one agent on the whole task) the run's outcome."""
    run.status = RunStatus(result.status.value)
    if not result.solved or result.plan is None:
        run.message = result.message
        return
    run.success = True
    run.plans = {"agent0": list(result.plan)}
    run.agent_order = ["agent0"]
    run.exec_length = len(result.plan)
    run.schedule = [[("agent0", a)] for a in result.plan]
    if run.sa_length is None:
        run.sa_length = len(result.plan)
        run.sa_cost = result.cost


def longer_than_sa(
    request: MethodRequest, length: int, sa_steps: Sequence[str] | None
) -> Fallback | None:
    """With ``fallback_if_longer`` and an SA plan at hand: the fallback of a joint schedule
    of ``length`` steps that is longer than the SA plan (None: the schedule stands)."""
    if not request.fallback_if_longer or sa_steps is None or length <= len(sa_steps):
        return None
    return Fallback(FallbackReason.LONGER_THAN_SA, f"{length} > {len(sa_steps)}")


def count_sa_time(run: RunResult, sa_plan: PlanResult) -> float:
    """Record that the SA plan's planner time counts in the run's planning time; return it."""
    run.sa_time_included_s = sa_plan.planner_time_s
    return sa_plan.planner_time_s


def adopt_execution(run: RunResult, fields: Mapping[str, Any]) -> None:
    """Add an embodied execution of the run's plans (``fields``:
    :func:`twostep.embodied.embodied_fields`) to the run. Any embodied status but
    ``success`` makes a successful run a failed one: ``status`` ``embodied_failed`` and
    the one-line verdict as its ``message`` (``embodied_failed: boxed_in at step 12,
    agent1``); the plans, the schedule and its symbolic length stay as found. A run that
    had already failed keeps its own status."""
    run.extra.update(fields)
    verdict = embodied_failure(fields)
    if verdict is not None and run.success:
        run.success = False
        run.status = RunStatus.EMBODIED_FAILED
        run.message = verdict


def record_proposals(run: RunResult, proposals: Sequence[SubgoalProposal]) -> None:
    """The proposals as result.json records them, with their LLM time; where answers were
    replayed from a bundle, ``answer_source`` says from where (``replayed, model gpt-4o,
    10_8_2_agent.txt:14``); where the rules translated, ``translation`` counts what they
    read and what they could not (``failed``: those subgoals are discarded)."""
    run.llm_time_s = sum(p.llm_time_s for p in proposals)
    exchanges = [x for p in proposals for x in p.exchanges]
    run.scripted_llm = any(x.get("scripted") for x in exchanges)
    run.subgoals = [p.to_dict() for p in proposals]
    sources = [x["source"] for x in exchanges if isinstance(x.get("source"), dict)]
    if sources:
        models = ", ".join(dict.fromkeys(str(s.get("model")) for s in sources))
        places = ", ".join(dict.fromkeys(f"{s.get('file')}:{s.get('line')}" for s in sources))
        run.extra["answer_source"] = f"replayed, model {models}, {places}"
        run.extra["answer_bundle"] = str(sources[0].get("bundle"))
    rules = [x for x in exchanges if x.get("translator") == "rules"]
    if rules:
        failed = sum(1 for x in rules if x.get("parsed") is None)
        run.extra["translation"] = {
            "translator": "rules",
            "read": len(rules) - failed,
            "failed": failed,
        }


def check_run(problem: Problem, run: RunResult, agent_predicates: Collection[str]) -> None:
    """Re-validate a run's joint schedule against the original ``problem`` by simulation.

    Raises :class:`~twostep.makespan.ScheduleError` (or :class:`PlanError` for a plan
    step the task does not know) when the schedule does not reach the goal.
    """
    grounder = Grounder(problem)
    index = {agent: i for i, agent in enumerate(run.agent_order)}
    plans = [grounder.ground_plan(run.plans[agent]) for agent in run.agent_order]
    steps = [tuple((index[agent], action) for agent, action in step) for step in run.schedule]
    check_schedule(steps, plans, problem.init, problem.goal, agent_predicates)
