"""The in-memory PDDL model every other module uses: the lifted task and its grounding.

The *lifted* level is what the files say, read by :mod:`twostep.pddl.lifted`: types,
constants, predicates, functions, action schemas and derived predicates (each with its
formulas as s-expressions and a summary of the literals they use), objects, the initial
state, the goal. It serves the multi-agent compilation, subgoal checks (predicates,
objects, arity), prompts and describers. Problems keep their files' s-expressions, so
that the planner receives the user's own PDDL (:mod:`twostep.pddl.writer`).

The *grounded* level (:class:`~twostep.pddl.grounded.GroundTask`, the translator's task:
ground actions with conditional effects, costs and axioms) gives the semantics: states,
applicability, successors, derived facts. A problem grounds itself on first use
(:attr:`Problem.grounded`); a problem whose meaning needs the grounding at once (derived
facts in the initial state, a goal that is a formula) is grounded when it is read.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace

from twostep.pddl.grounded import Fact, GroundTask, fact_to_pddl
from twostep.pddl.sexp import SExp, write_sexp

__all__ = [
    "ActionSchema",
    "Atom",
    "DerivedPredicate",
    "Domain",
    "Fact",
    "Goal",
    "Problem",
    "fact_to_pddl",
]


@dataclass(frozen=True)
class Atom:
    """A possibly lifted atom; terms starting with ``?`` are variables."""

    predicate: str
    terms: tuple[str, ...]

    def ground(self, binding: Mapping[str, str]) -> Fact:
        return (self.predicate, *(binding.get(t, t) for t in self.terms))

    def __str__(self) -> str:
        return "(" + " ".join((self.predicate, *self.terms)) + ")"


@dataclass(frozen=True, eq=False)
class ActionSchema:
    """An action schema as written, with a summary of its literals.

    ``precondition`` and ``effect`` are the formulas as read (lowercase s-expressions,
    ``[]`` for none). The summary: ``pre_positive``/``pre_negative`` and
    ``equal``/``not_equal`` are the literals of the precondition's top-level conjunction
    (a disjunction or quantifier inside contributes none); ``add``/``delete`` are every
    atom the effect may add or delete, conditional and universal effects included (their
    terms may be the effect's own quantified variables). ``cost`` is the constant of
    ``(increase (total-cost) N)``; None when the action has no such constant (no cost
    effect, or a cost computed from functions: the grounded action has the value).
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
    precondition: SExp = field(default_factory=list)
    effect: SExp = field(default_factory=list)
    is_strips: bool = True
    """Whether the precondition is a conjunction of literals and the effect one of atoms,
    negated atoms and cost increases (no ``when``, no quantifiers, no disjunction)."""

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ActionSchema):
            return NotImplemented
        return (
            self.name == other.name
            and self.parameters == other.parameters
            and (
                write_sexp(self.precondition),
                write_sexp(self.effect),
            )
            == (write_sexp(other.precondition), write_sexp(other.effect))
        )

    def __hash__(self) -> int:
        return hash((self.name, self.parameters))


@dataclass(frozen=True, eq=False)
class DerivedPredicate:
    """A ``(:derived (name ?x - t ...) formula)`` rule (a predicate may have several)."""

    name: str
    parameters: tuple[tuple[str, str], ...]
    formula: SExp


