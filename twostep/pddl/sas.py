"""Reading Fast Downward's translator output (``output.sas``) into the grounded model.

The format is the translator's documented one (version 3): variables with their value
names, mutex groups, the initial state, the goal, operators and axiom rules. Run with
``--full-encoding``, every value is named after its atom: ``Atom p(a, b)`` means the fact
``(p a b)`` is true, ``NegatedAtom p(a, b)`` that it is false, ``<none of those>`` that
every atom of the variable is false. Facts become tuples of names, as everywhere else.

Variables to facts
    A condition ``var = value`` is a positive literal (``Atom``), a negative literal
    (``NegatedAtom``), or the negation of every atom of the variable (``<none of
    those>``). An effect ``var := value`` adds the value's atom (if any) and deletes the
    variable's other atoms: the one that held (the effect's ``pre`` value, or the value an
    effect condition names) when it is known, else every other atom, which deletes just
    the one that held in any state the translator's invariants describe. The project runs
    the translator without invariant synthesis, so every variable is binary and every
    delete is a single, exact fact (see :mod:`twostep.pddl.translator`).

Operators
    Prevail conditions and effect ``pre`` values form the precondition; effects with
    conditions become :class:`~twostep.pddl.grounded.ConditionalEffect`. Operators that
    share a plan name (variants of a disjunctive or existential precondition) become one
    :class:`~twostep.pddl.grounded.GroundAction` with alternatives.

Axioms
    Derived variables (axiom layer >= 0) are false by default (their initial value; a
    derived variable whose default is its atom is rejected); each rule makes its head's
    atom true. Layers are kept as the translator assigns them.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence

from twostep.pddl.errors import PDDLError
from twostep.pddl.grounded import (
    AxiomRule,
    Axioms,
    ConditionalEffect,
    Fact,
    GroundAction,
    GroundTask,
)

_VALUE = re.compile(r"^(Atom|NegatedAtom) ([^(]*)\((.*)\)$")
NONE_OF_THOSE = "<none of those>"


def _value_fact(name: str) -> tuple[bool, Fact] | None:
    """(positive, fact) of a value name; None for ``<none of those>``."""
    if name == NONE_OF_THOSE:
        return None
    match = _VALUE.match(name)
    if match is None:
        raise PDDLError(f"unexpected value name {name!r} (run the translator with --full-encoding)")
    kind, predicate, args = match.groups()
    terms = tuple(a.strip() for a in args.split(",") if a.strip())
    return kind == "Atom", (predicate.strip(), *terms)


class _Variable:
    """A variable's values as literals and assignments (see the module docstring)."""

    def __init__(self, layer: int, values: list[tuple[bool, Fact] | None]):
        self.layer = layer
        self.values = values
        self.atoms = tuple(v[1] for v in values if v is not None and v[0])
        # per value: the fact it makes true (None: no atom), and the facts it makes false
        self.true: list[Fact | None] = [v[1] if v is not None and v[0] else None for v in values]
        self.false: list[tuple[Fact, ...]] = [
            self.atoms if v is None else () if v[0] else (v[1],) for v in values
        ]

    def assign(self, value: int, known: int | None) -> tuple[Fact | None, tuple[Fact, ...]]:
        """(added fact, deleted facts) of ``var := value``; ``known``: its value before."""
        added = self.true[value]
        if known is not None:
            before = self.true[known]
            return added, () if known == value or before is None else (before,)
        return added, tuple(a for a in self.atoms if a != added)


class _Reader:
    def __init__(self, text: str):
        self.lines = text.split("\n")
        self.at = 0

    def next(self) -> str:
        if self.at >= len(self.lines):
            raise PDDLError("translator output ends early", "output.sas", self.at)
        self.at += 1
        return self.lines[self.at - 1].strip()

    def number(self) -> int:
        line = self.next()
        try:
            return int(line)
        except ValueError:
            raise PDDLError(f"expected a number, got {line!r}", "output.sas", self.at) from None

    def expect(self, word: str) -> None:
        line = self.next()
        if line != word:
            raise PDDLError(f"expected {word!r}, got {line!r}", "output.sas", self.at)

    def block(self, count: int) -> list[list[int]]:
        """The next ``count`` lines as lists of numbers."""
        start = self.at
        self.at += count
        try:
            return [[int(x) for x in line.split()] for line in self.lines[start : self.at]]
        except ValueError:
            raise PDDLError("expected numbers", "output.sas", start + 1) from None

    def raw(self, count: int) -> list[str]:
        """The next ``count`` lines as they are."""
        start = self.at
        self.at += count
        return self.lines[start : self.at]


class _Literals:
    """``var value`` lines to (positive facts, negative facts), each line read once: large
    tasks repeat the same condition lines thousands of times."""

    def __init__(self, variables: list[_Variable]):
        self.variables = variables
        self.known: dict[str, tuple[Fact | None, tuple[Fact, ...]]] = {}

    def read(self, lines: Iterable[str]) -> tuple[frozenset[Fact], frozenset[Fact]]:
        positive: list[Fact] = []
        negative: list[Fact] = []
        known = self.known
        for line in lines:
            entry = known.get(line)
            if entry is None:
                try:
                    var, value = (int(x) for x in line.split())
                except ValueError:
                    raise PDDLError(f"expected a variable and a value, got {line!r}") from None
                variable = self.variables[var]
                entry = known[line] = (variable.true[value], variable.false[value])
            if entry[0] is not None:
                positive.append(entry[0])
            negative.extend(entry[1])
        return frozenset(positive), frozenset(negative)


