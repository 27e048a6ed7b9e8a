"""Plans over the grounded model: parsing plan text, looking actions up, simulating.

A state is a closed ``frozenset`` of :data:`~twostep.pddl.Fact` and a ground action a
:class:`~twostep.pddl.grounded.GroundAction` (preconditions, effects with conditions,
cost): the grounded model of :mod:`twostep.pddl.grounded`, which is Fast Downward's own
grounding of the task. Plans are sequences of action strings in Fast Downward's format,
``(pickup b1)``; :class:`Grounder` looks them up in a problem's grounded task, so
simulation and scoring are set operations in memory.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from twostep.pddl import Fact, Problem
from twostep.pddl.grounded import (
    ConditionalEffect,
    GroundAction,
    PlanError,
    parse_action,
)

__all__ = [
    "ConditionalEffect",
    "GroundAction",
    "Grounder",
    "PlanError",
    "effects_along",
    "parse_action",
    "read_plan",
    "simulate",
]


def read_plan(text: str) -> list[str]:
    """Read a plan file in Fast Downward's format: one action per line, ``;`` comments."""
    actions = []
    for line in text.splitlines():
        line = line.split(";", 1)[0].strip()
        if line:
            name, args = parse_action(line)
            actions.append("(" + " ".join((name, *args)) + ")")
    return actions


class Grounder:
    """Plan text to the problem's ground actions; unknown ones explained (lifted checks)."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self._task = problem.grounded

    def ground(self, action: str) -> GroundAction:
        found = self._task.actions.get(action)
        if found is not None:
            return found
        name, args = parse_action(action)
        found = self._task.actions.get("(" + " ".join((name, *args)) + ")")
        if found is not None:
            return found
        schema = self.problem.domain.actions.get(name)
        if schema is None:
            raise PlanError(f"unknown action '{name}' in {action}")
        if len(args) != len(schema.parameters):
            raise PlanError(
                f"{action}: '{name}' takes {len(schema.parameters)} argument(s), got {len(args)}"
            )
        objects = self.problem.all_objects
        for arg in args:
            if arg not in objects:
                raise PlanError(f"{action}: unknown object '{arg}'")
        raise PlanError(
            f"{action}: never applicable in this task (Fast Downward grounds no such action: "
            "a static precondition, a type or an equality rules it out)"
        )

    def ground_plan(self, plan: Iterable[str]) -> list[GroundAction]:
        return [self.ground(a) for a in plan]


def effects_along(
    state: frozenset[Fact], plan: Sequence[GroundAction]
) -> list[tuple[frozenset[Fact], frozenset[Fact]]]:
    """Each step's (adds, deletes) as the plan runs from ``state`` (conditional effects as
    they fire there); raise :class:`PlanError` at the first inapplicable step."""
    if all(action.is_strips for action in plan):
        return [(action.add, action.delete) for action in plan]
    effects = []
    for step, action in enumerate(plan, start=1):
        if not action.applicable(state):
            missing = action.failing_precondition(state)
            raise PlanError(f"step {step} {action}: precondition {missing} does not hold")
        effects.append(action.effect_in(state))
        state = action.apply(state)
    return effects


def simulate(state: frozenset[Fact], plan: Sequence[GroundAction]) -> frozenset[Fact]:
    """Apply ``plan`` from ``state``; raise :class:`PlanError` at the first inapplicable step."""
    for step, action in enumerate(plan, start=1):
        if not action.applicable(state):
            missing = action.failing_precondition(state)
            raise PlanError(f"step {step} {action}: precondition {missing} does not hold")
        state = action.apply(state)
    return state