@dataclass(frozen=True, eq=False)
class Domain:
    """A planning domain: types, constants, predicates, functions, actions, derived rules.

    ``body`` is the domain's ``define`` as s-expressions (after the repairs of
    :mod:`twostep.pddl.repairs`, if any were needed) and ``text`` the PDDL the planner
    receives: the file as it is when no repair was needed.
    """

    name: str
    requirements: tuple[str, ...]
    types: dict[str, str | None]  # type -> parent type (None for roots)
    constants: dict[str, str]  # constant -> type
    predicates: dict[str, tuple[str, ...]]  # predicate -> parameter types
    actions: dict[str, ActionSchema]
    source: str | None = None
    functions: dict[str, tuple[str, ...]] = field(default_factory=dict)
    derived: tuple[DerivedPredicate, ...] = ()
    body: list[SExp] = field(default_factory=list, repr=False)
    text: str | None = field(default=None, repr=False)

    @property
    def typed(self) -> bool:
        return any(t != "object" for t in self.types)

    def is_subtype(self, name: str | None, of: str) -> bool:
        """Whether type ``name`` is ``of`` or descends from it (cycles end the walk);
        ``of`` may be an ``(either a b)`` type."""
        if of.startswith("(either"):
            return any(self.is_subtype(name, t) for t in of.strip("()").split()[1:])
        if of == "object":
            return True
        seen: set[str] = set()
        while name is not None and name not in seen:
            if name == of:
                return True
            seen.add(name)
            name = self.types.get(name)
        return False

    @property
    def derived_predicates(self) -> frozenset[str]:
        return frozenset(d.name for d in self.derived)

    def is_derived(self, fact: Fact) -> bool:
        """Whether ``fact`` is derived (a ``:derived`` predicate, or one the translator
        introduced, whose names contain ``@``): never written as an initial fact."""
        return fact[0] in self.derived_predicates or "@" in fact[0]

    @property
    def has_action_costs(self) -> bool:
        """True when actions have costs (``:action-costs``): a plan's cost is their sum."""
        return ":action-costs" in self.requirements or any(
            a.cost is not None for a in self.actions.values()
        )

    @property
    def action_costs(self) -> dict[str, int]:
        """Action -> its non-zero constant cost; actions not listed cost 0 (or, with
        costs computed from functions, what their grounded actions say)."""
        return {name: a.cost for name, a in self.actions.items() if a.cost}

    @property
    def is_strips(self) -> bool:
        """Every action STRIPS and no derived predicates: no axioms can arise."""
        return not self.derived and all(a.is_strips for a in self.actions.values())


@dataclass(frozen=True)
class Goal:
    """A goal: a conjunction of ground literals, or a formula.

    ``positive`` and ``negative`` are the goal's literals. A goal that is more than a
    conjunction of literals (quantifiers, disjunctions: AlfWorld's ``exists``) keeps its
    ``formula``, and its truth comes from the grounded task: ``formula_facts`` are the
    facts (derived by the translator's axioms) that hold exactly when it does. Its
    literals are then those of its top-level conjunction, or, when the task's static facts
    leave one way to meet it (one egg, one counter), that one conjunction
    (``literals_complete``: the literals say all the goal says).
    """

    positive: frozenset[Fact] = frozenset()
    negative: frozenset[Fact] = frozenset()
    formula: SExp | None = field(default=None, compare=False)
    formula_facts: frozenset[Fact] = frozenset()
    literals_complete: bool = field(default=False, compare=False)

    @property
    def is_conjunction(self) -> bool:
        """Whether ``positive`` and ``negative`` say everything the goal says."""
        return self.formula is None or self.literals_complete

    def holds(self, state: frozenset[Fact] | set[Fact]) -> bool:
        return (
            self.positive <= state and not (self.negative & state) and self.formula_facts <= state
        )

    def unmet(self, state: frozenset[Fact] | set[Fact]) -> list[str]:
        """The literals of this goal that do not hold in ``state``, as PDDL text (a goal
        formula that does not hold is listed whole)."""
        missing = [fact_to_pddl(f) for f in sorted(self.positive - state)]
        missing += [f"(not {fact_to_pddl(f)})" for f in sorted(self.negative & state)]
        if self.formula is not None and not self.formula_facts <= state:
            missing.append(write_sexp(self.formula))
        return missing

    def __len__(self) -> int:
        return len(self.positive) + len(self.negative) + (self.formula is not None)

    def to_pddl(self) -> str:
        if self.formula is not None:
            return write_sexp(self.formula)
        lits = [fact_to_pddl(f) for f in sorted(self.positive)]
        lits += [f"(not {fact_to_pddl(f)})" for f in sorted(self.negative)]
        return "(and " + " ".join(lits) + ")" if lits else "(and)"