def _conditions(
    variables: list[_Variable], pairs: Iterable[Sequence[int]]
) -> tuple[frozenset[Fact], frozenset[Fact]]:
    positive: list[Fact] = []
    negative: list[Fact] = []
    for var, value in pairs:
        variable = variables[var]
        fact = variable.true[value]
        if fact is not None:
            positive.append(fact)
        negative.extend(variable.false[value])
    return frozenset(positive), frozenset(negative)


def read_sas(text: str) -> GroundTask:
    """The grounded task of a translator output (see the module docstring)."""
    lines = _Reader(text)
    lines.expect("begin_version")
    version = lines.number()
    if version != 3:
        raise PDDLError(f"translator output version {version}, expected 3", "output.sas")
    lines.expect("end_version")
    lines.expect("begin_metric")
    action_costs = lines.number() == 1
    lines.expect("end_metric")
    variables: list[_Variable] = []
    for _ in range(lines.number()):
        lines.expect("begin_variable")
        lines.next()  # its name
        layer = lines.number()
        values = [_value_fact(lines.next()) for _ in range(lines.number())]
        lines.expect("end_variable")
        variables.append(_Variable(layer, values))
    for _ in range(lines.number()):  # mutex groups: not needed
        lines.expect("begin_mutex_group")
        lines.block(lines.number())
        lines.expect("end_mutex_group")
    lines.expect("begin_state")
    initial = [lines.number() for _ in variables]
    lines.expect("end_state")
    lines.expect("begin_goal")
    goal_positive, goal_negative = _conditions(variables, lines.block(lines.number()))
    lines.expect("end_goal")

    derived: set[Fact] = set()
    for variable, value in zip(variables, initial, strict=True):
        if variable.layer < 0:
            continue
        if variable.true[value] is not None:
            raise PDDLError(
                f"derived variable with a true default value ({variable.true[value]}): "
                "not supported",
                "output.sas",
            )
        derived.update(variable.atoms)

    _Operator = tuple[str, tuple[str, ...], frozenset[Fact], frozenset[Fact], frozenset[Fact],
                      frozenset[Fact], tuple[ConditionalEffect, ...], int]  # fmt: skip
    operators: dict[str, list[_Operator]] = {}
    literals = _Literals(variables)
    for _ in range(lines.number()):
        lines.expect("begin_operator")
        name, *args = lines.next().split()
        prevail = lines.raw(lines.number())
        pre_pairs: list[list[int]] = []
        add: set[Fact] = set()
        delete: set[Fact] = set()
        effects: list[ConditionalEffect] = []
        for numbers in lines.block(lines.number()):
            count = numbers[0]
            var, before, after = numbers[1 + 2 * count : 4 + 2 * count]
            known: int | None = None
            if before != -1:
                pre_pairs.append([var, before])
                known = before
            conditions = [numbers[1 + 2 * k : 3 + 2 * k] for k in range(count)]
            for cond_var, cond_value in conditions:
                if cond_var == var and known is None:
                    known = cond_value
            added, deleted = variables[var].assign(after, known)
            if conditions:
                positive, negative = _conditions(variables, conditions)
                effects.append(
                    ConditionalEffect(
                        positive,
                        negative,
                        frozenset(() if added is None else (added,)),
                        frozenset(deleted),
                    )
                )
            else:
                if added is not None:
                    add.add(added)
                delete.update(deleted)
        cost = lines.number()
        lines.expect("end_operator")
        pre_positive, pre_negative = literals.read(prevail)
        if pre_pairs:
            more_positive, more_negative = _conditions(variables, pre_pairs)
            pre_positive |= more_positive
            pre_negative |= more_negative
        key = "(" + " ".join((name, *args)) + ")"
        operators.setdefault(key, []).append(
            (name, tuple(args), pre_positive, pre_negative, frozenset(add),
             frozenset(delete - add), tuple(effects), cost if action_costs else 1)
        )  # fmt: skip

    rules: list[AxiomRule] = []
    for _ in range(lines.number()):
        lines.expect("begin_rule")
        conditions = lines.block(lines.number())
        var, _before, after = (int(x) for x in lines.next().split())
        lines.expect("end_rule")
        head = variables[var].true[after]
        if head is None:
            raise PDDLError("an axiom that derives a negated value: not supported", "output.sas")
        positive, negative = _conditions(variables, conditions)
        rules.append(AxiomRule(head, tuple(sorted(positive)), tuple(sorted(negative)),
                               variables[var].layer))  # fmt: skip
    axioms = Axioms(rules, derived)
    closing = axioms if axioms else None
    actions: dict[str, GroundAction] = {}
    for key, (first, *others) in operators.items():
        alternatives = tuple(GroundAction(*other, (), closing) for other in others)
        actions[key] = GroundAction(*first, alternatives, closing)
    return GroundTask(actions, axioms, goal_positive, goal_negative, action_costs)
