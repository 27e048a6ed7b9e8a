"""The lifted reader: domain and problem s-expressions into the model, as Fast Downward reads them.

Our own reader on :mod:`twostep.pddl.sexp`, chosen for robustness and speed: it accepts
what Fast Downward's translator accepts (typing, ``either``, constants, ADL formulas,
``when`` and ``forall`` effects, derived predicates, functions and numeric initial values
for costs, missing or odd ``:requirements``, a predicate declared with one parameter name
twice, commas in variable lists), reads a large task in milliseconds, and names file and
line for what it rejects (an unknown predicate or object). It decides nothing about
meaning: the translator grounds the task (:mod:`twostep.pddl.translator`).
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterator
from dataclasses import dataclass

from twostep.pddl.errors import PDDLError
from twostep.pddl.model import ActionSchema, Atom, DerivedPredicate, Domain, Fact, Goal
from twostep.pddl.sexp import SExp, section, typed_list, write_sexp

QUANTIFIERS = frozenset({"exists", "forall"})
CONNECTIVES = frozenset({"and", "or", "not", "imply"})
COMPARISONS = frozenset({"<", ">", "<=", ">="})
NUMERIC_EFFECTS = frozenset({"increase", "decrease", "assign", "scale-up", "scale-down"})
COST_FUNCTION = "total-cost"
# What Fast Downward's translator accepts in :requirements (it rejects anything else).
REQUIREMENTS = frozenset(
    {":strips", ":adl", ":typing", ":negation", ":equality", ":negative-preconditions",
     ":disjunctive-preconditions", ":existential-preconditions", ":universal-preconditions",
     ":quantified-preconditions", ":conditional-effects", ":derived-predicates",
     ":action-costs"}
)  # fmt: skip
NOT_CLASSICAL = "Fast Downward plans classical tasks with action costs"
METRIC = "(:metric minimize (total-cost))"
UNSUPPORTED_SECTIONS = {
    ":durative-action": "durative actions (temporal planning)",
    ":process": "processes (PDDL+)",
    ":event": "events (PDDL+)",
}


def type_name(spec: str | tuple[str, ...]) -> str:
    """A declared type as one string: ``t``, or ``(either a b)``."""
    return spec if isinstance(spec, str) else "(either " + " ".join(spec) + ")"


def typed_pairs(items: list[SExp], where: _Source | None = None) -> tuple[tuple[str, str], ...]:
    """A typed list as (name, type) pairs; a name that starts with ``-`` (``?c -compressor``:
    no space after the dash) is an error, as Fast Downward has it, naming file and line."""
    pairs = tuple((name, type_name(spec)) for name, spec in typed_list(items))
    for name, _ in pairs:
        if name.startswith("-") and len(name) > 1:
            message = (
                f"'{name}' in a typed list: a type follows '-' and a space ('- {name[1:]}'); "
                "Fast Downward rejects it"
            )
            if where is None:
                raise PDDLError(message)
            raise where.error(message, rf"(?<![\w?-]){re.escape(name)}(?![\w-])")
    return pairs


def line_of(
    text: str | None, pattern: str, after: str | None = None, occurrence: int = 1
) -> int | None:
    """The line (comments ignored) of the first (``occurrence``-th) match of ``pattern``,
    after the first match of ``after`` when given."""
    if not text:
        return None
    start = 0
    clean = "\n".join(line.split(";", 1)[0] for line in text.splitlines())
    if after is not None:
        found = re.search(after, clean, re.IGNORECASE)
        start = found.start() if found else 0
    matches = re.compile(pattern, re.IGNORECASE).finditer(clean, start)
    match = next(itertools.islice(matches, occurrence - 1, None), None)
    return clean.count("\n", 0, match.start()) + 1 if match else None


def _head_pattern(name: str) -> str:
    return rf"\(\s*{re.escape(name)}[\s)]"


@dataclass
class _Source:
    text: str | None
    name: str | None

    def error(
        self,
        message: str,
        pattern: str | None = None,
        after: str | None = None,
        occurrence: int = 1,
    ) -> PDDLError:
        line = line_of(self.text, pattern, after, occurrence) if pattern else None
        return PDDLError(message, self.name, line)


# ----------------------------------------------------------------- formulas


def condition_atoms(expr: SExp) -> Iterator[tuple[bool, list[SExp]]]:
    """(positive, atom) for every atom of a condition formula (``=`` included, numeric
    comparisons left out); polarity is the atom's, after pushing negations inward."""

    def walk(node: SExp, positive: bool) -> Iterator[tuple[bool, list[SExp]]]:
        if not isinstance(node, list) or not node:
            return
        head = node[0]
        if head in ("and", "or"):
            for part in node[1:]:
                yield from walk(part, positive)
        elif head == "not" and len(node) == 2:
            yield from walk(node[1], not positive)
        elif head == "imply" and len(node) == 3:
            yield from walk(node[1], not positive)
            yield from walk(node[2], positive)
        elif head in QUANTIFIERS and len(node) == 3:
            yield from walk(node[2], positive)
        elif head in COMPARISONS or (head == "=" and any(isinstance(t, list) for t in node[1:])):
            return
        else:
            yield positive, node

    yield from walk(expr, True)


