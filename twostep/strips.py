"""Grounded STRIPS actions and states: the one state representation of the project.

A state is a ``frozenset`` of :data:`~twostep.pddl.Fact`. Plans are sequences of action
strings in Fast Downward's format, ``(pickup b1)``; :class:`Grounder` turns them into
:class:`GroundAction` objects (precondition, add and delete sets) once, with a cache, so
simulation and scoring are set operations in memory.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from twostep.pddl import Fact, Problem, fact_to_pddl


class PlanError(Exception):
    """A plan that names an unknown action or object, or cannot be applied."""


@dataclass(frozen=True)
class GroundAction:
    """One ground action: its name and arguments, preconditions and effects."""

    name: str
    args: tuple[str, ...]
    pre_positive: frozenset[Fact]
    pre_negative: frozenset[Fact]
    add: frozenset[Fact]
    delete: frozenset[Fact]

    def __str__(self) -> str:
        return "(" + " ".join((self.name, *self.args)) + ")"

    @property
    def facts(self) -> frozenset[Fact]:
        """Every fact the action reads or writes."""
        return self.pre_positive | self.pre_negative | self.add | self.delete

    def applicable(self, state: frozenset[Fact] | set[Fact]) -> bool:
        return self.pre_positive <= state and not (self.pre_negative & state)

    def failing_precondition(self, state: frozenset[Fact] | set[Fact]) -> str | None:
        """The first precondition that does not hold in ``state``, as PDDL, or None."""
        for fact in sorted(self.pre_positive - state):
            return fact_to_pddl(fact)
        for fact in sorted(self.pre_negative & state):
            return f"(not {fact_to_pddl(fact)})"
        return None

    def apply(self, state: frozenset[Fact]) -> frozenset[Fact]:
        """The successor state (delete before add, as in PDDL)."""
        return (state - self.delete) | self.add


def parse_action(text: str) -> tuple[str, tuple[str, ...]]:
    """Split ``"(stack b1 b2)"`` (or ``"stack b1 b2"``) into name and arguments."""
    words = text.strip().strip("()").lower().split()
    if not words:
        raise PlanError(f"empty action {text!r}")
    return words[0], tuple(words[1:])


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
    """Grounds action strings against one problem's domain and objects, with a cache."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self._objects = problem.all_objects
        self._cache: dict[str, GroundAction] = {}

    def ground(self, action: str) -> GroundAction:
        cached = self._cache.get(action)
        if cached is not None:
            return cached
        name, args = parse_action(action)
        schema = self.problem.domain.actions.get(name)
        if schema is None:
            raise PlanError(f"unknown action '{name}' in {action}")
        if len(args) != len(schema.parameters):
            raise PlanError(
                f"{action}: '{name}' takes {len(schema.parameters)} argument(s), got {len(args)}"
            )
        for arg in args:
            if arg not in self._objects:
                raise PlanError(f"{action}: unknown object '{arg}'")
        binding = {var: arg for (var, _), arg in zip(schema.parameters, args, strict=True)}
        for x, y in schema.equal:
            if binding.get(x, x) != binding.get(y, y):
                raise PlanError(f"{action}: requires {x} = {y}")
        for x, y in schema.not_equal:
            if binding.get(x, x) == binding.get(y, y):
                raise PlanError(f"{action}: requires {x} != {y}")
        ground = GroundAction(
            name,
            args,
            frozenset(a.ground(binding) for a in schema.pre_positive),
            frozenset(a.ground(binding) for a in schema.pre_negative),
            frozenset(a.ground(binding) for a in schema.add),
            frozenset(a.ground(binding) for a in schema.delete),
        )
        self._cache[action] = ground
        return ground

    def ground_plan(self, plan: Iterable[str]) -> list[GroundAction]:
        return [self.ground(a) for a in plan]


def simulate(state: frozenset[Fact], plan: Sequence[GroundAction]) -> frozenset[Fact]:
    """Apply ``plan`` from ``state``; raise :class:`PlanError` at the first inapplicable step."""
    for step, action in enumerate(plan, start=1):
        missing = action.failing_precondition(state)
        if missing is not None:
            raise PlanError(f"step {step} {action}: precondition {missing} does not hold")
        state = action.apply(state)
    return state
