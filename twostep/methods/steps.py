"""The steps a method calls, as replaceable functions: :class:`Steps`.

The library runs them directly (:data:`DIRECT`); ``flows/`` passes versions wrapped as
Prefect tasks without repeating any control flow. ``generate`` and ``translate`` are the
LLM decomposer's two calls (caching and retries stay in the LLM client), ``plan`` is the
planner call, ``progress`` the hand-off of the environment between agents and ``score``
the parallel execution length.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from typing import Protocol

from twostep.decomposers.base import LLMStep
from twostep.decomposers.llm import generate_subgoal, translate_subgoal
from twostep.execution import (
    DEFAULT_SEARCH_BUDGET,
    ParallelExecution,
    SearchBudget,
    parallel_length,
)
from twostep.pddl import Fact, Problem
from twostep.planner import PlannerSettings, PlanResult, plan
from twostep.progression import progress_state
from twostep.strips import Grounder


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
    plan: Callable[[Problem, PlannerSettings], PlanResult] = plan
    progress: Callable[[Problem, Sequence[str], Collection[str]], frozenset[Fact]] = progress
    score: ScoreStep = score


DIRECT = Steps()
"""The library's own functions."""