@dataclass(frozen=True)
class EffectAtom:
    """An atom an effect adds (``positive``) or deletes, and whether it is unconditional."""

    positive: bool
    atom: list[SExp]
    conditional: bool


def effect_parts(expr: SExp) -> Iterator[EffectAtom | tuple[str, list[SExp]]]:
    """The atoms of an effect (:class:`EffectAtom`), and its numeric effects as
    ``(operation, expression)``; conditions of ``when`` are not visited."""

    def walk(node: SExp, conditional: bool) -> Iterator[EffectAtom | tuple[str, list[SExp]]]:
        if not isinstance(node, list) or not node:
            return
        head = node[0]
        if head == "and":
            for part in node[1:]:
                yield from walk(part, conditional)
        elif (head == "forall" and len(node) == 3) or (head == "when" and len(node) == 3):
            yield from walk(node[2], True)
        elif head == "not" and len(node) == 2 and isinstance(node[1], list):
            yield EffectAtom(False, node[1], conditional)
        elif head in NUMERIC_EFFECTS:
            yield str(head), node
        else:
            yield EffectAtom(True, node, conditional)

    yield from walk(expr, False)


def conjunction_literals(expr: SExp) -> list[tuple[bool, list[SExp]]] | None:
    """The literals of a conjunction of literals (nested ``and`` flattened); None when the
    formula is more than that."""
    if not isinstance(expr, list):
        return None
    if not expr:
        return []
    if expr[0] == "and":
        found: list[tuple[bool, list[SExp]]] = []
        for part in expr[1:]:
            inner = conjunction_literals(part)
            if inner is None:
                return None
            found += inner
        return found
    if expr[0] == "not" and len(expr) == 2:
        negated = expr[1]
        if isinstance(negated, list) and negated and _is_atom(negated):
            return [(False, negated)]
        return None
    if _is_atom(expr):
        return [(True, expr)]
    return None


def _is_atom(expr: list[SExp]) -> bool:
    head = expr[0]
    return (
        isinstance(head, str)
        and head not in CONNECTIVES | QUANTIFIERS | COMPARISONS | {"when", *NUMERIC_EFFECTS}
        and all(isinstance(t, str) for t in expr[1:])
    )


def _atom(expr: list[SExp]) -> Atom:
    return Atom(str(expr[0]), tuple(str(t) for t in expr[1:]))


# ----------------------------------------------------------------- the domain


def _declarations(items: list[SExp], where: _Source) -> dict[str, tuple[str, ...]]:
    """``(name ?x - t ...)`` entries (predicates, functions); ``- number`` types skipped."""
    found: dict[str, tuple[str, ...]] = {}
    for item in items:
        if isinstance(item, list) and item and isinstance(item[0], str):
            found[item[0]] = tuple(t for _, t in typed_pairs(item[1:], where))
    return found


