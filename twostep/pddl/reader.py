"""Reading domains, problems and goals: the s-expression checks, the repairs, unified-planning.

The model is STRIPS with typing, constants, negative preconditions and equality; tasks
beyond it (ADL, action costs, ``either`` types: AlfWorld's ``alfred.pddl``) are compiled into
it first by :mod:`twostep.pddl.adl`.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import pickle
import re
from importlib import metadata
from pathlib import Path

from twostep.files import write_bytes_atomic
from twostep.pddl import adl
from twostep.pddl.errors import PDDLError
from twostep.pddl.model import ActionOrigin, Domain, Fact, Goal, Problem
from twostep.pddl.repairs import repair_undeclared_constants
from twostep.pddl.sexp import SExp, define_body, read_sexp, section, typed_names, write_sexp
from twostep.pddl.unified import (
    action_costs,
    fact_from_up,
    literals,
    parse_with_up,
    schema_from_up,
)


def parse_problem(
    domain_text: str,
    problem_text: str,
    domain_source: str | None = None,
    problem_source: str | None = None,
) -> Problem:
    """Parse a domain and a problem given as PDDL text."""
    read_sexp(domain_text, domain_source, single=True)  # unbalanced parentheses: file and line
    read_sexp(problem_text, problem_source, single=True)
    original = (domain_text, problem_text)
    origins: dict[str, ActionOrigin] = {}
    costs: dict[str, int] = {}
    if adl.needs_compilation(
        define_body(domain_text, "domain", domain_source),
        define_body(problem_text, "problem", problem_source),
    ):
        compiled = adl.compile_task(domain_text, problem_text, domain_source, problem_source)
        domain_text, problem_text = compiled.domain_text, compiled.problem_text
        origins, costs = compiled.origins, compiled.costs
    domain_text, problem_text = repair_undeclared_constants(
        domain_text, problem_text, domain_source, problem_source
    )
    try:
        up_problem = parse_with_up(domain_text, problem_text, domain_source, problem_source)
    except PDDLError as error:
        named = _unknown_name(*original, domain_source, problem_source)
        if named is not None:  # clearer than unified-planning's "Not able to handle"
            raise named from None
        if not origins:
            raise
        # line numbers of the compiled text would mislead: name the files only
        raise PDDLError(f"after compiling ADL: {error.message}", error.source) from None
    domain_body = define_body(domain_text, "domain", domain_source)
    domain_name_expr = domain_body[1]
    domain_name = (
        str(domain_name_expr[1])
        if isinstance(domain_name_expr, list) and len(domain_name_expr) > 1
        else "domain"
    )
    requirements = tuple(
        r for r in (section(domain_body, ":requirements") or [":r"])[1:] if isinstance(r, str)
    )
    constant_names = {n for n, _ in typed_names((section(domain_body, ":constants") or [":c"])[1:])}
    types: dict[str, str | None] = {}
    for user_type in up_problem.user_types:
        types[user_type.name] = user_type.father.name if user_type.father is not None else None
    if not types:
        types["object"] = None
    all_objects = {o.name: o.type.name for o in up_problem.all_objects}
    constants = {n: t for n, t in all_objects.items() if n in constant_names}
    objects = {n: t for n, t in all_objects.items() if n not in constant_names}
    predicates = {f.name: tuple(p.type.name for p in f.signature) for f in up_problem.fluents}
    found = action_costs(up_problem)
    if costs:  # compiled from ADL: every action has a cost, 0 where nothing is increased
        found = {a.name: costs.get(a.name, 0) for a in up_problem.actions}
    try:
        actions = {a.name: schema_from_up(a, (found or {}).get(a.name)) for a in up_problem.actions}
    except PDDLError as error:
        raise PDDLError(error.message, error.source or domain_source, error.line) from None
    domain = Domain(
        domain_name, requirements, types, constants, predicates, actions, domain_source, origins
    )
    init = frozenset(
        fact_from_up(k) for k, v in up_problem.explicit_initial_values.items() if v.is_true()
    )
    positive: set[Fact] = set()
    negative: set[Fact] = set()
    for goal in up_problem.goals:
        for is_positive, pred, terms in literals(goal, "goal"):
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


_CONNECTIVES = frozenset(
    {"and", "or", "not", "=", "imply", "forall", "exists", "when", "increase", "decrease"}
)


def _unknown_name(
    domain_text: str,
    problem_text: str,
    domain_source: str | None,
    problem_source: str | None,
) -> PDDLError | None:
    """The first predicate or object of the problem's ``:init`` and ``:goal`` that the
    domain and problem do not declare, as an error with file and line (None: all known).
    Asked only after parsing failed, to say what unified-planning's message does not."""
    try:
        domain = define_body(domain_text, "domain", domain_source)
        problem = define_body(problem_text, "problem", problem_source)
    except PDDLError:
        return None
    predicates = {
        str(p[0]).lower()
        for p in (section(domain, ":predicates") or [":p"])[1:]
        if isinstance(p, list) and p
    }
    functions = {
        str(f[0]).lower()
        for f in (section(domain, ":functions") or [":f"])[1:]
        if isinstance(f, list) and f
    }
    objects = {
        n.lower()
        for key, body in ((":constants", domain), (":objects", problem))
        for n, _ in typed_names((section(body, key) or [key])[1:])
    }

    def first(expr: SExp, bound: frozenset[str]) -> tuple[str, str] | None:
        if not isinstance(expr, list) or not expr or not isinstance(expr[0], str):
            return None
        head = expr[0].lower()
        if head in ("forall", "exists") and len(expr) > 2 and isinstance(expr[1], list):
            names = {str(n).lower() for n, _ in typed_names(expr[1])}
            return first(expr[2], bound | names)
        if head in _CONNECTIVES:
            for arg in expr[1:]:
                found = first(arg, bound)
                if found:
                    return found
            return None
        if head in functions:
            return None
        if head not in predicates:
            return "predicate", head
        for term in expr[1:]:
            name = term.lower() if isinstance(term, str) else "?"
            if not name.startswith("?") and name not in objects and name not in bound:
                return "object", name
        return None

    for key in (":init", ":goal"):
        part = section(problem, key)
        for expr in (part or [key])[1:]:
            found = first(expr, frozenset())
            if found is None:
                continue
            kind, name = found
            pattern = (
                rf"\(\s*{re.escape(name)}[\s)]"
                if kind == "predicate"
                else rf"\b{re.escape(name)}\b"
            )
            line = _line_of(problem_text, pattern, key)
            known = sorted(predicates) if kind == "predicate" else sorted(objects)
            listing = ", ".join(known[:12]) + (", ..." if len(known) > 12 else "")
            return PDDLError(
                f"unknown {kind} '{name}' in {key} (declared: {listing or 'none'})",
                problem_source,
                line,
            )
    return None