class _Grounding:
    """A problem's grounded task, made on first use and shared by its variants."""

    def __init__(self, make: Callable[[], GroundTask] | None, task: GroundTask | None = None):
        self.make = make
        self.task = task

    def get(self) -> GroundTask:
        if self.task is None:
            assert self.make is not None
            self.task = self.make()
        return self.task

    def __getstate__(self) -> dict[str, object]:
        return {"task": self.get()}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.make = None
        self.task = state["task"]  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class Problem:
    """A planning problem together with its domain.

    ``objects`` holds the problem's own objects; the domain's constants are in
    ``domain.constants`` and both are in ``all_objects``. ``init`` is the initial state
    (closed under the task's axioms: derived facts included); ``numeric_init`` the
    ``(= (f ...) n)`` entries of the file, kept for the planner. ``body`` is the file's
    ``define`` as s-expressions and ``text`` the file itself while the problem is the
    file's own (None once ``with_state`` changed it).
    """

    name: str
    domain: Domain
    objects: dict[str, str]
    init: frozenset[Fact]
    goal: Goal
    source: str | None = None
    _all_objects: dict[str, str] = field(default_factory=dict, repr=False)
    numeric_init: tuple[SExp, ...] = field(default=(), repr=False)
    body: list[SExp] = field(default_factory=list, repr=False)
    text: str | None = field(default=None, repr=False)
    _grounding: _Grounding | None = field(default=None, repr=False)

    @property
    def all_objects(self) -> dict[str, str]:
        if not self._all_objects:
            self._all_objects.update(self.domain.constants)
            self._all_objects.update(self.objects)
        return self._all_objects

    @property
    def grounded(self) -> GroundTask:
        """The task Fast Downward's translator grounds from this problem's PDDL."""
        return self._shared_grounding().get()

    @property
    def is_grounded(self) -> bool:
        return self._grounding is not None and self._grounding.task is not None

    @property
    def needs_axioms(self) -> bool:
        """Whether states may hold derived facts (then they are closed by the grounding)."""
        return not self.domain.is_strips or self.goal.formula is not None

    def _shared_grounding(self) -> _Grounding:
        if self._grounding is None:
            object.__setattr__(self, "_grounding", _Grounding(lambda: _ground(self)))
        assert self._grounding is not None
        return self._grounding

    def close(self, facts: Iterable[Fact]) -> frozenset[Fact]:
        """``facts`` as a state of this task: derived facts evaluated by its axioms."""
        if self.needs_axioms or self.is_grounded:
            return self.grounded.close(facts)
        return facts if isinstance(facts, frozenset) else frozenset(facts)

    def with_state(self, init: Iterable[Fact] | None = None, goal: Goal | None = None) -> Problem:
        """The same problem from another initial state and/or towards another goal.

        The new initial state is closed under the task's axioms; the grounding is shared
        (every state reached from the initial one grounds to a part of it).
        """
        self._shared_grounding()
        return replace(
            self,
            init=self.close(init) if init is not None else self.init,
            goal=goal if goal is not None else self.goal,
            _all_objects={},
            text=None if (init is not None or goal is not None) else self.text,
        )


_grounder: list[Callable[[Problem], GroundTask]] = []


def set_grounder(ground: Callable[[Problem], GroundTask]) -> None:
    """Who grounds a problem on first use of :attr:`Problem.grounded`: the loader,
    :func:`twostep.pddl.reader.ground_problem` (Fast Downward's translator), sets itself when
    it is imported (``twostep.pddl`` imports it), so the data model imports no reader."""
    _grounder[:] = [ground]


def _ground(problem: Problem) -> GroundTask:
    if not _grounder:
        raise RuntimeError("no grounder set: import twostep.pddl (its reader grounds problems)")
    return _grounder[0](problem)