def read_domain(body: list[SExp], text: str | None, source: str | None) -> Domain:
    """The domain of a ``(define (domain ...) ...)`` body (see the module docstring)."""
    where = _Source(text, source)
    header = body[1] if len(body) > 1 else None
    name = str(header[1]) if isinstance(header, list) and len(header) > 1 else "domain"
    for item in body[2:]:
        if isinstance(item, list) and item and item[0] in UNSUPPORTED_SECTIONS:
            key = str(item[0])
            raise where.error(
                f"{UNSUPPORTED_SECTIONS[key]} are not supported (Fast Downward plans classical "
                "tasks only)",
                _head_pattern(key),
            )
    requirements = tuple(
        str(r) for r in (section(body, ":requirements") or [":r"])[1:] if isinstance(r, str)
    )
    for requirement in requirements:
        if requirement not in REQUIREMENTS:
            raise where.error(
                f"requirement {requirement} is not supported ({NOT_CLASSICAL}; it accepts "
                f"{', '.join(sorted(REQUIREMENTS))})",
                rf"{re.escape(requirement)}(?![\w-])",
            )
    types: dict[str, str | None] = {}
    for type_, parent in typed_list((section(body, ":types") or [":t"])[1:]):
        if type_ == "object":
            continue  # the root; AlfWorld lists it among its types
        if type_ == "number":
            raise where.error(
                'the type "number" is reserved for numeric values and cannot be declared '
                "(Fast Downward rejects it)",
                r"(?<![\w?-])number(?![\w-])",
                r"\(:types",
            )
        types[type_] = parent if isinstance(parent, str) and parent != "object" else None
    if not types:
        types["object"] = None
    constants = dict(typed_pairs((section(body, ":constants") or [":c"])[1:], where))
    predicates = _declarations((section(body, ":predicates") or [":p"])[1:], where)
    functions = _declarations((section(body, ":functions") or [":f"])[1:], where)
    derived: list[DerivedPredicate] = []
    for item in body[2:]:
        if isinstance(item, list) and item[:1] == [":derived"]:
            if len(item) != 3 or not isinstance(item[1], list) or not item[1]:
                raise where.error("a :derived rule needs a head and a formula", r"\(:derived")
            head = item[1]
            derived_name = str(head[0])
            parameters = typed_pairs(head[1:], where)
            if derived_name not in predicates:
                predicates[derived_name] = tuple(t for _, t in parameters)
            derived.append(DerivedPredicate(derived_name, parameters, item[2]))
    known = set(predicates)
    for rule in derived:
        _check_formula(rule.formula, known, where, f"derived predicate {rule.name}")
    derived_names = {rule.name for rule in derived}
    actions: dict[str, ActionSchema] = {}
    for item in body[2:]:
        if isinstance(item, list) and item[:1] == [":action"]:
            action = _read_action(item, known, set(functions), where)
            if action.name in actions:
                raise where.error(
                    f"action '{action.name}' is defined twice",
                    rf"\(:action\s+{re.escape(action.name)}(?![\w-])",
                    occurrence=2,
                )
            for atom in (*action.add, *action.delete):
                if atom.predicate in derived_names:
                    raise where.error(
                        f"action {action.name}: its effect changes the derived predicate "
                        f"'{atom.predicate}' (derived facts follow from the rules alone)",
                        rf"\(:action\s+{re.escape(action.name)}\b",
                    )
            actions[action.name] = action
    return Domain(
        name,
        requirements,
        types,
        constants,
        predicates,
        actions,
        source,
        functions,
        tuple(derived),
        body,
        text,
    )


def _check_formula(expr: SExp, predicates: set[str], where: _Source, context: str) -> None:
    comparison = _numeric_comparison(expr)
    if comparison is not None:
        raise where.error(
            f"{context}: numeric conditions ({comparison} ...) are not supported ({NOT_CLASSICAL})",
            rf"\(\s*{re.escape(comparison)}\s",
        )
    for _, atom in condition_atoms(expr):
        head = atom[0]
        if not isinstance(head, str) or (head != "=" and head not in predicates):
            shown = head if isinstance(head, str) else write_sexp(head)
            raise where.error(
                f"{context}: unknown predicate '{shown}'",
                _head_pattern(shown) if isinstance(head, str) else None,
            )


def _numeric_comparison(expr: SExp) -> str | None:
    """The first numeric comparison of a condition (``<``, ``=`` between numbers, ...)."""
    if not isinstance(expr, list) or not expr:
        return None
    head = expr[0]
    if head in COMPARISONS or (head == "=" and any(isinstance(t, list) for t in expr[1:])):
        return str(head)
    parts = [expr[2]] if head in QUANTIFIERS and len(expr) == 3 else expr[1:]
    for part in parts:
        found = _numeric_comparison(part)
        if found is not None:
            return found
    return None