def _line_of(text: str, pattern: str, after: str) -> int | None:
    """Line of the first match of ``pattern`` after the section ``after`` begins."""
    start = re.search(rf"\(\s*{re.escape(after)}\b", text, re.IGNORECASE)
    offset = start.start() if start else 0
    match = re.compile(pattern, re.IGNORECASE).search(text, offset)
    return text.count("\n", 0, match.start()) + 1 if match else None


def read_pddl_file(path: Path) -> str:
    """A PDDL file's text; a file that is not UTF-8 text is a :class:`PDDLError` naming it."""
    data = path.read_bytes()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise PDDLError(
            f"not a text file (byte {error.start} is not UTF-8): expected PDDL", str(path)
        ) from None


def load_problem(
    domain_path: str | Path, problem_path: str | Path, cache_dir: str | Path | None = None
) -> Problem:
    """Read a domain file and a problem file.

    ``cache_dir``: keep the parsed problem there, so that the next process reads it back
    in milliseconds instead of importing unified-planning and parsing (about a second).
    An entry is keyed by both files' paths and contents and by the parser's own code
    (:func:`_parser_version`): a change to any of them parses again. Files that do not
    parse raise as without a cache (nothing is stored).
    """
    domain_path, problem_path = Path(domain_path), Path(problem_path)
    for path in (domain_path, problem_path):
        if not path.is_file():
            raise PDDLError("no such file", str(path))
    domain_text, problem_text = read_pddl_file(domain_path), read_pddl_file(problem_path)
    sources = (str(domain_path), str(problem_path))
    if cache_dir is None:
        return parse_problem(domain_text, problem_text, *sources)
    key = hashlib.sha256(
        json.dumps([_parser_version(), *sources, domain_text, problem_text]).encode()
    ).hexdigest()
    entry = Path(cache_dir) / f"{key}.pickle"
    try:
        cached = pickle.loads(entry.read_bytes())
    except Exception:  # absent, or written by other code: parse again
        cached = None
    if isinstance(cached, Problem):
        return cached
    problem = parse_problem(domain_text, problem_text, *sources)
    with contextlib.suppress(OSError):  # a read-only cache only costs the parse
        write_bytes_atomic(entry, pickle.dumps(problem, protocol=pickle.HIGHEST_PROTOCOL))
    return problem


@functools.cache
def _parser_version() -> str:
    """Digest of what turns PDDL into a :class:`Problem`: this package's code and the
    unified-planning release that reads the files."""
    digest = hashlib.sha256()
    for module in sorted(Path(__file__).parent.glob("*.py")):
        digest.update(module.name.encode() + b"\0" + module.read_bytes())
    with contextlib.suppress(metadata.PackageNotFoundError):
        digest.update(metadata.version("unified-planning").encode())
    return digest.hexdigest()


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
    if any(adl.is_compound(expr) for expr in exprs):
        return adl.ground_goal(exprs, problem, source)
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
