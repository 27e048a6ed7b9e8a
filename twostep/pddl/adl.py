"""PDDL beyond STRIPS, compiled to the project's STRIPS model before unified-planning reads it.

Real domains such as AlfWorld's ``alfred.pddl`` use ADL (``exists``, ``forall``, ``or``,
``imply``, ``when``), ``:action-costs``, ``(either t1 t2)`` types, empty preconditions
``()``, variable lists with commas, untyped functions, predicates applied to arguments of
another type, and constants that only the problem declares. Fast Downward accepts all of
that; unified-planning's reader and the project's STRIPS model do not. This module
rewrites such a domain and problem, on s-expressions, into typed STRIPS with negative
preconditions and equality, and records how every compiled action maps back:

- ``forall`` (preconditions, goals, effects) is expanded over the task's objects;
- ``exists`` in a precondition becomes extra parameters of the action (appended after
  the original ones), so the compiled domain stays lifted;
- ``or`` (after negation normal form) splits an action into variants, one per disjunct;
- ``when`` splits an action into variants, one per consistent set of effect conditions
  (the conditions that hold, and the negations of the others, join the precondition);
- ``(either a b)`` parameters split an action into one variant per type; predicates
  take the closest common supertype;
- ``(increase (total-cost) n)`` becomes the variant's cost (:attr:`CompiledPDDL.costs`),
  written back as ``:action-costs`` for Fast Downward by :mod:`twostep.pddl.writer`;
- a goal with quantifiers or disjunctions is grounded; when the static facts of the task
  leave exactly one conjunction of literals, that is the goal; otherwise a goal action
  ``reach-goal`` (one variant per disjunct) achieves a new fact ``goal-reached``.

Each compiled action keeps the original name when it has a single variant, else
``<name>-v<k>``; :class:`~twostep.pddl.model.ActionOrigin` maps it back (original name and
number of original arguments); :mod:`twostep.pddl.origins` writes compiled plans in the
task's own terms and back. The compilation is sound and complete for the fragment above: every
compiled plan maps to a plan of the original task and vice versa.

Unsupported constructs (derived predicates, durative actions, numeric fluents other than
``total-cost``, costs from functions) raise :class:`PDDLError` naming the construct, the
file and the line.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

from twostep.pddl.errors import PDDLError
from twostep.pddl.model import ActionOrigin, Goal, Problem
from twostep.pddl.sexp import SExp, TypeSpec, define_body, section, typed_list, write_sexp

Atom = tuple[str, ...]
"""A possibly lifted atom: predicate (or ``=``) followed by terms."""

Literal = tuple[bool, Atom]

GOAL_ACTION = "reach-goal"
GOAL_FACT = "goal-reached"
COST_FUNCTION = "total-cost"
MAX_VARIANTS = 512  # per action: beyond this the case split is not worth planning with
MAX_WHEN = 10  # conditional effects per action (2^k condition assignments)
MAX_GOAL_BINDINGS = 20_000

_ADL_REQUIREMENTS = frozenset(
    {":adl", ":action-costs", ":conditional-effects", ":disjunctive-preconditions",
     ":existential-preconditions", ":universal-preconditions", ":quantified-preconditions",
     ":numeric-fluents", ":fluents"}
)  # fmt: skip
_ADL_HEADS = frozenset({"exists", "forall", "or", "imply", "when", "increase", "either"})
_UNSUPPORTED_SECTIONS = {
    ":derived": "derived predicates are not supported",
    ":durative-action": "durative actions are not supported",
    ":constraints": "constraints are not supported",
}
_NUMERIC_HEADS = frozenset(
    {"increase", "decrease", "assign", "scale-up", "scale-down", ">", "<", ">=", "<="}
)


# ----------------------------------------------------------------- detection and errors


def _heads(expr: SExp) -> Iterator[str]:
    if isinstance(expr, list):
        if expr and isinstance(expr[0], str):
            yield expr[0]
        if not expr:
            yield "()"
        for sub in expr:
            yield from _heads(sub)


def needs_compilation(domain_body: list[SExp], problem_body: list[SExp]) -> bool:
    """Whether a domain/problem pair uses anything beyond typed STRIPS (then: :func:`compile_task`)."""
    requirements = set((section(domain_body, ":requirements") or [])[1:])  # type: ignore[arg-type]
    if requirements & _ADL_REQUIREMENTS:
        return True
    for item in domain_body[2:]:
        if isinstance(item, list) and item and item[0] in (":functions", *_UNSUPPORTED_SECTIONS):
            return True
        if (_ADL_HEADS | _NUMERIC_HEADS) & set(_heads(item)):
            return True
        if isinstance(item, list) and item[:1] == [":action"]:
            parts = dict(zip(item[2::2], item[3::2], strict=False))  # type: ignore[arg-type]
            if [] in (parts.get(":precondition"), parts.get(":effect")):
                return True  # "()": AlfWorld's empty precondition
    for item in problem_body[2:]:
        if isinstance(item, list) and item and item[0] in (":metric",):
            return True
        heads = set(_heads(item[1:])) if isinstance(item, list) and item else set()
        if item[0] in (":goal", ":init") and (_ADL_HEADS | {"="}) & heads:
            return True
    return False


def _line_of(text: str | None, pattern: str) -> int | None:
    """The first line of ``text`` (comments ignored) on which ``pattern`` occurs."""
    if not text:
        return None
    regex = re.compile(pattern, re.IGNORECASE)
    for lineno, line in enumerate(text.splitlines(), start=1):
        if regex.search(line.split(";", 1)[0]):
            return lineno
    return None


@dataclass(frozen=True)
class _Source:
    text: str | None
    name: str | None

    def error(self, message: str, pattern: str | None = None) -> PDDLError:
        line = _line_of(self.text, pattern) if pattern else None
        return PDDLError(message, self.name, line)


# ----------------------------------------------------------------- types and objects


@dataclass
class _Types:
    parent: dict[str, str | None]

    def ancestors(self, name: str) -> list[str]:
        chain = [name]
        seen = {name}
        while (up := self.parent.get(chain[-1])) is not None and up not in seen:
            chain.append(up)
            seen.add(up)
        if chain[-1] != "object":
            chain.append("object")
        return chain

    def is_subtype(self, name: str, of: TypeSpec) -> bool:
        targets = (of,) if isinstance(of, str) else of
        return any(t in self.ancestors(name) for t in targets)

    def common(self, names: Iterable[str]) -> str:
        """The closest common supertype of ``names``."""
        names = list(names)
        if not names:
            return "object"
        shared = self.ancestors(names[0])
        for name in names[1:]:
            theirs = set(self.ancestors(name))
            shared = [t for t in shared if t in theirs]
        return shared[0] if shared else "object"

    def spec_types(self, spec: TypeSpec) -> tuple[str, ...]:
        return (spec,) if isinstance(spec, str) else spec


def _parse_types(domain_body: list[SExp]) -> _Types:
    parent: dict[str, str | None] = {}
    for name, spec in typed_list((section(domain_body, ":types") or [":types"])[1:]):
        if name == "object":
            continue  # the root; AlfWorld lists it among its types
        if isinstance(spec, tuple):
            raise PDDLError(f"type '{name}' has an (either ...) supertype: not supported")
        parent[name] = None if spec == "object" else spec
    return _Types(parent)


# ----------------------------------------------------------------- formulas


@dataclass(frozen=True)
class _Lit:
    positive: bool
    atom: Atom


@dataclass(frozen=True)
class _Junction:
    kind: str  # "and" | "or"
    parts: tuple[_Node, ...]


@dataclass(frozen=True)
class _Quantified:
    kind: str  # "exists" | "forall"
    variables: tuple[tuple[str, TypeSpec], ...]
    body: _Node


_Node = _Lit | _Junction | _Quantified

_TRUE = _Junction("and", ())


@dataclass
class _Context:
    """What formula parsing and grounding need to know about the task."""

    types: _Types
    predicates: dict[str, tuple[TypeSpec, ...]]
    objects: dict[str, str]  # every object and constant -> its type
    source: _Source
    counter: itertools.count[int] = field(default_factory=itertools.count)
    init: frozenset[Atom] = frozenset()
    changing: set[str] | None = None
    """Predicates some action changes; the others are static, so a ground literal of one
    is decided by ``init`` (None: unknown yet, nothing is decided)."""

    def static_truth(self, lit: _Lit) -> bool | None:
        atom = lit.atom
        if self.changing is None or atom[0] == "=" or atom[0] in self.changing:
            return None
        if any(t.startswith("?") for t in atom[1:]):
            return None
        return (atom in self.init) == lit.positive

    def objects_of(self, spec: TypeSpec) -> list[str]:
        return sorted(o for o, t in self.objects.items() if self.types.is_subtype(t, spec))


def _parse_formula(expr: SExp, ctx: _Context, where: str) -> _Node:
    if isinstance(expr, str):
        raise ctx.source.error(f"{where}: expected a formula, got '{expr}'")
    if not expr:
        return _TRUE  # "()" is the empty precondition
    head = expr[0]
    if head in ("and", "or"):
        return _Junction(str(head), tuple(_parse_formula(e, ctx, where) for e in expr[1:]))
    if head == "not" and len(expr) == 2:
        return _negate(_parse_formula(expr[1], ctx, where))
    if head == "imply" and len(expr) == 3:
        antecedent = _parse_formula(expr[1], ctx, where)
        return _Junction("or", (_negate(antecedent), _parse_formula(expr[2], ctx, where)))
    if head in ("exists", "forall") and len(expr) == 3 and isinstance(expr[1], list):
        variables = tuple(typed_list(expr[1]))
        return _Quantified(str(head), variables, _parse_formula(expr[2], ctx, where))
    if head in _NUMERIC_HEADS:
        raise ctx.source.error(
            f"{where}: numeric conditions ({head} ...) are not supported",
            rf"\({re.escape(str(head))}\s",
        )
    if not all(isinstance(t, str) for t in expr):
        raise ctx.source.error(f"{where}: unsupported PDDL construct {write_sexp(expr)}")
    atom = tuple(str(t) for t in expr)
    if atom[0] != "=" and atom[0] not in ctx.predicates:
        raise ctx.source.error(
            f"{where}: unknown predicate '{atom[0]}'", rf"\({re.escape(atom[0])}[\s)]"
        )
    return _Lit(True, atom)


def _negate(node: _Node) -> _Node:
    """Negation pushed to the literals (negation normal form)."""
    if isinstance(node, _Lit):
        return _Lit(not node.positive, node.atom)
    if isinstance(node, _Junction):
        return _Junction(
            "or" if node.kind == "and" else "and", tuple(_negate(p) for p in node.parts)
        )
    return _Quantified(
        "forall" if node.kind == "exists" else "exists", node.variables, _negate(node.body)
    )


def _substitute(node: _Node, binding: Mapping[str, str]) -> _Node:
    if isinstance(node, _Lit):
        return _Lit(node.positive, tuple(binding.get(t, t) for t in node.atom))
    if isinstance(node, _Junction):
        return _Junction(node.kind, tuple(_substitute(p, binding) for p in node.parts))
    inner = {k: v for k, v in binding.items() if k not in {v for v, _ in node.variables}}
    return _Quantified(node.kind, node.variables, _substitute(node.body, inner))


@dataclass(frozen=True)
class _Disjunct:
    literals: tuple[_Lit, ...]
    parameters: tuple[tuple[str, TypeSpec], ...]  # existential variables lifted to parameters


def _conjoin(a: _Disjunct, b: _Disjunct) -> _Disjunct:
    return _Disjunct(a.literals + b.literals, a.parameters + b.parameters)


def _dnf(node: _Node, ctx: _Context) -> list[_Disjunct]:
    """Disjunctive normal form; ``exists`` variables become fresh parameters, ``forall`` expands."""
    if isinstance(node, _Lit):
        return [_Disjunct((node,), ())]
    if isinstance(node, _Junction):
        if node.kind == "or":
            options: list[_Disjunct] = []
            for part in node.parts:
                for d in _dnf(part, ctx):
                    simple = _simplify(d, ctx)
                    if simple == _Disjunct((), ()):
                        return [simple]  # one option always holds: so does the "or"
                    if simple is not None and simple not in options:
                        options.append(simple)
            return options
        result = [_Disjunct((), ())]
        for part in node.parts:
            result = [_conjoin(a, b) for a in result for b in _dnf(part, ctx)]
            result = list(
                dict.fromkeys(d for d in (_simplify(d, ctx) for d in result) if d is not None)
            )
            if len(result) > MAX_VARIANTS:
                raise ctx.source.error(
                    f"a formula has more than {MAX_VARIANTS} disjuncts after normalisation"
                )
        return result
    if node.kind == "forall":
        groundings = itertools.product(*(ctx.objects_of(t) for _, t in node.variables))
        names = [v for v, _ in node.variables]
        parts = tuple(_substitute(node.body, dict(zip(names, g, strict=True))) for g in groundings)
        return _dnf(_Junction("and", parts), ctx)
    fresh = {v: f"{v}_{next(ctx.counter)}" for v, _ in node.variables}
    lifted = tuple((fresh[v], t) for v, t in node.variables)
    return [
        _Disjunct(d.literals, lifted + d.parameters)
        for d in _dnf(_substitute(node.body, fresh), ctx)
    ]


def _simplify(d: _Disjunct, ctx: _Context) -> _Disjunct | None:
    """Drop duplicate and trivially true literals; None when the conjunction cannot hold.

    Ground literals of static predicates are decided by the initial state.
    """
    seen: dict[Atom, bool] = {}
    kept: list[_Lit] = []
    for lit in d.literals:
        atom = lit.atom
        decided = ctx.static_truth(lit)
        if decided is not None:
            if decided:
                continue
            return None
        if atom[0] == "=" and len(atom) == 3:
            a, b = atom[1], atom[2]
            if a == b:
                if lit.positive:
                    continue
                return None
            if not a.startswith("?") and not b.startswith("?"):
                if lit.positive:
                    return None
                continue
        if atom in seen:
            if seen[atom] != lit.positive:
                return None
            continue
        seen[atom] = lit.positive
        kept.append(lit)
    return _Disjunct(tuple(kept), d.parameters)


# ----------------------------------------------------------------- effects


@dataclass(frozen=True)
class _Effect:
    add: tuple[Atom, ...] = ()
    delete: tuple[Atom, ...] = ()
    cost: int = 0

    def __add__(self, other: _Effect) -> _Effect:
        return _Effect(self.add + other.add, self.delete + other.delete, self.cost + other.cost)


@dataclass(frozen=True)
class _When:
    condition: _Node
    effect: _Effect


def _parse_effect(
    expr: SExp, ctx: _Context, where: str, binding: Mapping[str, str], inside_when: bool = False
) -> tuple[_Effect, list[_When]]:
    if isinstance(expr, str):
        raise ctx.source.error(f"{where}: expected an effect, got '{expr}'")
    whens: list[_When]
    if not expr or expr[0] == "and":
        total, whens = _Effect(), []
        for sub in expr[1:]:
            effect, more = _parse_effect(sub, ctx, where, binding, inside_when)
            total, whens = total + effect, whens + more
        return total, whens
    head = expr[0]
    if head == "not" and len(expr) == 2 and isinstance(expr[1], list):
        atom = _effect_atom(expr[1], ctx, where, binding)
        return _Effect(delete=(atom,)), []
    if head == "forall" and len(expr) == 3 and isinstance(expr[1], list):
        variables = typed_list(expr[1])
        total, whens = _Effect(), []
        for grounding in itertools.product(*(ctx.objects_of(t) for _, t in variables)):
            inner = dict(binding)
            inner.update(zip((v for v, _ in variables), grounding, strict=True))
            effect, more = _parse_effect(expr[2], ctx, where, inner, inside_when)
            total, whens = total + effect, whens + more
        return total, whens
    if head == "when" and len(expr) == 3:
        if inside_when:
            raise ctx.source.error(
                f"{where}: nested conditional effects are not supported", r"\(when\s"
            )
        condition = _substitute(_parse_formula(expr[1], ctx, where), binding)
        effect, _ = _parse_effect(expr[2], ctx, where, binding, inside_when=True)
        return _Effect(), [_When(condition, effect)]
    if head == "increase" and len(expr) == 3:
        target, amount = expr[1], expr[2]
        if target != [COST_FUNCTION] and target != COST_FUNCTION:
            raise ctx.source.error(
                f"{where}: numeric fluent {write_sexp(target)} is not supported (only total-cost)",
                r"\(increase\s",
            )
        if isinstance(amount, str) and re.fullmatch(r"\d+(\.0+)?", amount):
            return _Effect(cost=int(float(amount))), []
        raise ctx.source.error(
            f"{where}: action costs from functions ({write_sexp(amount)}) are not supported, "
            "only constant costs",
            r"\(increase\s",
        )
    if head in _NUMERIC_HEADS:
        raise ctx.source.error(
            f"{where}: numeric effects ({head} ...) are not supported", rf"\({head}\s"
        )
    return _Effect(add=(_effect_atom(expr, ctx, where, binding),)), []


def _effect_atom(expr: SExp, ctx: _Context, where: str, binding: Mapping[str, str]) -> Atom:
    if not isinstance(expr, list) or not expr or not all(isinstance(t, str) for t in expr):
        raise ctx.source.error(f"{where}: unsupported effect {write_sexp(expr)}")
    atom = tuple(binding.get(str(t), str(t)) for t in expr)
    if atom[0] not in ctx.predicates:
        raise ctx.source.error(
            f"{where}: unknown predicate '{atom[0]}'", rf"\({re.escape(atom[0])}[\s)]"
        )
    return atom


# ----------------------------------------------------------------- actions


@dataclass(frozen=True)
class _Variant:
    name: str
    parameters: tuple[tuple[str, str], ...]
    literals: tuple[_Lit, ...]
    effect: _Effect
    origin: ActionOrigin


def _split_either(
    parameters: Sequence[tuple[str, TypeSpec]],
) -> list[tuple[tuple[str, str], ...]]:
    choices = [[(v, t)] if isinstance(t, str) else [(v, alt) for alt in t] for v, t in parameters]
    return [tuple(c) for c in itertools.product(*choices)]


def _compile_action(item: list[SExp], ctx: _Context) -> list[_Variant]:
    name = str(item[1])
    where = f"action {name}"
    keys = {str(k): v for k, v in zip(item[2::2], item[3::2], strict=False)}
    parameters = typed_list(keys.get(":parameters") or [])  # type: ignore[arg-type]
    precondition = _parse_formula(keys.get(":precondition", []), ctx, where)
    base, whens = _parse_effect(keys.get(":effect", []), ctx, where, {})
    if len(whens) > MAX_WHEN:
        raise ctx.source.error(f"{where}: more than {MAX_WHEN} conditional effects", r"\(when\s")
    cases: list[tuple[_Node, _Effect]] = []
    for assignment in itertools.product((True, False), repeat=len(whens)):
        conditions = [
            w.condition if on else _negate(w.condition)
            for w, on in zip(whens, assignment, strict=True)
        ]
        effect = base
        for w, on in zip(whens, assignment, strict=True):
            if on:
                effect = effect + w.effect
        cases.append((_Junction("and", (precondition, *conditions)), effect))
    variants: list[tuple[tuple[tuple[str, str], ...], _Disjunct, _Effect]] = []
    for formula, effect in cases:
        for disjunct in _dnf(formula, ctx):
            for typed in _split_either([*parameters, *disjunct.parameters]):
                variants.append((typed, disjunct, effect))
    if len(variants) > MAX_VARIANTS:
        raise ctx.source.error(f"{where}: more than {MAX_VARIANTS} variants after compilation")
    origin = ActionOrigin(name, len(parameters))
    return [
        _Variant(
            name if len(variants) == 1 else f"{name}-v{k}", typed, disjunct.literals, effect, origin
        )
        for k, (typed, disjunct, effect) in enumerate(variants, start=1)
    ]


# ----------------------------------------------------------------- goals


def _ground_disjuncts(
    disjuncts: Sequence[_Disjunct],
    ctx: _Context,
    init: frozenset[Atom],
    changing: set[str],
) -> list[tuple[frozenset[Atom], frozenset[Atom]]] | None:
    """Every ground conjunction (positive, negative) a goal in DNF can take.

    Existential parameters are bound to objects consistent with the static literals (those
    of predicates no action changes), which are then evaluated and dropped. Returns None
    when there are more than :data:`MAX_GOAL_BINDINGS` bindings.
    """
    found: list[tuple[frozenset[Atom], frozenset[Atom]]] = []
    budget = [MAX_GOAL_BINDINGS]
    for disjunct in disjuncts:
        if not _bind(disjunct, ctx, init, changing, {}, found, budget):
            return None
    return list(dict.fromkeys(found))


def _is_static(lit: _Lit, changing: set[str]) -> bool:
    return lit.atom[0] == "=" or lit.atom[0] not in changing


def _bind(
    disjunct: _Disjunct,
    ctx: _Context,
    init: frozenset[Atom],
    changing: set[str],
    binding: dict[str, str],
    found: list[tuple[frozenset[Atom], frozenset[Atom]]],
    budget: list[int],
) -> bool:
    """Backtracking over the existential parameters; False when the budget runs out."""
    for lit in disjunct.literals:
        if not _is_static(lit, changing):
            continue
        atom = tuple(binding.get(t, t) for t in lit.atom)
        if any(t.startswith("?") for t in atom[1:]):
            continue
        holds = atom[1] == atom[2] if atom[0] == "=" else atom in init
        if holds != lit.positive:
            return True  # this branch cannot hold: prune it
    if len(binding) == len(disjunct.parameters):
        budget[0] -= 1
        if budget[0] < 0:
            return False
        dynamic = [
            (lit.positive, tuple(binding.get(t, t) for t in lit.atom))
            for lit in disjunct.literals
            if not _is_static(lit, changing)
        ]
        positive = frozenset(a for p, a in dynamic if p)
        negative = frozenset(a for p, a in dynamic if not p)
        if not positive & negative:
            found.append((positive, negative))
        return True
    variable, spec = disjunct.parameters[len(binding)]
    for obj in ctx.objects_of(spec):
        binding[variable] = obj
        if not _bind(disjunct, ctx, init, changing, binding, found, budget):
            return False
        del binding[variable]
    return True


def _check_atoms(
    exprs: Sequence[SExp],
    predicates: Mapping[str, tuple[str, ...]],
    objects: Mapping[str, str],
    source: str,
) -> None:
    """Unknown predicates, wrong arities and unknown objects, before anything is decided."""
    for expr in exprs:
        if not isinstance(expr, list) or not expr:
            continue
        head = expr[0]
        if head in ("exists", "forall") and len(expr) == 3:
            _check_atoms([expr[2]], predicates, objects, source)
        elif head in ("and", "or", "not", "imply"):
            _check_atoms(expr[1:], predicates, objects, source)
        elif isinstance(head, str) and head != "=":
            if head not in predicates:
                raise PDDLError(f"unknown predicate '{head}'", source)
            if len(expr) - 1 != len(predicates[head]):
                arity = len(predicates[head])
                raise PDDLError(f"'{head}' takes {arity} argument(s), got {len(expr) - 1}", source)
        if isinstance(head, str) and head not in ("exists", "forall"):
            for term in expr[1:]:
                if isinstance(term, str) and not term.startswith("?") and term not in objects:
                    raise PDDLError(f"unknown object '{term}' in {write_sexp(expr)}", source)


def ground_goal(exprs: Sequence[SExp], problem: Problem, source: str) -> Goal:
    """A goal with quantifiers or disjunctions, grounded against ``problem`` (for subgoals).

    The static facts of the task must leave exactly one conjunction of literals, e.g.
    ``(exists (?o - object) (and (objectType ?o EggType) (isHot ?o)))`` with one egg.
    """
    domain = problem.domain
    types = _Types({t: p for t, p in domain.types.items() if t != "object"})
    objects = problem.all_objects
    changing = {
        a.predicate for schema in domain.actions.values() for a in (*schema.add, *schema.delete)
    }
    ctx = _Context(
        types,
        dict(domain.predicates),
        dict(objects),
        _Source(None, source),
        init=problem.init,
        changing=changing,
    )
    _check_atoms(exprs, domain.predicates, objects, source)
    node = _parse_formula(["and", *exprs], ctx, "goal")
    disjuncts = _dnf(node, ctx)
    grounded = _ground_disjuncts(disjuncts, ctx, problem.init, changing)
    if grounded is None or len(grounded) != 1:
        count = "too many" if grounded is None else str(len(grounded))
        text = " ".join(write_sexp(e) for e in exprs)
        raise PDDLError(
            f"not a ground literal conjunction: {text} can be met in {count} different ways "
            "(0: never); name the objects instead of quantifying or choosing",
            source,
        )
    positive, negative = grounded[0]
    return Goal(positive, negative)


# ----------------------------------------------------------------- the whole task


@dataclass(frozen=True)
class CompiledPDDL:
    """A domain and problem rewritten in typed STRIPS, with the way back."""

    domain_text: str
    problem_text: str
    origins: dict[str, ActionOrigin]
    costs: dict[str, int]


def _fresh(name: str, taken: Iterable[str]) -> str:
    taken = set(taken)
    candidate, k = name, 1
    while candidate in taken:
        k += 1
        candidate = f"{name}-{k}"
    return candidate


def compile_task(
    domain_text: str,
    problem_text: str,
    domain_source: str | None = None,
    problem_source: str | None = None,
) -> CompiledPDDL:
    """Compile a domain and problem beyond STRIPS into typed STRIPS PDDL text (see module doc)."""
    dsrc, psrc = _Source(domain_text, domain_source), _Source(problem_text, problem_source)
    domain_body = define_body(domain_text, "domain", domain_source)
    problem_body = define_body(problem_text, "problem", problem_source)
    for item in domain_body[2:]:
        if isinstance(item, list) and item and item[0] in _UNSUPPORTED_SECTIONS:
            key = str(item[0])
            raise dsrc.error(_UNSUPPORTED_SECTIONS[key], rf"\({re.escape(key)}[\s)]")
    try:
        types = _parse_types(domain_body)
    except PDDLError as error:
        raise dsrc.error(error.message, r"\(:types") from None
    domain_name = (
        domain_body[1][1]
        if isinstance(domain_body[1], list) and len(domain_body[1]) > 1
        else "domain"
    )
    predicates: dict[str, tuple[TypeSpec, ...]] = {}
    for entry in (section(domain_body, ":predicates") or [":predicates"])[1:]:
        if isinstance(entry, list) and entry and isinstance(entry[0], str):
            predicates[entry[0]] = tuple(t for _, t in typed_list(entry[1:]))
    constants = dict(typed_list((section(domain_body, ":constants") or [":c"])[1:]))
    problem_objects = dict(typed_list((section(problem_body, ":objects") or [":o"])[1:]))
    for name, spec in [*constants.items(), *problem_objects.items()]:
        if isinstance(spec, tuple):
            raise (dsrc if name in constants else psrc).error(
                f"object '{name}' has an (either ...) type"
            )
    objects: dict[str, str] = {n: str(t) for n, t in {**problem_objects, **constants}.items()}
    for name, type_name in objects.items():
        if type_name != "object" and type_name not in types.parent:
            where = dsrc if name in constants else psrc
            raise where.error(
                f"object '{name}' has unknown type '{type_name}'", rf"\b{re.escape(type_name)}\b"
            )

    actions = [i for i in domain_body[2:] if isinstance(i, list) and i and i[0] == ":action"]
    # Constants the actions use but only the problem declares (or nobody: then typed from
    # the predicate's declaration; no fact mentions them, so they change nothing).
    used_constants: dict[str, str] = {}

    def collect(expr: SExp, variables: set[str]) -> None:
        if not isinstance(expr, list) or not expr:
            return
        head = expr[0]
        if head in ("exists", "forall") and len(expr) == 3 and isinstance(expr[1], list):
            inner = variables | {v for v, _ in typed_list(expr[1])}
            collect(expr[2], inner)
            return
        if isinstance(head, str) and (head in predicates or head == "="):
            specs = predicates.get(head, ())
            for i, term in enumerate(expr[1:]):
                if isinstance(term, str) and not term.startswith("?") and term not in constants:
                    spec = specs[i] if i < len(specs) else "object"
                    used_constants.setdefault(term, spec if isinstance(spec, str) else spec[0])
        for sub in expr[1:]:
            collect(sub, variables)

    for item in actions:
        for part, value in zip(item[2::2], item[3::2], strict=False):
            if part in (":precondition", ":effect"):
                collect(value, set())
    for name, spec in used_constants.items():
        constants[name] = problem_objects.get(name, spec)
        objects[name] = str(constants[name])

    # initial atoms (numeric facts dropped): they decide ground static literals
    init: set[Atom] = set()
    for fact in (section(problem_body, ":init") or [":init"])[1:]:
        if isinstance(fact, list) and fact and fact[0] == "=":
            continue  # (= (total-cost) 0), (= (distance a b) 3): numeric facts
        if isinstance(fact, list) and fact[:1] == ["not"]:
            continue  # closed world: a negative initial fact says nothing new
        if not isinstance(fact, list) or not fact or not all(isinstance(t, str) for t in fact):
            raise psrc.error(f"unsupported initial fact {write_sexp(fact)}", r"\(:init")
        init.add(tuple(str(t) for t in fact))
    changing = {
        head
        for item in actions
        for part, value in zip(item[2::2], item[3::2], strict=False)
        if part == ":effect"
        for head in _heads(value)
        if head in predicates
    }  # over-approximated (when conditions included): fewer statics, still sound
    ctx = _Context(types, predicates, objects, dsrc, init=frozenset(init), changing=changing)
    variants: list[_Variant] = []
    for item in actions:
        if len(item) < 2 or not isinstance(item[1], str):
            raise dsrc.error("an action without a name", r"\(:action")
        variants += _compile_action(item, ctx)
    taken = {v.name for v in variants}
    if len(taken) != len(variants):  # a "<name>-v<k>" that collides with another action
        raise dsrc.error("compiled action names collide; rename the domain's '-v<k>' actions")

    goal_expr = (section(problem_body, ":goal") or [":goal", []])[1:]
    goal_ctx = _Context(types, predicates, objects, psrc, ctx.counter, ctx.init, changing)
    goal_node = _parse_formula(goal_expr[0] if goal_expr else [], goal_ctx, "goal")
    disjuncts = _dnf(goal_node, goal_ctx)
    grounded = _ground_disjuncts(disjuncts, goal_ctx, frozenset(init), changing)
    goal_fact: str | None = None
    goal_literals: list[SExp]
    if grounded is not None and len(grounded) == 1:
        positive, negative = grounded[0]
        goal_literals = [_sexp(a) for a in sorted(positive)]
        goal_literals += [["not", _sexp(a)] for a in sorted(negative)]
    else:
        # a choice the static facts do not settle: let the planner choose (goal action)
        goal_fact = _fresh(GOAL_FACT, predicates)
        goal_name = _fresh(GOAL_ACTION, taken)
        agent_parameter = _agent_parameter(types, variants)
        for k, disjunct in enumerate(disjuncts, start=1):
            for typed in _split_either(disjunct.parameters):
                name = goal_name if len(disjuncts) == 1 else f"{goal_name}-v{k}"
                name = _fresh(name, taken)
                taken.add(name)
                literals = disjunct.literals
                if agent_parameter:
                    # the agent that reaches the goal is the one the goal quantifies over,
                    # so that a multi-agent plan gives the goal step to that agent
                    agent_variable = agent_parameter[0][0]
                    same = {v: agent_variable for v, t in typed if types.is_subtype(t, "agent")}
                    typed = tuple((v, t) for v, t in typed if v not in same)
                    literals = tuple(
                        _Lit(lit.positive, tuple(same.get(x, x) for x in lit.atom))
                        for lit in literals
                    )
                params = (*typed, *agent_parameter)
                variants.append(
                    _Variant(
                        name,
                        params,
                        literals,
                        _Effect(add=((goal_fact,),)),
                        ActionOrigin(None, 0),
                    )
                )
        goal_literals = [_sexp((goal_fact,))]

    # predicate signatures: widened where the task applies them to other types
    signatures = _signatures(predicates, types, variants, objects, init, goal_literals)
    if goal_fact is not None:
        signatures[goal_fact] = ()
    domain_out = _write_domain(str(domain_name), types, constants, signatures, variants)
    problem_name = (
        problem_body[1][1]
        if isinstance(problem_body[1], list) and len(problem_body[1]) > 1
        else "problem"
    )
    problem_out = _write_problem(
        str(problem_name),
        str(domain_name),
        {n: str(t) for n, t in problem_objects.items() if n not in constants},
        init,
        goal_literals,
    )
    return CompiledPDDL(
        domain_out,
        problem_out,
        {v.name: v.origin for v in variants},
        {v.name: v.effect.cost for v in variants if v.effect.cost},
    )


def _sexp(atom: Atom) -> list[SExp]:
    out: list[SExp] = []
    out.extend(atom)
    return out


def _agent_parameter(types: _Types, variants: Sequence[_Variant]) -> tuple[tuple[str, str], ...]:
    """``(?agent - agent)`` for the goal action when every action of the domain has an agent."""
    if "agent" not in types.parent:
        return ()
    if all(any(types.is_subtype(t, "agent") for _, t in v.parameters) for v in variants):
        return (("?goal-agent", "agent"),)
    return ()


def _signatures(
    predicates: Mapping[str, tuple[TypeSpec, ...]],
    types: _Types,
    variants: Sequence[_Variant],
    objects: Mapping[str, str],
    init: Iterable[Atom],
    goal: Sequence[SExp],
) -> dict[str, tuple[str, ...]]:
    used: dict[str, list[set[str]]] = {p: [set() for _ in specs] for p, specs in predicates.items()}

    def note(atom: Sequence[str], scope: Mapping[str, str]) -> None:
        slots = used.get(atom[0])
        if slots is None:
            return
        for i, term in enumerate(atom[1:]):
            if i < len(slots):
                type_name = scope.get(term) or objects.get(term)
                if type_name is not None:
                    slots[i].add(type_name)

    for v in variants:
        scope = dict(v.parameters)
        for lit in v.literals:
            note(lit.atom, scope)
        for atom in (*v.effect.add, *v.effect.delete):
            note(atom, scope)
    for atom in init:
        note(atom, {})
    for entry in goal:
        if isinstance(entry, list) and entry:
            inner = entry[1] if entry[0] == "not" else entry
            if isinstance(inner, list):
                note([str(t) for t in inner], {})
    result: dict[str, tuple[str, ...]] = {}
    for name, specs in predicates.items():
        arg_types = []
        for spec, seen in zip(specs, used[name], strict=True):
            declared = types.spec_types(spec)
            if isinstance(spec, str) and all(types.is_subtype(t, spec) for t in seen):
                arg_types.append(spec)
            else:
                arg_types.append(types.common([*declared, *seen]))
        result[name] = tuple(arg_types)
    return result


def _typed(pairs: Iterable[tuple[str, str]]) -> str:
    return " ".join(f"{n} - {t}" for n, t in pairs)


def _lit_text(lit: _Lit) -> str:
    text = "(" + " ".join(lit.atom) + ")"
    return text if lit.positive else f"(not {text})"


def _write_domain(
    name: str,
    types: _Types,
    constants: Mapping[str, TypeSpec],
    predicates: Mapping[str, tuple[str, ...]],
    variants: Sequence[_Variant],
) -> str:
    lines = [f"(define (domain {name})"]
    lines.append(" (:requirements :strips :typing :negative-preconditions :equality)")
    if types.parent:
        lines.append(
            " (:types " + " ".join(f"{t} - {p or 'object'}" for t, p in types.parent.items()) + ")"
        )
    if constants:
        lines.append(" (:constants " + _typed((n, str(t)) for n, t in constants.items()) + ")")
    preds = [
        "(" + " ".join([p, *(f"?x{i} - {t}" for i, t in enumerate(args))]) + ")"
        for p, args in predicates.items()
    ]
    lines.append(" (:predicates " + " ".join(preds) + ")")
    for v in variants:
        lines.append(f" (:action {v.name}")
        lines.append(f"  :parameters ({_typed(v.parameters)})")
        pre = [_lit_text(lit) for lit in v.literals]
        if pre:
            lines.append("  :precondition (and " + " ".join(pre) + ")")
        add = ["(" + " ".join(a) + ")" for a in dict.fromkeys(v.effect.add)]
        delete = [
            f"(not ({' '.join(a)}))"
            for a in dict.fromkeys(v.effect.delete)
            if a not in v.effect.add
        ]
        lines.append("  :effect (and " + " ".join(add + delete) + "))")
    lines.append(")")
    return "\n".join(lines) + "\n"


def _write_problem(
    name: str, domain: str, objects: Mapping[str, str], init: Iterable[Atom], goal: Sequence[SExp]
) -> str:
    lines = [f"(define (problem {name})", f" (:domain {domain})"]
    lines.append(" (:objects " + _typed(sorted(objects.items())) + ")")
    lines.append(" (:init")
    lines += ["  (" + " ".join(atom) + ")" for atom in sorted(init)]
    lines.append(" )")
    lines.append(" (:goal (and " + " ".join(write_sexp(g) for g in goal) + "))")
    lines.append(")")
    return "\n".join(lines) + "\n"


def is_compound(expr: SExp) -> bool:
    """Whether a goal expression is more than a literal (quantifier, disjunction, ...)."""
    return (
        isinstance(expr, list)
        and bool(expr)
        and expr[0] in ("exists", "forall", "or", "imply", "and")
    )