def _read_action(
    item: list[SExp], predicates: set[str], functions: set[str], where: _Source
) -> ActionSchema:
    if len(item) < 2 or not isinstance(item[1], str):
        raise where.error("an action without a name", r"\(:action")
    name = item[1]
    context = f"action {name}"
    keys: dict[str, SExp] = {}
    rest = item[2:]
    for key, value in zip(rest[::2], rest[1::2], strict=False):
        keys[str(key)] = value
    raw_parameters = keys.get(":parameters", [])
    parameters = typed_pairs(raw_parameters if isinstance(raw_parameters, list) else [], where)
    for variable, type_ in parameters:
        if type_.startswith("(either"):
            raise where.error(
                f"{context}: parameter {variable} has an (either ...) type, which Fast Downward "
                "accepts in predicate declarations but not in action parameters; declare a "
                "common supertype",
                rf"{re.escape(variable)}\s*-\s*\(\s*either",
            )
    precondition = keys.get(":precondition", [])
    effect = keys.get(":effect", [])
    _check_formula(precondition, predicates, where, context)
    for condition in _when_conditions(effect):
        _check_formula(condition, predicates, where, context)
    literals = conjunction_literals(precondition)
    is_strips = literals is not None
    pre_positive: list[Atom] = []
    pre_negative: list[Atom] = []
    equal: list[tuple[str, str]] = []
    not_equal: list[tuple[str, str]] = []
    if literals is None:  # the summary: the top-level conjunction's literals only
        top = (
            precondition[1:]
            if isinstance(precondition, list) and precondition[:1] == ["and"]
            else [precondition]
        )
        literals = [lit for part in top for lit in (conjunction_literals(part) or [])]
    for positive, atom in literals:
        if atom[0] == "=" and len(atom) == 3:
            (equal if positive else not_equal).append((str(atom[1]), str(atom[2])))
        elif atom[0] != "=":
            (pre_positive if positive else pre_negative).append(_atom(atom))
    add: list[Atom] = []
    delete: list[Atom] = []
    cost: int | None = None
    for part in effect_parts(effect):
        if isinstance(part, EffectAtom):
            atom = part.atom
            if not atom or not isinstance(atom[0], str) or atom[0] not in predicates:
                shown = str(atom[0]) if atom and isinstance(atom[0], str) else write_sexp(atom)
                raise where.error(f"{context}: unknown predicate '{shown}'", _head_pattern(shown))
            if part.conditional:
                is_strips = False
            (add if part.positive else delete).append(_atom(atom))
            continue
        operation, expression = part
        target = expression[1] if len(expression) > 1 else None
        target_name = target[0] if isinstance(target, list) and target else target
        if operation == "increase" and target_name == COST_FUNCTION and len(expression) == 3:
            amount = expression[2]
            if isinstance(amount, str) and re.fullmatch(r"\d+(\.0+)?", amount):
                cost = (cost or 0) + int(float(amount))
            continue
        if target_name not in functions:
            raise where.error(
                f"{context}: numeric effect on unknown function '{write_sexp(target or [])}'",
                rf"\({operation}\s",
            )
        raise where.error(
            f"{context}: numeric effects other than (increase (total-cost) ...) are not "
            f"supported ({NOT_CLASSICAL})",
            rf"\({operation}\s",
        )
    return ActionSchema(
        name,
        parameters,
        tuple(pre_positive),
        tuple(pre_negative),
        tuple(add),
        tuple(delete),
        tuple(equal),
        tuple(not_equal),
        cost,
        precondition,
        effect,
        is_strips,
    )


def _when_conditions(expr: SExp) -> Iterator[SExp]:
    """The conditions of an effect's ``when`` parts."""
    if not isinstance(expr, list) or not expr:
        return
    head = expr[0]
    if head == "and":
        for part in expr[1:]:
            yield from _when_conditions(part)
    elif head == "forall" and len(expr) == 3:
        yield from _when_conditions(expr[2])
    elif head == "when" and len(expr) == 3:
        yield expr[1]
        yield from _when_conditions(expr[2])


# ----------------------------------------------------------------- the problem


@dataclass(frozen=True)
class ProblemParts:
    """What a problem file says, read against its domain."""

    name: str
    objects: dict[str, str]
    init: frozenset[Fact]
    numeric_init: tuple[SExp, ...]
    goal: Goal


