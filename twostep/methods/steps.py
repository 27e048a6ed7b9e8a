"""The steps a method calls, as replaceable functions: :class:`Steps`.

The library runs them directly (:data:`DIRECT`); ``flows/`` passes versions wrapped as
Prefect tasks without repeating any control flow. ``generate`` and ``translate`` are the
LLM decomposer's two calls (caching and retries stay in the LLM client), ``plan`` is the
planner call, ``progress`` the hand-off of the environment between agents and ``score``
the parallel execution length.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Protocol

from twostep.decomposers.base import LLMStep
from twostep.decomposers.llm import generate_subgoal, translate_subgoal
from twostep.makespan import (
    DEFAULT_SEARCH_BUDGET,
    ParallelExecution,
    SearchBudget,
    parallel_length,
)
from twostep.pddl import Fact, Problem
from twostep.planner import PlannerSettings, PlanResult, plan
from twostep.plans.progression import progress_state
from twostep.plans.simulate import Grounder


def score(
    problem: Problem,
    plans: Sequence[Sequence[str]],
    agent_predicates: Collection[str],
    mode: str = "exact",
    budget: SearchBudget = DEFAULT_SEARCH_BUDGET,
) -> ParallelExecution:
    """Parallel execution length of per-agent plans given in hand-off order; ``budget``
    bounds the exact search (past it the result says ``exact=False``)."""
    grounder = Grounder(problem)
    grounded = [grounder.ground_plan(p) for p in plans]
    return parallel_length(
        grounded,
        problem.init,
        problem.goal,
        agent_predicates,
        mode,
        max_nodes=budget.max_nodes,
        time_limit_s=budget.time_limit_s,
    )


def progress(
    problem: Problem, plan_steps: Sequence[str], agent_predicates: Collection[str]
) -> frozenset[Fact]:
    """The environment after an agent runs ``plan_steps`` from ``problem``'s initial state."""
    return progress_state(problem.init, Grounder(problem).ground_plan(plan_steps), agent_predicates)


@dataclass(frozen=True)
class PlanCall:
    """Which of a method's planner calls a ``plan`` step makes: its role (``single``: the
    task itself, ``multi``: MA's compiled task, ``helper``, ``main``) and its agent, as the
    run's :class:`~twostep.methods.result.AgentPlan` records them."""

    role: str = "single"
    agent: str = "agent0"

    @property
    def name(self) -> str:
        """``sa``, ``ma``, ``helper agent1``, ``main agent0``."""
        return {"single": "sa", "multi": "ma"}.get(self.role) or f"{self.role} {self.agent}"


SA_CALL = PlanCall()


class PlanStep(Protocol):
    """A planner call: :func:`twostep.planner.plan` of ``problem`` with ``settings``;
    ``call`` says which one it is (for names and logs: never for the answer)."""

    def __call__(
        self, problem: Problem, settings: PlannerSettings, call: PlanCall = ...
    ) -> PlanResult: ...


class ProgressStep(Protocol):
    """:func:`progress`'s signature; ``agent``: whose plan moves the environment on."""

    def __call__(
        self,
        problem: Problem,
        plan_steps: Sequence[str],
        agent_predicates: Collection[str],
        agent: str = ...,
    ) -> frozenset[Fact]: ...


def plan_step(problem: Problem, settings: PlannerSettings, call: PlanCall = SA_CALL) -> PlanResult:
    """The library's planner call (``call`` only names it)."""
    return plan(problem, settings)


def progress_step(
    problem: Problem,
    plan_steps: Sequence[str],
    agent_predicates: Collection[str],
    agent: str = "",
) -> frozenset[Fact]:
    """:func:`progress` (``agent`` only names it)."""
    return progress(problem, plan_steps, agent_predicates)


class ScoreStep(Protocol):
    """:func:`score`'s signature."""

    def __call__(
        self,
        problem: Problem,
        plans: Sequence[Sequence[str]],
        agent_predicates: Collection[str],
        mode: str = ...,
        budget: SearchBudget = ...,
    ) -> ParallelExecution: ...


@dataclass(frozen=True)
class Steps:
    """The steps of the methods as replaceable functions (see the module docstring)."""

    generate: LLMStep = generate_subgoal
    translate: LLMStep = translate_subgoal
    plan: PlanStep = plan_step
    progress: ProgressStep = progress_step
    score: ScoreStep = score


DIRECT = Steps()
"""The library's own functions."""
