"""Subgoals written with quantifiers or disjunctions, grounded by the task's static facts.

A helper's subgoal must be a conjunction of ground literals (a helper plans for it, and
its truth is a set test). A proposal such as ``(exists (?o - object) (and (objecttype ?o
eggtype) (ishot ?o)))`` is still usable when the task's static facts (those of predicates
no action changes) leave exactly one way to meet it: with one egg, ``(ishot egg1)``.
The formula is expanded over the task's objects (``forall`` as a conjunction, ``exists``
as a disjunction), static literals are decided by the initial state, and the remaining
disjunctive normal form must have exactly one disjunct.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

from twostep.pddl.errors import PDDLError
from twostep.pddl.grounded import Fact
from twostep.pddl.lifted import typed_pairs
from twostep.pddl.model import Goal, Problem
from twostep.pddl.sexp import SExp, write_sexp

MAX_DISJUNCTS = 20_000

_Conjunction = tuple[frozenset[Fact], frozenset[Fact]]


class _TooMany(Exception):
    pass


def ground_goal(exprs: Sequence[SExp], problem: Problem, source: str) -> Goal:
    """The one conjunction of ground literals a quantified goal amounts to (see above)."""
    _check_atoms(exprs, problem, source)
    domain = problem.domain
    changing = {a.predicate for s in domain.actions.values() for a in (*s.add, *s.delete)}
    changing |= domain.derived_predicates
    objects = problem.all_objects

    def objects_of(type_name: str) -> list[str]:
        return sorted(o for o, t in objects.items() if domain.is_subtype(t, type_name))

    def dnf(node: SExp, positive: bool, binding: dict[str, str]) -> list[_Conjunction]:
        if not isinstance(node, list) or not node:
            return [(frozenset(), frozenset())] if positive else []
        head = node[0]
        if head == "not" and len(node) == 2:
            return dnf(node[1], not positive, binding)
        if head == "imply" and len(node) == 3:
            return dnf(["or", ["not", node[1]], node[2]], positive, binding)
        if head in ("and", "or"):
            conjunctive = (head == "and") == positive
            parts = [dnf(part, positive, binding) for part in node[1:]]
            return _conjoin(parts) if conjunctive else _union(parts)
        if head in ("exists", "forall") and len(node) == 3 and isinstance(node[1], list):
            variables = typed_pairs(node[1])
            parts = []
            for values in itertools.product(*(objects_of(t) for _, t in variables)):
                inner = dict(binding)
                inner.update(zip((v for v, _ in variables), values, strict=True))
                parts.append(dnf(node[2], positive, inner))
            conjunctive = (head == "forall") == positive
            return _conjoin(parts) if conjunctive else _union(parts)
        atom: Fact = tuple(binding.get(str(t), str(t)) for t in node)
        if atom[0] == "=":
            holds = len(atom) == 3 and atom[1] == atom[2]
            return [(frozenset(), frozenset())] if holds == positive else []
        if atom[0] not in changing:
            holds = atom in problem.init
            return [(frozenset(), frozenset())] if holds == positive else []
        single = frozenset((atom,))
        return [(single, frozenset())] if positive else [(frozenset(), single)]

    try:
        options = dnf(["and", *exprs], True, {})
    except _TooMany:
        options = None
    if options is None or len(options) != 1:
        count = "too many" if options is None else str(len(options))
        text = " ".join(write_sexp(e) for e in exprs)
        raise PDDLError(
            f"not a ground literal conjunction: {text} can be met in {count} different ways "
            "(0: never); name the objects instead of quantifying or choosing",
            source,
        )
    positive, negative = options[0]
    return Goal(positive, negative)


def _union(parts: list[list[_Conjunction]]) -> list[_Conjunction]:
    found = list(dict.fromkeys(c for part in parts for c in part))
    if len(found) > MAX_DISJUNCTS:
        raise _TooMany
    if (frozenset(), frozenset()) in found:
        return [(frozenset(), frozenset())]  # one option always holds: so does the whole
    return found


def _conjoin(parts: list[list[_Conjunction]]) -> list[_Conjunction]:
    result: list[_Conjunction] = [(frozenset(), frozenset())]
    for part in parts:
        combined = []
        for (p1, n1), (p2, n2) in itertools.product(result, part):
            positive, negative = p1 | p2, n1 | n2
            if not positive & negative:
                combined.append((positive, negative))
        result = list(dict.fromkeys(combined))
        if len(result) > MAX_DISJUNCTS:
            raise _TooMany
        if not result:
            return []
    return result


def _check_atoms(exprs: Sequence[SExp], problem: Problem, source: str) -> None:
    """Unknown predicates, wrong arities and unknown objects, before anything is decided."""
    predicates = problem.domain.predicates
    objects = problem.all_objects
    for expr in exprs:
        if not isinstance(expr, list) or not expr:
            continue
        head = expr[0]
        if head in ("exists", "forall") and len(expr) == 3:
            _check_atoms([expr[2]], problem, source)
            continue
        if head in ("and", "or", "not", "imply"):
            _check_atoms(expr[1:], problem, source)
            continue
        if isinstance(head, str) and head != "=":
            if head not in predicates:
                raise PDDLError(f"unknown predicate '{head}'", source)
            if len(expr) - 1 != len(predicates[head]):
                arity = len(predicates[head])
                raise PDDLError(f"'{head}' takes {arity} argument(s), got {len(expr) - 1}", source)
        for term in expr[1:]:
            if isinstance(term, str) and not term.startswith("?") and term not in objects:
                raise PDDLError(f"unknown object '{term}' in {write_sexp(expr)}", source)
