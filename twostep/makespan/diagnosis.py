"""Why plans have no joint schedule: agent-copy checks up front, hand-off simulation after;
and the one goal test at the end of a schedule."""

from __future__ import annotations

from collections.abc import Collection, Sequence

from twostep.makespan.model import ScheduleError, split_state
from twostep.pddl import Fact, Goal, fact_to_pddl
from twostep.pddl.grounded import Axioms
from twostep.plans.simulate import GroundAction


def missing_literal(
    positive: frozenset[Fact], negative: frozenset[Fact], state: frozenset[Fact]
) -> str | None:
    for fact in sorted(positive - state):
        return fact_to_pddl(fact)
    for fact in sorted(negative & state):
        return f"(not {fact_to_pddl(fact)})"
    return None


def precondition_error(agent: int, step: int, action: str, missing: str) -> ScheduleError:
    return ScheduleError(
        f"agent {agent} step {step} {action}: precondition {missing} does not hold",
        agent=agent,
        step=step,
        action=action,
        precondition=missing,
    )


def agent_goal_error(agent: int, literal: str) -> ScheduleError:
    return ScheduleError(
        f"goal literal {literal} does not hold for agent {agent} at the end "
        "(agent-specific goal literals must hold for every agent)",
        agent=agent,
        goal=literal,
    )


def check_agent_copies(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> None:
    """Fail early on what no schedule can fix: an agent's own copy breaks its plan or goal.

    Each copy evolves only through its owner's actions, so an agent-specific precondition
    that fails here fails in every schedule, and each copy's final content is fixed.
    """
    _, agent_init = split_state(init, agent_predicates)
    _, goal_positive = split_state(goal.positive, agent_predicates)
    _, goal_negative = split_state(goal.negative, agent_predicates)
    for agent, plan in enumerate(plans):
        copy = agent_init
        for step, action in enumerate(plan, start=1):
            _, positive = split_state(action.pre_positive, agent_predicates)
            _, negative = split_state(action.pre_negative, agent_predicates)
            missing = missing_literal(positive, negative, copy)
            if missing is not None:
                raise precondition_error(agent, step, str(action), missing)
            _, delete = split_state(action.delete, agent_predicates)
            _, add = split_state(action.add, agent_predicates)
            copy = (copy - delete) | add
        unmet = Goal(goal_positive, goal_negative).unmet(copy)
        if unmet:
            raise agent_goal_error(agent, unmet[0])


def check_goal(
    goal: Goal,
    environment: frozenset[Fact],
    copies: Sequence[frozenset[Fact]],
    agent_predicates: Collection[str],
    axioms: Axioms | None,
) -> None:
    """Raise :class:`ScheduleError` unless ``goal`` holds at the end: environment literals
    on the environment, agent-specific literals in every agent's copy, derived literals
    (a goal formula's included) in every agent's view (its copy and the environment,
    closed under the axioms)."""
    derived = axioms.derived if axioms else frozenset()
    basic = Goal(goal.positive - derived, goal.negative - derived)
    environment_goal = Goal(
        split_state(basic.positive, agent_predicates)[0],
        split_state(basic.negative, agent_predicates)[0],
    )
    unmet = environment_goal.unmet(environment)
    if unmet:
        raise ScheduleError(f"goal literal {unmet[0]} does not hold at the end", goal=unmet[0])
    agent_goal = Goal(
        split_state(basic.positive, agent_predicates)[1],
        split_state(basic.negative, agent_predicates)[1],
    )
    for agent, copy in enumerate(copies):
        unmet = agent_goal.unmet(copy)
        if unmet:
            raise agent_goal_error(agent, unmet[0])
    rest = Goal(goal.positive & derived, goal.negative & derived, goal.formula, goal.formula_facts)
    if not rest.positive and not rest.negative and not rest.formula_facts:
        return
    for agent, copy in enumerate(copies or [frozenset()]):
        state = environment | copy
        unmet = rest.unmet(axioms.close(state) if axioms else state)
        if unmet:
            raise ScheduleError(
                f"goal {unmet[-1]} does not hold for agent {agent} at the end",
                agent=agent,
                goal=unmet[-1],
            )


def diagnose(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> ScheduleError:
    """Why no schedule exists, found by running the plans in hand-off order.

    Hand-off order is itself a schedule, so when the search finds none, this simulation
    must fail somewhere; its first failure is what a user can act on.
    """
    axioms = next((a.axioms for plan in plans for a in plan if a.axioms), None)
    environment, agent_init = split_state(init, agent_predicates)
    copies = []
    for agent, plan in enumerate(plans):
        copy = agent_init
        for step, action in enumerate(plan, start=1):
            view = environment | copy
            view = axioms.close(view) if axioms else view
            missing = action.failing_precondition(view)
            if missing is not None:
                return precondition_error(agent, step, str(action), missing)
            environment, copy = split_state(action.apply(view), agent_predicates)
        copies.append(copy)
    try:
        check_goal(goal, environment, copies, agent_predicates, axioms)
    except ScheduleError as error:
        return error
    return ScheduleError("no joint schedule of the plans reaches the goal")