def read_problem(
    body: list[SExp], domain: Domain, text: str | None, source: str | None
) -> ProblemParts:
    """The parts of a ``(define (problem ...) ...)`` body, checked against ``domain``."""
    where = _Source(text, source)
    header = body[1] if len(body) > 1 else None
    name = str(header[1]) if isinstance(header, list) and len(header) > 1 else "problem"
    objects = dict(typed_pairs((section(body, ":objects") or [":o"])[1:], where))
    for obj, obj_type in objects.items():
        known_type = obj_type in domain.types or obj_type in domain.types.values()
        if obj_type != "object" and not known_type and "(" not in obj_type:
            declared = ", ".join(sorted(domain.types)) or "none"
            raise where.error(
                f"object '{obj}' has type '{obj_type}', which the domain does not declare "
                f"(types: {declared})",
                rf"-\s*{re.escape(obj_type)}(?![\w-])",
                r"\(:objects",
            )
    known_objects = {**domain.constants, **objects}
    init: set[Fact] = set()
    numeric: list[SExp] = []
    for entry in (section(body, ":init") or [":init"])[1:]:
        if not isinstance(entry, list) or not entry:
            raise where.error(f"not an initial fact: {write_sexp(entry)}", r"\(:init")
        if entry[0] == "=":
            numeric.append(entry)
            continue
        if entry[0] == "not":
            continue  # closed world: a negative initial fact says nothing new
        _check_ground_atom(entry, domain, known_objects, where, ":init")
        init.add(tuple(str(t) for t in entry))
    metric = section(body, ":metric")
    if metric is not None and write_sexp(metric).lower() != METRIC:
        raise where.error(
            f"{write_sexp(metric)} is not supported ({NOT_CLASSICAL}: it accepts only "
            f"{METRIC}, or no metric)",
            r"\(:metric",
        )
    goal_entry = section(body, ":goal")
    formula: SExp = goal_entry[1] if goal_entry is not None and len(goal_entry) > 1 else []
    for _, atom in condition_atoms(formula):
        _check_ground_atom(atom, domain, known_objects, where, ":goal", variables_allowed=True)
    return ProblemParts(name, objects, frozenset(init), tuple(numeric), goal_from_formula(formula))


def goal_from_formula(formula: SExp) -> Goal:
    """A goal: its literals when it is a conjunction of ground literals, else its formula
    (with the literals of its top-level conjunction)."""
    literals = conjunction_literals(formula)
    whole = literals is not None and all(
        atom[0] != "=" and not any(str(t).startswith("?") for t in atom[1:]) for _, atom in literals
    )
    if literals is None:
        top = formula[1:] if isinstance(formula, list) and formula[:1] == ["and"] else [formula]
        literals = [lit for part in top for lit in (conjunction_literals(part) or [])]
    positive = frozenset(
        tuple(str(t) for t in atom) for p, atom in literals if p and atom[0] != "="
    )
    negative = frozenset(
        tuple(str(t) for t in atom) for p, atom in literals if not p and atom[0] != "="
    )
    return Goal(positive, negative, None if whole else formula)


def _check_ground_atom(
    atom: list[SExp],
    domain: Domain,
    objects: dict[str, str],
    where: _Source,
    part: str,
    variables_allowed: bool = False,
) -> None:
    head = atom[0]
    if not isinstance(head, str) or not all(isinstance(t, str) for t in atom[1:]):
        raise where.error(f"{part}: not an atom: {write_sexp(atom)}", rf"\({re.escape(part)}\b")
    if head != "=" and head not in domain.predicates:
        listing = ", ".join(sorted(domain.predicates)[:12])
        more = ", ..." if len(domain.predicates) > 12 else ""
        raise where.error(
            f"unknown predicate '{head}' in {part} (declared: {listing or 'none'}{more})",
            _head_pattern(head),
            rf"\(\s*{re.escape(part)}\b",
        )
    if head != "=" and len(atom) - 1 != len(domain.predicates[head]):
        raise where.error(
            f"predicate '{head}' takes {len(domain.predicates[head])} arguments, "
            f"{len(atom) - 1} given in {part}: {write_sexp(atom)}",
            r"\(\s*" + r"\s+".join(re.escape(str(t)) for t in atom) + r"\s*\)",
            rf"\(\s*{re.escape(part)}\b",
        )
    for term in atom[1:]:
        name = str(term)
        if name.startswith("?") and variables_allowed:
            continue
        if name not in objects:
            listing = ", ".join(sorted(objects)[:12])
            more = ", ..." if len(objects) > 12 else ""
            raise where.error(
                f"unknown object '{name}' in {part} (declared: {listing or 'none'}{more})",
                rf"(?<![\w?-]){re.escape(name)}(?![\w-])",
                rf"\(\s*{re.escape(part)}\b",
            )
