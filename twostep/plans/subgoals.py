"""Whether a proposed helper subgoal is usable: the one owner of the subgoal rules.

Any decomposer's proposal goes through :func:`check_subgoal` before a helper plans for it.
A subgoal is rejected (:class:`SubgoalError`, whose message is the recorded reason) when

* it is not a PDDL goal of the task: syntax, unknown predicate or object, wrong arity
  (:func:`parse_subgoal`);
* it already holds where the helper starts (only when that state is given);
* it equals, includes or contradicts the full goal, or repeats an earlier helper's
  subgoal (:func:`goal_conflict`).

The LLM decomposer applies the rules that need no state right after translating an
answer; the pipeline applies all of them before planning the helper. A proposal's
life cycle is :class:`SubgoalStatus`.
"""

from __future__ import annotations

from collections.abc import Mapping

from twostep.pddl import Fact, Goal, PDDLError, Problem, fact_to_pddl, parse_goal
from twostep.util.outcome import SubgoalStatus as SubgoalStatus


class SubgoalError(ValueError):
    """A subgoal (or an answer meant to give one) that is no use; the message says why."""


def parse_subgoal(text: str, problem: Problem, source: str = "subgoal") -> Goal:
    """``text`` as a goal of ``problem``: known predicates and objects, right arity."""
    try:
        return parse_goal(text, problem, source=source)
    except PDDLError as error:
        raise SubgoalError(f"invalid PDDL subgoal: {error.message}") from None


def goal_conflict(
    goal: Goal, full_goal: Goal, earlier: Mapping[int, Goal] | None = None
) -> str | None:
    """Why ``goal`` cannot be a helper subgoal of ``full_goal`` whatever the state, or None.

    It equals or includes the full goal (nothing would be left for the main agent), asks
    for the opposite of a goal literal (the main agent would have to undo the helper's
    work), or repeats the subgoal of an ``earlier`` helper (helper number -> goal).
    """
    # A full goal with a formula (``exists``, ``forall``) may be more than its literals:
    # then a conjunction of literals neither equals nor includes it.
    literal_goal = full_goal.is_conjunction
    if literal_goal and goal.positive == full_goal.positive and goal.negative == full_goal.negative:
        return "equals the full goal"
    for fact in sorted(goal.negative & full_goal.positive):
        return f"contradicts the main goal: (not {fact_to_pddl(fact)}) undoes a goal fact"
    for fact in sorted(goal.positive & full_goal.negative):
        return f"contradicts the main goal: {fact_to_pddl(fact)} is negated in the goal"
    if literal_goal and full_goal.positive <= goal.positive and full_goal.negative <= goal.negative:
        return "includes the full goal: nothing would be left for the main agent"
    for helper, other in sorted((earlier or {}).items()):
        if goal.positive == other.positive and goal.negative == other.negative:
            return f"repeats the subgoal of agent{helper}"
    return None


def check_subgoal(
    text: str | None,
    problem: Problem,
    *,
    start: frozenset[Fact] | None = None,
    earlier: Mapping[int, Goal] | None = None,
    source: str = "subgoal",
) -> Goal:
    """The subgoal ``text`` as a goal of ``problem``, or :class:`SubgoalError` saying why not.

    ``start`` is the state the helper plans from (omit it to skip the "already true"
    rule); ``earlier`` maps earlier helpers to their subgoals.
    """
    if not text or not text.strip():
        raise SubgoalError("no PDDL subgoal")
    goal = parse_subgoal(text, problem, source)
    if start is not None and goal.holds(start):
        raise SubgoalError("already true in the helper's initial state")
    reason = goal_conflict(goal, problem.goal, earlier)
    if reason is not None:
        raise SubgoalError(reason)
    return goal


__all__ = [
    "SubgoalError",
    "SubgoalStatus",
    "check_subgoal",
    "goal_conflict",
    "parse_subgoal",
]
