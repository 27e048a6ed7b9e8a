"""A lint pass over a task's types, predicates and variables, before Fast Downward sees it.

Fast Downward's translator accepts some files that cannot mean what they say and then
grounds them into something else: an action parameter of a type no one declared has no
objects, so the action never applies and the search "proves" the task unsolvable; a goal
atom with an object of the wrong type can never be made true. This pass names such
mistakes with file and line (a :class:`~twostep.pddl.PDDLError`, an input error) instead:

- a type used but never declared (in ``:constants``, predicate, function and action
  parameters, ``:derived`` heads, ``forall``/``exists`` variables, ``either`` members);
  a type is declared by ``:types``, as a name or as a parent (``a b - c`` declares ``c``);
- types whose parents form a cycle (``truck - pkg``, ``pkg - truck``);
- an atom with the wrong number of arguments in an action or a derived rule;
- a variable an action or rule uses but does not declare, and an action parameter
  declared twice (Fast Downward rejects both, in words that name no line);
- an object or constant of a type the predicate's parameter does not take, in the
  problem's ``:init`` or ``:goal``.

It rejects nothing Fast Downward's translator reads as the file means: the tests run it
over every domain and problem of the IPC sample, the benchmark data and AlfWorld's
``alfred.pddl`` with no finding.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping

from twostep.pddl.errors import PDDLError
from twostep.pddl.lifted import (
    COMPARISONS,
    NUMERIC_EFFECTS,
    QUANTIFIERS,
    ProblemParts,
    line_of,
    typed_pairs,
)
from twostep.pddl.model import Domain
from twostep.pddl.sexp import SExp, section, typed_list, write_sexp

_NUMBER = "number"


def _error(
    message: str, text: str | None, source: str | None, pattern: str, after: str | None = None
) -> PDDLError:
    return PDDLError(message, source, line_of(text, pattern, after))


def _word(name: str) -> str:
    return rf"(?<![\w?-]){re.escape(name)}(?![\w-])"


def _type_names(spec: str) -> list[str]:
    """The names in a declared type: ``t``, or the members of ``(either a b)``."""
    return spec.strip("()").split()[1:] if spec.startswith("(either") else [spec]


def check_kinds(
    domain_body: list[SExp],
    problem_body: list[SExp],
    sources: tuple[str | None, str | None],
    texts: tuple[str | None, str | None],
) -> None:
    """A domain file that defines a problem, or a problem file that defines a domain (the
    two files swapped, or one given twice), named before anything is read from them."""
    for body, kind, text, source in zip(
        (domain_body, problem_body), ("domain", "problem"), texts, sources, strict=True
    ):
        header = body[1] if len(body) > 1 else None
        found = header[0] if isinstance(header, list) and header else None
        if found in ("domain", "problem") and found != kind:
            raise _error(
                f"this file defines a {found}, not a {kind} (are the domain and problem files "
                "swapped?)",
                text,
                source,
                rf"\(\s*{found}\b",
            )


def lint_domain(domain: Domain, text: str | None, source: str | None) -> None:
    """Raise :class:`PDDLError` for the first finding of the module docstring in ``domain``."""
    declared = {"object", *domain.types, *(p for p in domain.types.values() if p)}
    _check_cycles(domain, text, source)

    def check(spec: str, context: str, after: str | None) -> None:
        for name in _type_names(spec):
            if name not in declared and name != _NUMBER:
                known = ", ".join(sorted(declared - {"object"})) or "none"
                raise _error(
                    f"{context}: type '{name}' is not declared (types: {known})",
                    text,
                    source,
                    rf"-\s*(\(\s*either[^)]*)?{_word(name)}",
                    after,
                )

    for constant, spec in domain.constants.items():
        check(spec, f"constant {constant}", r"\(:constants")
    for name, types in domain.predicates.items():
        for spec in types:
            check(spec, f"predicate {name}", rf"\(\s*{re.escape(name)}[\s)]")
    for name, types in domain.functions.items():
        for spec in types:
            check(spec, f"function {name}", r"\(:functions")
    for rule in domain.derived:
        context = f"derived predicate {rule.name}"
        after = rf"\(:derived\s*\(\s*{re.escape(rule.name)}[\s)]"
        for _, spec in rule.parameters:
            check(spec, context, after)
        variables = {v for v, _ in rule.parameters}
        for spec, where in _quantified_types(rule.formula):
            check(spec, f"{context} ({where})", after)
        _check_formula(domain, rule.formula, variables, context, text, source, after, False)
    for action in domain.actions.values():
        context = f"action {action.name}"
        after = rf"\(:action\s+{re.escape(action.name)}(?![\w-])"
        seen: set[str] = set()
        for variable, spec in action.parameters:
            if variable in seen:
                raise _error(
                    f"{context}: parameter {variable} is declared twice",
                    text,
                    source,
                    re.escape(variable),
                    after,
                )
            seen.add(variable)
            check(spec, context, after)
        for formula in (action.precondition, action.effect):
            for spec, where in _quantified_types(formula):
                check(spec, f"{context} ({where})", after)
        _check_formula(domain, action.precondition, seen, context, text, source, after, False)
        _check_formula(domain, action.effect, seen, context, text, source, after, True)


def _check_cycles(domain: Domain, text: str | None, source: str | None) -> None:
    for start in domain.types:
        path = [start]
        parent = domain.types.get(start)
        while parent is not None:
            if parent in path:
                cycle = " - ".join([*path[path.index(parent) :], parent])
                raise _error(
                    f"the types' parents form a cycle ({cycle}): a type cannot descend from itself",
                    text,
                    source,
                    _word(parent),
                    r"\(:types",
                )
            path.append(parent)
            parent = domain.types.get(parent)


def _quantified_types(formula: SExp) -> Iterator[tuple[str, str]]:
    """(type, ``forall``/``exists``) of every variable a quantifier in ``formula`` declares."""
    if not isinstance(formula, list) or not formula:
        return
    if formula[0] in QUANTIFIERS and len(formula) == 3 and isinstance(formula[1], list):
        for _, spec in typed_pairs(formula[1]):
            yield spec, str(formula[0])
    for part in formula:
        yield from _quantified_types(part)


def _check_formula(
    domain: Domain,
    formula: SExp,
    variables: set[str],
    context: str,
    text: str | None,
    source: str | None,
    after: str,
    effect: bool,
) -> None:
    """Every atom of ``formula`` (a condition, or an effect) has its predicate's arity and
    uses only variables bound by the action or rule, or by a quantifier around it."""
    for atom, bound in _atoms(formula, frozenset(variables), effect):
        head = atom[0]
        if not isinstance(head, str) or head == "=" or head not in domain.predicates:
            arity = None  # unknown predicates are the reader's (named already)
        else:
            arity = len(domain.predicates[head])
        terms = [t for t in atom[1:] if isinstance(t, str)]
        if arity is not None and len(atom) - 1 != arity:
            raise _error(
                f"{context}: predicate '{head}' takes {arity} argument(s), "
                f"{len(atom) - 1} given: {write_sexp(atom)}",
                text,
                source,
                r"\(\s*" + r"\s*".join(re.escape(str(t)) for t in atom) + r"\s*\)",
                after,
            )
        for term in terms:
            if term.startswith("?") and term not in bound:
                raise _error(
                    f"{context}: variable {term} is not declared (not a parameter, nor "
                    f"bound by forall or exists around it): {write_sexp(atom)}",
                    text,
                    source,
                    rf"{re.escape(term)}(?![\w-])",
                    after,
                )


def _atoms(
    node: SExp, bound: frozenset[str], effect: bool
) -> Iterator[tuple[list[SExp], frozenset[str]]]:
    """Every atom of a condition (``effect`` False) or an effect, with the variables bound
    where it stands; numeric comparisons and numeric effects are not atoms."""
    if not isinstance(node, list) or not node:
        return
    head = node[0]
    if head == "and" or (not effect and head == "or"):
        for part in node[1:]:
            yield from _atoms(part, bound, effect)
    elif head == "not" and len(node) == 2:
        yield from _atoms(node[1], bound, effect)
    elif not effect and head == "imply" and len(node) == 3:
        yield from _atoms(node[1], bound, False)
        yield from _atoms(node[2], bound, False)
    elif head in QUANTIFIERS and len(node) == 3 and isinstance(node[1], list):
        inner = bound | {name for name, _ in typed_list(node[1])}
        yield from _atoms(node[2], inner, effect)
    elif effect and head == "when" and len(node) == 3:
        yield from _atoms(node[1], bound, False)
        yield from _atoms(node[2], bound, True)
    elif (
        head in COMPARISONS
        or head in NUMERIC_EFFECTS
        or (head == "=" and any(isinstance(t, list) for t in node[1:]))
    ):
        return
    elif isinstance(head, str):
        yield node, bound


def lint_problem(
    domain: Domain,
    parts: ProblemParts,
    body: list[SExp],
    text: str | None,
    source: str | None,
) -> None:
    """Raise :class:`PDDLError` for an object of the wrong type in ``:init`` or ``:goal``
    (typed domains only)."""
    if not domain.typed:
        return
    types: Mapping[str, str] = {**domain.constants, **parts.objects}
    for fact in sorted(parts.init):
        _check_types(domain, types, fact, ":init", text, source)
    goal = section(body, ":goal")
    for atom, _ in _atoms(
        goal[1] if goal is not None and len(goal) > 1 else [], frozenset(), False
    ):
        if all(isinstance(t, str) for t in atom):
            _check_types(domain, types, tuple(str(t) for t in atom), ":goal", text, source)


def _check_types(
    domain: Domain,
    types: Mapping[str, str],
    atom: tuple[str, ...],
    part: str,
    text: str | None,
    source: str | None,
) -> None:
    head, *args = atom
    parameters = domain.predicates.get(head)
    if parameters is None or len(parameters) != len(args):
        return  # "=", or what the reader names already
    for position, (arg, wanted) in enumerate(zip(args, parameters, strict=True), 1):
        have = types.get(arg)
        if have is None or have.startswith("(") or domain.is_subtype(have, wanted):
            continue  # a variable of a quantified goal, or an (either ...) object
        raise _error(
            f"{part}: ({' '.join(atom)}): '{arg}' is of type '{have}', but argument {position} "
            f"of '{head}' is of type '{wanted}'",
            text,
            source,
            r"\(\s*" + r"\s+".join(re.escape(t) for t in atom) + r"\s*\)",
            rf"\(\s*{re.escape(part)}\b",
        )
