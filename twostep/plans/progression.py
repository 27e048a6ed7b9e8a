"""State progression between agents: the paper's "editing initial state" step.

Each helper plans from the environment state that earlier helpers left behind. Facts of
the environment carry over from agent to agent; agent-specific facts (what an agent holds,
where it stands) do not: every agent starts from its own initial agent state, which is the
agent-specific part of the task's initial state. A state is the grounded model's
(:mod:`twostep.pddl.grounded`): effects with conditions are evaluated where the plan runs,
and derived facts are evaluated again wherever facts are joined.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

from twostep.pddl import Fact, Goal, Problem
from twostep.plans.simulate import GroundAction, simulate


def environment_part(state: frozenset[Fact], agent_predicates: Collection[str]) -> frozenset[Fact]:
    return frozenset(f for f in state if f[0] not in agent_predicates)


def agent_part(state: frozenset[Fact], agent_predicates: Collection[str]) -> frozenset[Fact]:
    return frozenset(f for f in state if f[0] in agent_predicates)


def progress_state(
    state: frozenset[Fact], plan: Sequence[GroundAction], agent_predicates: Collection[str]
) -> frozenset[Fact]:
    """The environment state after ``plan`` runs from ``state`` (agent facts dropped).

    Derived facts are dropped too: they depend on whose agent facts join the environment,
    and :func:`handoff_problem` derives them again for the next agent.
    """
    final = simulate(state, plan)
    axioms = next((action.axioms for action in plan if action.axioms), None)
    if axioms:
        final = final - axioms.derived
    return environment_part(final, agent_predicates)


def handoff_problem(
    problem: Problem, environment: frozenset[Fact], goal: Goal, agent_predicates: Collection[str]
) -> Problem:
    """The next agent's problem: the reached environment plus the agent's own initial state
    (closed under the task's axioms by :meth:`~twostep.pddl.Problem.with_state`)."""
    own = agent_part(problem.init, agent_predicates)
    return problem.with_state(environment_part(environment, agent_predicates) | own, goal)
