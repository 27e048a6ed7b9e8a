"""The in-memory PDDL model every other module uses.

Small, immutable dataclasses: ground facts are tuples of lowercase names, goals are
conjunctions of ground literals, action schemas are STRIPS with negative preconditions and
(in)equality constraints.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace

Fact = tuple[str, ...]
"""A ground atom: predicate name followed by object names, all lowercase."""


@dataclass(frozen=True)
class Atom:
    """A possibly lifted atom; terms starting with ``?`` are action parameters."""

    predicate: str
    terms: tuple[str, ...]

    def ground(self, binding: Mapping[str, str]) -> Fact:
        return (self.predicate, *(binding.get(t, t) for t in self.terms))

    def __str__(self) -> str:
        return "(" + " ".join((self.predicate, *self.terms)) + ")"


@dataclass(frozen=True)
class ActionSchema:
    """A STRIPS action schema with negative preconditions and (in)equality constraints.

    ``cost`` is the action's constant cost in a domain with ``:action-costs`` (actions that
    do not increase ``total-cost`` cost 0 there) and None in a domain without costs, where
    every action costs 1.
    """

    name: str
    parameters: tuple[tuple[str, str], ...]  # (?variable, type)
    pre_positive: tuple[Atom, ...] = ()
    pre_negative: tuple[Atom, ...] = ()
    add: tuple[Atom, ...] = ()
    delete: tuple[Atom, ...] = ()
    equal: tuple[tuple[str, str], ...] = ()
    not_equal: tuple[tuple[str, str], ...] = ()
    cost: int | None = None
    """``(increase (total-cost) N)``: N in a domain with ``:action-costs``, else None."""


@dataclass(frozen=True)
class ActionOrigin:
    """Where a compiled action comes from (:mod:`twostep.pddl.adl`).

    ``name`` is the task's own action name (None for a goal action the compilation added)
    and ``arity`` its number of parameters: parameters after those were added for
    ``exists`` and are dropped when a plan is written in the task's own terms.
    """

    name: str | None
    arity: int


@dataclass(frozen=True, eq=False)
class Domain:
    """A planning domain: types, constants, predicates and action schemas."""

    name: str
    requirements: tuple[str, ...]
    types: dict[str, str | None]  # type -> parent type (None for roots)
    constants: dict[str, str]  # constant -> type
    predicates: dict[str, tuple[str, ...]]  # predicate -> parameter types
    actions: dict[str, ActionSchema]
    source: str | None = None
    origins: dict[str, ActionOrigin] = field(default_factory=dict)
    """Compiled action -> the task's own action; empty when the domain was STRIPS already."""

    @property
    def typed(self) -> bool:
        return any(t != "object" for t in self.types)

    def is_subtype(self, name: str | None, of: str) -> bool:
        """Whether type ``name`` is ``of`` or descends from it (cycles end the walk)."""
        seen: set[str] = set()
        while name is not None and name not in seen:
            if name == of:
                return True
            seen.add(name)
            name = self.types.get(name)
        return False

    @property
    def has_action_costs(self) -> bool:
        """True when actions have costs (``:action-costs``): a plan's cost is their sum."""
        return any(a.cost is not None for a in self.actions.values())

    @property
    def action_costs(self) -> dict[str, int]:
        """Action -> its non-zero cost (``:action-costs``); actions not listed cost 0."""
        return {name: a.cost for name, a in self.actions.items() if a.cost}


@dataclass(frozen=True)
class Goal:
    """A conjunction of ground literals."""

    positive: frozenset[Fact] = frozenset()
    negative: frozenset[Fact] = frozenset()

    def holds(self, state: frozenset[Fact] | set[Fact]) -> bool:
        return self.positive <= state and not (self.negative & state)

    def unmet(self, state: frozenset[Fact] | set[Fact]) -> list[str]:
        """The literals of this goal that do not hold in ``state``, as PDDL text."""
        missing = [fact_to_pddl(f) for f in sorted(self.positive - state)]
        missing += [f"(not {fact_to_pddl(f)})" for f in sorted(self.negative & state)]
        return missing

    def __len__(self) -> int:
        return len(self.positive) + len(self.negative)

    def to_pddl(self) -> str:
        lits = [fact_to_pddl(f) for f in sorted(self.positive)]
        lits += [f"(not {fact_to_pddl(f)})" for f in sorted(self.negative)]
        return "(and " + " ".join(lits) + ")" if lits else "(and)"


@dataclass(frozen=True, eq=False)
class Problem:
    """A planning problem together with its domain.

    ``objects`` holds the problem's own objects; the domain's constants are in
    ``domain.constants`` and both are in ``all_objects``.
    """

    name: str
    domain: Domain
    objects: dict[str, str]
    init: frozenset[Fact]
    goal: Goal
    source: str | None = None
    _all_objects: dict[str, str] = field(default_factory=dict, repr=False)

    @property
    def all_objects(self) -> dict[str, str]:
        if not self._all_objects:
            self._all_objects.update(self.domain.constants)
            self._all_objects.update(self.objects)
        return self._all_objects

    def with_state(self, init: Iterable[Fact] | None = None, goal: Goal | None = None) -> Problem:
        """The same problem from another initial state and/or towards another goal."""
        return replace(
            self,
            init=frozenset(init) if init is not None else self.init,
            goal=goal if goal is not None else self.goal,
            _all_objects={},
        )


def fact_to_pddl(fact: Fact) -> str:
    return "(" + " ".join(fact) + ")"
