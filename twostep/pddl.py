"""PDDL domains and problems: reading, the in-memory model, and writing.

Files are parsed by unified-planning's ``PDDLReader``; the result is turned into the small,
immutable model below (ground facts are tuples of lowercase names), which every other
module uses. Real-world files are read as they are: before unified-planning sees them, a
light s-expression pass reports unbalanced parentheses with file and line, and repairs the
two quirks of the LLM+P benchmark files (action names reused as predicate names, and
domain actions that mention objects only the problem declares).

Supported fragment: STRIPS with typing, constants, negative preconditions and equality.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

Fact = tuple[str, ...]
"""A ground atom: predicate name followed by object names, all lowercase."""

SExp = str | list["SExp"]


class PDDLError(Exception):
    """A PDDL file or string that cannot be used, with where and what."""

    def __init__(self, message: str, source: str | None = None, line: int | None = None):
        self.message = message
        self.source = source
        self.line = line
        where = source or "<pddl>"
        if line is not None:
            where = f"{where}:{line}"
        super().__init__(f"{where}: {message}")


# --------------------------------------------------------------------------- model


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
    """A STRIPS action schema with negative preconditions and (in)equality constraints."""

    name: str
    parameters: tuple[tuple[str, str], ...]  # (?variable, type)
    pre_positive: tuple[Atom, ...] = ()
    pre_negative: tuple[Atom, ...] = ()
    add: tuple[Atom, ...] = ()
    delete: tuple[Atom, ...] = ()
    equal: tuple[tuple[str, str], ...] = ()
    not_equal: tuple[tuple[str, str], ...] = ()


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

    @property
    def typed(self) -> bool:
        return any(t != "object" for t in self.types)


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


# ------------------------------------------------------------- s-expression layer

_TOKEN = re.compile(r"\(|\)|[^\s()]+")
# Sections that open directly inside (define ...): seeing one deeper means a ')' is missing.
_SECTIONS = frozenset(
    {":domain", ":requirements", ":types", ":constants", ":predicates", ":functions",
     ":action", ":durative-action", ":derived", ":objects", ":init", ":goal", ":metric"}
)  # fmt: skip


def read_sexp(text: str, source: str | None = None, single: bool = False) -> list[SExp]:
    """Read all top-level s-expressions of ``text``; PDDL comments (``;``) are skipped.

    With ``single``, anything after the first complete expression is an error (a ``)``
    too many closes a PDDL file's ``define`` early).
    """
    stack: list[list[SExp]] = [[]]
    opened: list[int] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        line = line.split(";", 1)[0]
        for token in _TOKEN.findall(line):
            if single and len(stack) == 1 and stack[0]:
                raise PDDLError(
                    f"unexpected '{token}' after the end of the define: a ')' too many before it?",
                    source,
                    lineno,
                )
            if token == "(":
                stack.append([])
                opened.append(lineno)
            elif token.lower() in _SECTIONS and len(stack) > 3 and not stack[-1]:
                raise PDDLError(
                    f"'({token.lower()}' on line {lineno} opens inside an expression that is "
                    "never closed: a ')' is missing",
                    source,
                    opened[-2],
                )
            elif token == ")":
                if len(stack) == 1:
                    raise PDDLError("unexpected ')' with no matching '('", source, lineno)
                done = stack.pop()
                opened.pop()
                stack[-1].append(done)
            else:
                stack[-1].append(token.lower())
    if len(stack) > 1:
        raise PDDLError("'(' is never closed", source, opened[-1])
    return stack[0]


def write_sexp(expr: SExp) -> str:
    if isinstance(expr, str):
        return expr
    return "(" + " ".join(write_sexp(e) for e in expr) + ")"


def _define_body(text: str, kind: str, source: str | None) -> list[SExp]:
    exprs = read_sexp(text, source)
    if not exprs or not isinstance(exprs[0], list) or not exprs[0] or exprs[0][0] != "define":
        raise PDDLError(f"expected '(define ({kind} ...) ...)'", source, 1)
    return exprs[0]


def _section(body: list[SExp], key: str) -> list[SExp] | None:
    for item in body:
        if isinstance(item, list) and item and item[0] == key:
            return item
    return None


def _typed_names(items: list[SExp]) -> list[tuple[str, str]]:
    """Parse a PDDL typed list ``a b - t c`` into ``[(a, t), (b, t), (c, object)]``."""
    names: list[tuple[str, str]] = []
    pending: list[str] = []
    i = 0
    while i < len(items):
        item = items[i]
        if item == "-" and i + 1 < len(items):
            parent = items[i + 1]
            type_name = parent if isinstance(parent, str) else "object"  # (either ...) unsupported
            names += [(n, type_name) for n in pending]
            pending = []
            i += 2
            continue
        if isinstance(item, str):
            pending.append(item)
        i += 1
    names += [(n, "object") for n in pending]
    return names


def _undeclared_constants(domain_body: list[SExp]) -> set[str]:
    """Names that domain actions use as objects without declaring them as constants."""
    predicates = {
        p[0] for p in (_section(domain_body, ":predicates") or [])[1:] if isinstance(p, list) and p
    }
    constants = {n for n, _ in _typed_names((_section(domain_body, ":constants") or [":c"])[1:])}
    found: set[str] = set()

    def visit(expr: SExp) -> None:
        if not isinstance(expr, list) or not expr:
            return
        head = expr[0]
        if isinstance(head, str) and (head in predicates or head == "="):
            for term in expr[1:]:
                if isinstance(term, str) and not term.startswith("?") and term not in constants:
                    found.add(term)
        for sub in expr[1:]:
            visit(sub)

    for item in domain_body:
        if isinstance(item, list) and item and item[0] == ":action":
            for key, value in zip(item[2::2], item[3::2], strict=False):
                if key in (":precondition", ":effect"):
                    visit(value)
    return found


def _repair_undeclared_constants(
    domain_text: str, problem_text: str, domain_source: str | None, problem_source: str | None
) -> tuple[str, str]:
    """Move objects that the domain uses but only the problem declares into domain constants.

    The LLM+P tyreworld domain mentions ``wrench``, ``jack`` and ``pump`` in its actions
    while only its problems declare them; both unified-planning and Fast Downward reject
    that. Declaring them as typed constants of the domain keeps the meaning.
    """
    domain_body = _define_body(domain_text, "domain", domain_source)
    missing = _undeclared_constants(domain_body)
    if not missing:
        return domain_text, problem_text
    problem_body = _define_body(problem_text, "problem", problem_source)
    objects_section = _section(problem_body, ":objects") or [":objects"]
    declared = dict(_typed_names(objects_section[1:]))
    unknown = sorted(missing - declared.keys())
    if unknown:
        raise PDDLError(
            f"the domain's actions use undeclared object(s) {', '.join(unknown)} "
            "that neither its constants nor the problem's objects declare",
            domain_source,
        )
    constants_section = _section(domain_body, ":constants")
    new_constants: list[SExp] = [":constants"]
    if constants_section is not None:
        new_constants += constants_section[1:]
    for name in sorted(missing):
        new_constants += [name, "-", declared[name]] if _domain_body_typed(domain_body) else [name]
    rebuilt: list[SExp] = []
    inserted = False
    for item in domain_body:
        if item is constants_section:
            continue
        if not inserted and isinstance(item, list) and item and item[0] == ":predicates":
            rebuilt.append(new_constants)
            inserted = True
        rebuilt.append(item)
    if not inserted:
        rebuilt.insert(2, new_constants)
    kept: list[SExp] = [":objects"]
    for name, type_name in _typed_names(objects_section[1:]):
        if name not in missing:
            kept += [name, "-", type_name]
    problem_rebuilt = [kept if item is objects_section else item for item in problem_body]
    return _pretty(rebuilt), _pretty(problem_rebuilt)


def _domain_body_typed(domain_body: list[SExp]) -> bool:
    return _section(domain_body, ":types") is not None


def _pretty(body: list[SExp]) -> str:
    return "(" + "\n ".join(write_sexp(item) for item in body) + ")\n"


# ------------------------------------------------------ unified-planning layer


def _up_environment() -> Any:
    from unified_planning.shortcuts import get_environment

    env = get_environment()
    # LLM+P tyreworld names actions like predicates (open, close): allow it.
    env.error_used_name = False
    env.credits_stream = None
    return env


_LINE_IN_MESSAGE = re.compile(r"line:? (\d+)", re.IGNORECASE)


def _parse_with_up(
    domain_text: str, problem_text: str, domain_source: str | None, problem_source: str | None
) -> Any:
    from unified_planning.io import PDDLReader

    _up_environment()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        try:
            return PDDLReader().parse_problem_string(domain_text, problem_text)
        except Exception as exc:
            problem_error = exc
        try:  # which file is wrong? the domain alone tells (only on failure: parsing is slow)
            PDDLReader().parse_problem_string(domain_text)
        except Exception as exc:
            raise _as_pddl_error(exc, domain_source) from None
        raise _as_pddl_error(problem_error, problem_source) from None


def _as_pddl_error(exc: Exception, source: str | None) -> PDDLError:
    line = getattr(exc, "lineno", None)
    message = str(getattr(exc, "msg", None) or exc)
    if line is None:
        match = _LINE_IN_MESSAGE.search(str(exc))
        line = int(match.group(1)) if match else None
    return PDDLError(message.split(". From line")[0].strip(), source, line)


def _terms(node: Any) -> tuple[str, ...]:
    terms: list[str] = []
    for arg in node.args:
        if arg.is_parameter_exp():
            terms.append("?" + arg.parameter().name)
        elif arg.is_object_exp():
            terms.append(arg.object().name)
        elif arg.is_variable_exp():
            terms.append("?" + arg.variable().name)
        else:
            raise PDDLError(f"unsupported term {arg}")
    return tuple(terms)


def _literals(node: Any, where: str) -> Iterator[tuple[bool, str, tuple[str, ...]]]:
    """Flatten a conjunction into (positive, predicate-or-'=', terms)."""
    if node.is_true():
        return
    if node.is_and():
        for arg in node.args:
            yield from _literals(arg, where)
        return
    positive = True
    if node.is_not():
        positive, node = False, node.arg(0)
    if node.is_fluent_exp():
        yield positive, node.fluent().name, _terms(node)
    elif node.is_equals():
        yield positive, "=", _terms(node)
    else:
        raise PDDLError(f"{where}: unsupported PDDL construct {node} (only STRIPS literals)")


def _schema_from_up(action: Any) -> ActionSchema:
    where = f"action {action.name}"
    params = tuple(("?" + p.name, p.type.name) for p in action.parameters)
    pre_pos: list[Atom] = []
    pre_neg: list[Atom] = []
    equal: list[tuple[str, str]] = []
    not_equal: list[tuple[str, str]] = []
    for pre in action.preconditions:
        for positive, pred, terms in _literals(pre, where):
            if pred == "=":
                (equal if positive else not_equal).append((terms[0], terms[1]))
            else:
                (pre_pos if positive else pre_neg).append(Atom(pred, terms))
    add: list[Atom] = []
    delete: list[Atom] = []
    for effect in action.effects:
        if effect.is_conditional() or effect.is_forall():
            raise PDDLError(f"{where}: conditional and universal effects are not supported")
        atom = Atom(effect.fluent.fluent().name, _terms(effect.fluent))
        (add if effect.value.is_true() else delete).append(atom)
    return ActionSchema(
        action.name,
        params,
        tuple(pre_pos),
        tuple(pre_neg),
        tuple(add),
        tuple(delete),
        tuple(equal),
        tuple(not_equal),
    )


def _fact(node: Any) -> Fact:
    return (node.fluent().name, *_terms(node))


# ------------------------------------------------------------------- loading


def parse_problem(
    domain_text: str,
    problem_text: str,
    domain_source: str | None = None,
    problem_source: str | None = None,
) -> Problem:
    """Parse a domain and a problem given as PDDL text."""
    read_sexp(domain_text, domain_source, single=True)  # unbalanced parentheses: file and line
    read_sexp(problem_text, problem_source, single=True)
    domain_text, problem_text = _repair_undeclared_constants(
        domain_text, problem_text, domain_source, problem_source
    )
    up_problem = _parse_with_up(domain_text, problem_text, domain_source, problem_source)
    domain_body = _define_body(domain_text, "domain", domain_source)
    domain_name_expr = domain_body[1]
    domain_name = (
        str(domain_name_expr[1])
        if isinstance(domain_name_expr, list) and len(domain_name_expr) > 1
        else "domain"
    )
    requirements = tuple(
        r for r in (_section(domain_body, ":requirements") or [":r"])[1:] if isinstance(r, str)
    )
    constant_names = {
        n for n, _ in _typed_names((_section(domain_body, ":constants") or [":c"])[1:])
    }
    types: dict[str, str | None] = {}
    for user_type in up_problem.user_types:
        types[user_type.name] = user_type.father.name if user_type.father is not None else None
    if not types:
        types["object"] = None
    all_objects = {o.name: o.type.name for o in up_problem.all_objects}
    constants = {n: t for n, t in all_objects.items() if n in constant_names}
    objects = {n: t for n, t in all_objects.items() if n not in constant_names}
    predicates = {f.name: tuple(p.type.name for p in f.signature) for f in up_problem.fluents}
    actions = {a.name: _schema_from_up(a) for a in up_problem.actions}
    domain = Domain(domain_name, requirements, types, constants, predicates, actions, domain_source)
    init = frozenset(_fact(k) for k, v in up_problem.explicit_initial_values.items() if v.is_true())
    positive: set[Fact] = set()
    negative: set[Fact] = set()
    for goal in up_problem.goals:
        for is_positive, pred, terms in _literals(goal, "goal"):
            if pred == "=":
                raise PDDLError("equality in the goal is not supported", problem_source)
            (positive if is_positive else negative).add((pred, *terms))
    return Problem(
        up_problem.name,
        domain,
        objects,
        init,
        Goal(frozenset(positive), frozenset(negative)),
        problem_source,
    )


def load_problem(domain_path: str | Path, problem_path: str | Path) -> Problem:
    """Read a domain file and a problem file."""
    domain_path, problem_path = Path(domain_path), Path(problem_path)
    for path in (domain_path, problem_path):
        if not path.is_file():
            raise PDDLError("no such file", str(path))
    return parse_problem(
        domain_path.read_text(), problem_path.read_text(), str(domain_path), str(problem_path)
    )


# ------------------------------------------------------------------- goals


def parse_goal(text: str, problem: Problem, source: str = "subgoal") -> Goal:
    """Parse a PDDL goal and check it against ``problem``.

    Accepts ``(:goal (and ...))``, ``(and ...)``, a single literal, or several literals in a
    row. Raises :class:`PDDLError` naming the first unknown predicate, wrong arity or
    unknown object.
    """
    exprs = read_sexp(text, source)
    if len(exprs) == 1 and isinstance(exprs[0], list) and exprs[0][:1] == [":goal"]:
        exprs = exprs[0][1:]
    if len(exprs) == 1 and isinstance(exprs[0], list) and exprs[0][:1] == ["and"]:
        exprs = exprs[0][1:]
    if not exprs:
        raise PDDLError("the goal is empty", source)
    objects = problem.all_objects
    positive: set[Fact] = set()
    negative: set[Fact] = set()
    for expr in exprs:
        is_positive = True
        if isinstance(expr, list) and expr[:1] == ["not"] and len(expr) == 2:
            is_positive, expr = False, expr[1]
        if not isinstance(expr, list) or not expr or not all(isinstance(t, str) for t in expr):
            raise PDDLError(f"not a ground literal: {write_sexp(expr)}", source)
        pred, *args = [str(t) for t in expr]
        if pred not in problem.domain.predicates:
            raise PDDLError(f"unknown predicate '{pred}'", source)
        arity = len(problem.domain.predicates[pred])
        if len(args) != arity:
            raise PDDLError(f"'{pred}' takes {arity} argument(s), got {len(args)}", source)
        for arg in args:
            if arg not in objects:
                raise PDDLError(f"unknown object '{arg}' in {write_sexp(expr)}", source)
        (positive if is_positive else negative).add((pred, *args))
    if positive & negative:
        raise PDDLError("the goal asks for a fact and its negation", source)
    return Goal(frozenset(positive), frozenset(negative))


# ------------------------------------------------------------------- writing


def _requirements(domain: Domain, extra: Iterable[str] = ()) -> list[str]:
    reqs = set(domain.requirements) | set(extra) | {":strips"}
    if domain.typed:
        reqs.add(":typing")
    if any(a.pre_negative for a in domain.actions.values()):
        reqs.add(":negative-preconditions")
    if any(a.equal or a.not_equal for a in domain.actions.values()):
        reqs.add(":equality")
    return sorted(reqs)


def _typed_list(pairs: Iterable[tuple[str, str]], typed: bool) -> str:
    if not typed:
        return " ".join(name for name, _ in pairs)
    return " ".join(f"{name} - {type_name}" for name, type_name in pairs)


def _conjunction(parts: list[str]) -> str:
    if len(parts) == 1:
        return parts[0]
    return "(and " + " ".join(parts) + ")"


def domain_to_pddl(domain: Domain, extra_requirements: Iterable[str] = ()) -> str:
    """Write ``domain`` as PDDL text that Fast Downward and unified-planning both read."""
    typed = domain.typed
    lines = [f"(define (domain {domain.name})"]
    lines.append(" (:requirements " + " ".join(_requirements(domain, extra_requirements)) + ")")
    if typed:
        entries = [
            f"{t} - {parent or 'object'}" for t, parent in domain.types.items() if t != "object"
        ]
        lines.append(" (:types " + " ".join(entries) + ")")
    if domain.constants:
        lines.append(" (:constants " + _typed_list(domain.constants.items(), typed) + ")")
    preds = []
    for name, arg_types in domain.predicates.items():
        params = _typed_list(((f"?x{i}", t) for i, t in enumerate(arg_types)), typed)
        preds.append(f"({name}{' ' + params if params else ''})")
    lines.append(" (:predicates " + " ".join(preds) + ")")
    for action in domain.actions.values():
        pre = [str(a) for a in action.pre_positive]
        pre += [f"(not {a})" for a in action.pre_negative]
        pre += [f"(= {x} {y})" for x, y in action.equal]
        pre += [f"(not (= {x} {y}))" for x, y in action.not_equal]
        eff = [str(a) for a in action.add] + [f"(not {a})" for a in action.delete]
        lines.append(f" (:action {action.name}")
        lines.append(f"  :parameters ({_typed_list(action.parameters, typed)})")
        if pre:
            lines.append(f"  :precondition {_conjunction(pre)}")
        lines.append(f"  :effect {_conjunction(eff) if eff else '(and)'})")
    lines.append(")")
    return "\n".join(lines) + "\n"


def problem_to_pddl(problem: Problem) -> str:
    """Write ``problem`` (objects, initial state, goal) as PDDL text."""
    typed = problem.domain.typed
    lines = [f"(define (problem {problem.name})", f" (:domain {problem.domain.name})"]
    lines.append(" (:objects " + _typed_list(sorted(problem.objects.items()), typed) + ")")
    lines.append(" (:init")
    lines += [f"  {fact_to_pddl(f)}" for f in sorted(problem.init)]
    lines.append(" )")
    lines.append(f" (:goal {problem.goal.to_pddl()})")
    lines.append(")")
    return "\n".join(lines) + "\n"
