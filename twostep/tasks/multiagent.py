"""The MA-PDDL baseline: compile a single-agent task into an N-agent one, on s-expressions.

As in the paper, an ``agent`` type is added, every action gets an agent parameter, every
agent-specific predicate gets an agent argument, and the agent-specific facts of the
initial state are duplicated for each agent. The compilation works on the task's own
s-expressions, so whatever the planner reads in the original it reads in the compiled
task: the agent argument goes everywhere an agent-specific predicate occurs, inside
quantifiers, disjunctions and conditional effects included. A derived predicate whose
rules use an agent-specific predicate is agent-specific too (it gets the agent argument
as well). Agent-specific goal literals must hold for every agent (as in
:mod:`twostep.makespan`); inside a goal formula an agent-specific atom reads "for every
agent" where it is asserted and "for some agent" where it is denied, so that its negation
too holds for every agent. Numeric initial values (costs) are kept as they are. A
sequential plan of the compiled task is split per agent and written back in the
single-agent task's own terms.

Domains that already model the agent (AlfWorld: an ``agent`` type, and every action takes
the acting agent as a parameter) are not given a second agent parameter: their one agent
object is replaced by N agent objects, every fact that names it is duplicated for each of
them, and a compiled plan is written back by naming the task's own agent object again.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import replace

from twostep.pddl import Domain, Fact, Goal, Problem
from twostep.pddl.lifted import condition_atoms
from twostep.pddl.model import Atom, DerivedPredicate
from twostep.pddl.sexp import SExp
from twostep.plans.simulate import parse_action

AGENT_TYPE = "agent"
AGENT_VARIABLE = "?agent"
_FORMULA_HEADS = frozenset({"and", "or", "not", "imply", "when"})
_QUANTIFIERS = frozenset({"forall", "exists"})
_NUMERIC = frozenset({"increase", "decrease", "assign", "scale-up", "scale-down", "<", ">",
                      "<=", ">="})  # fmt: skip


class AgentNames(list[str]):
    """The agent objects of a compiled task, agent 0 first.

    ``stands_for`` is the single-agent task's own agent object when the domain already
    models agents (the compiled plan names one of these objects where the task names it);
    None when the compilation added the agent parameter.
    """

    def __init__(self, names: Sequence[str], stands_for: str | None = None):
        super().__init__(names)
        self.stands_for = stands_for


def _agent_typed(domain: Domain) -> bool:
    """Whether ``domain`` already models agents: an ``agent`` type every action takes."""
    if AGENT_TYPE not in domain.types or not domain.actions:
        return False
    agent_types = {t for t in domain.types if domain.is_subtype(t, AGENT_TYPE)}
    return all(any(t in agent_types for _, t in a.parameters) for a in domain.actions.values())


def agent_names(agents: int, taken: Collection[str] = ()) -> list[str]:
    """``agent0 .. agent{N-1}``, prefixed if the task already uses those names."""
    prefix = "agent"
    while any(f"{prefix}{i}" in taken for i in range(agents)):
        prefix = "ma-" + prefix
    return [f"{prefix}{i}" for i in range(agents)]


def agent_specific_predicates(domain: Domain, agent_predicates: Collection[str]) -> set[str]:
    """The agent predicates and the derived predicates whose rules use one (transitively)."""
    specific = set(agent_predicates)
    changed = True
    while changed:
        changed = False
        for rule in domain.derived:
            if rule.name in specific:
                continue
            if any(str(atom[0]) in specific for _, atom in condition_atoms(rule.formula)):
                specific.add(rule.name)
                changed = True
    return specific


def _lift(expr: SExp, specific: Collection[str], variable: str) -> SExp:
    """``expr`` with ``variable`` as first argument of every atom of a predicate in
    ``specific`` (formulas and effects alike; quantified variable lists untouched)."""
    if not isinstance(expr, list) or not expr:
        return expr
    head = expr[0]
    if head in _FORMULA_HEADS:
        return [head, *(_lift(part, specific, variable) for part in expr[1:])]
    if head in _QUANTIFIERS and len(expr) == 3:
        return [head, expr[1], _lift(expr[2], specific, variable)]
    if head in _NUMERIC or head == "=":
        return expr
    if isinstance(head, str) and head in specific:
        return [head, variable, *expr[1:]]
    return expr


def _fresh_variable(expr: SExp) -> str:
    used: set[str] = set()

    def collect(node: SExp) -> None:
        if isinstance(node, str):
            used.add(node)
        else:
            for part in node:
                collect(part)

    collect(expr)
    name, k = AGENT_VARIABLE, 1
    while name in used:
        k += 1
        name = f"{AGENT_VARIABLE}{k}"
    return name


def _compile_body(domain: Domain, specific: set[str]) -> list[SExp]:
    """The N-agent domain's ``define`` (independent of N: agents are objects)."""
    body: list[SExp] = []
    has_types = False
    for item in domain.body:
        if not isinstance(item, list) or not item:
            body.append(item)
            continue
        key = item[0]
        if key == "domain":
            body.append(["domain", f"{domain.name}-ma"])
        elif key == ":requirements":
            body.append([*item, *([] if ":typing" in item else [":typing"])])
        elif key == ":types":
            has_types = True
            body.append([*item, AGENT_TYPE])
        elif key == ":predicates":
            entries: list[SExp] = [":predicates"]
            for entry in item[1:]:
                if isinstance(entry, list) and entry and entry[0] in specific:
                    variable = _fresh_variable(entry)
                    entries.append([entry[0], variable, "-", AGENT_TYPE, *entry[1:]])
                else:
                    entries.append(entry)
            body.append(entries)
        elif key == ":action":
            body.append(_compile_action(item, specific))
        elif key == ":derived" and len(item) == 3 and isinstance(item[1], list):
            head = item[1]
            if head and head[0] in specific:
                variable = _fresh_variable(item)
                body.append([":derived", [head[0], variable, "-", AGENT_TYPE, *head[1:]],
                             _lift(item[2], specific, variable)])  # fmt: skip
            else:
                body.append(item)
        else:
            body.append(item)
    if not has_types:
        index = next(
            (i for i, it in enumerate(body) if isinstance(it, list) and it[:1] == [":predicates"]),
            len(body),
        )
        body.insert(index, [":types", AGENT_TYPE])
        if not any(isinstance(it, list) and it[:1] == [":requirements"] for it in body):
            body.insert(2, [":requirements", ":typing"])
    return body


def _compile_action(item: list[SExp], specific: set[str]) -> list[SExp]:
    variable = _fresh_variable(item)
    out: list[SExp] = [item[0], item[1]]
    rest = item[2:]
    keys = [str(k) for k in rest[::2]]
    values = dict(zip(keys, rest[1::2], strict=False))
    parameters = values.get(":parameters", [])
    out += [
        ":parameters",
        [variable, "-", AGENT_TYPE, *(parameters if isinstance(parameters, list) else [])],
    ]
    for key in keys:
        if key != ":parameters":
            out += [key, _lift(values[key], specific, variable)]
    return out


def _goal_formula(expr: SExp, specific: set[str], positive: bool = True) -> SExp:
    """A goal formula whose agent-specific atoms hold for every agent (see the module doc)."""
    if not isinstance(expr, list) or not expr:
        return expr
    head = expr[0]
    if head == "not" and len(expr) == 2:
        return ["not", _goal_formula(expr[1], specific, not positive)]
    if head == "imply" and len(expr) == 3:
        return ["imply", _goal_formula(expr[1], specific, not positive),
                _goal_formula(expr[2], specific, positive)]  # fmt: skip
    if head in ("and", "or"):
        return [head, *(_goal_formula(part, specific, positive) for part in expr[1:])]
    if head in _QUANTIFIERS and len(expr) == 3:
        return [head, expr[1], _goal_formula(expr[2], specific, positive)]
    if isinstance(head, str) and head in specific:
        variable = _fresh_variable(expr)
        return ["forall" if positive else "exists", [variable, "-", AGENT_TYPE],
                [head, variable, *expr[1:]]]  # fmt: skip
    return expr


def _per_agent(facts: frozenset[Fact], agents: list[str], specific: Collection[str]) -> set[Fact]:
    out: set[Fact] = set()
    for fact in facts:
        if fact[0] in specific:
            out.update((fact[0], agent, *fact[1:]) for agent in agents)
        else:
            out.add(fact)
    return out


def _basic(problem: Problem) -> frozenset[Fact]:
    return frozenset(f for f in problem.init if not problem.domain.is_derived(f))


def _grounded_if_needed(problem: Problem) -> Problem:
    if problem.needs_axioms:
        from twostep.pddl.reader import with_grounding

        return with_grounding(problem)
    return problem


def _mentions(expr: SExp, name: str) -> bool:
    if isinstance(expr, str):
        return expr == name
    return any(_mentions(part, name) for part in expr)


def _replicate_agent(problem: Problem, agents: int) -> tuple[Problem, AgentNames]:
    """The N-agent task of a domain that already models agents (see the module docstring)."""
    domain = problem.domain
    own = sorted(o for o, t in problem.objects.items() if domain.is_subtype(t, AGENT_TYPE))
    if len(own) != 1:
        raise ValueError(
            f"task {problem.name} has {len(own)} agent objects ({', '.join(own) or 'none'}); "
            "the multi-agent compilation of an agent-typed domain needs exactly one"
        )
    (single,) = own
    names = agent_names(agents, problem.all_objects)

    def per_agent(facts: frozenset[Fact]) -> frozenset[Fact]:
        out: set[Fact] = set()
        for fact in facts:
            if single in fact[1:]:
                out.update(tuple(name if t == single else t for t in fact) for name in names)
            else:
                out.add(fact)
        return frozenset(out)

    def rename(expr: SExp, name: str) -> SExp:
        if isinstance(expr, str):
            return name if expr == single else expr
        return [rename(part, name) for part in expr]

    goal = problem.goal
    formula = goal.formula
    if formula is not None:
        formula = ["and", *(rename(formula, name) for name in names)]
    objects = {n: t for n, t in problem.objects.items() if n != single}
    objects.update({name: problem.objects[single] for name in names})
    compiled = Problem(
        f"{problem.name}-{agents}agents",
        domain,
        objects,
        per_agent(_basic(problem)),
        Goal(per_agent(goal.positive), per_agent(goal.negative), formula),
        None,
        numeric_init=tuple(
            rename(entry, name) if _mentions(entry, single) else entry
            for entry in problem.numeric_init
            for name in (names if _mentions(entry, single) else names[:1])
        ),
        body=problem.body,
    )
    return _grounded_if_needed(compiled), AgentNames(names, stands_for=single)


def compile_multi_agent_domain(domain: Domain, agent_predicates: Collection[str]) -> Domain:
    """The N-agent version of ``domain`` (independent of N: agents are objects)."""
    unknown = set(agent_predicates) - set(domain.predicates)
    if unknown:
        raise ValueError(
            f"agent predicates not in domain {domain.name}: {', '.join(sorted(unknown))}"
        )
    if AGENT_TYPE in domain.types:
        raise ValueError(f"domain {domain.name} already has a type named '{AGENT_TYPE}'")
    specific = agent_specific_predicates(domain, agent_predicates)
    types = dict(domain.types)
    types.setdefault("object", None)
    types[AGENT_TYPE] = "object"
    predicates = {
        name: ((AGENT_TYPE, *params) if name in specific else params)
        for name, params in domain.predicates.items()
    }
    actions = {}
    for name, action in domain.actions.items():

        def lift(atoms: tuple[Atom, ...]) -> tuple[Atom, ...]:
            return tuple(
                Atom(a.predicate, (AGENT_VARIABLE, *a.terms)) if a.predicate in specific else a
                for a in atoms
            )

        actions[name] = replace(
            action,
            parameters=((AGENT_VARIABLE, AGENT_TYPE), *action.parameters),
            pre_positive=lift(action.pre_positive),
            pre_negative=lift(action.pre_negative),
            add=lift(action.add),
            delete=lift(action.delete),
            precondition=_lift(action.precondition, specific, AGENT_VARIABLE),
            effect=_lift(action.effect, specific, AGENT_VARIABLE),
        )
    derived = tuple(
        DerivedPredicate(d.name, ((AGENT_VARIABLE, AGENT_TYPE), *d.parameters),
                         _lift(d.formula, specific, AGENT_VARIABLE))
        if d.name in specific else d
        for d in domain.derived
    )  # fmt: skip
    requirements = tuple(sorted(set(domain.requirements) | {":typing"}))
    return Domain(
        f"{domain.name}-ma",
        requirements,
        types,
        dict(domain.constants),
        predicates,
        actions,
        None,
        dict(domain.functions),
        derived,
        _compile_body(domain, specific) if domain.body else [],
    )


def compile_multi_agent_problem(
    problem: Problem, agents: int, agent_predicates: Collection[str]
) -> tuple[Problem, list[str]]:
    """The N-agent task and the names of its agents (agent0 first)."""
    unknown = set(agent_predicates) - set(problem.domain.predicates)
    if _agent_typed(problem.domain) and not unknown:
        return _replicate_agent(problem, agents)
    domain = compile_multi_agent_domain(problem.domain, agent_predicates)
    specific = agent_specific_predicates(problem.domain, agent_predicates)
    names = agent_names(agents, problem.all_objects)
    objects = {n: (t if problem.domain.typed else "object") for n, t in problem.objects.items()}
    objects.update({name: AGENT_TYPE for name in names})
    goal = problem.goal
    compiled = Problem(
        f"{problem.name}-{agents}agents",
        domain,
        objects,
        frozenset(_per_agent(_basic(problem), names, specific)),
        Goal(
            frozenset(_per_agent(goal.positive, names, specific)),
            frozenset(_per_agent(goal.negative, names, specific)),
            None if goal.formula is None else _goal_formula(goal.formula, specific),
        ),
        None,
        numeric_init=problem.numeric_init,
        body=problem.body,
    )
    return _grounded_if_needed(compiled), names


def split_plan(plan: Sequence[str], agent_names: Sequence[str]) -> list[list[str]]:
    """Split a compiled sequential plan into per-agent plans in single-agent terms.

    With :class:`AgentNames` that stand for the task's own agent object, the agent is the
    first argument that names an agent, and it is renamed back to that object; otherwise
    the agent is the first argument, and it is dropped.
    """
    index = {name: i for i, name in enumerate(agent_names)}
    plans: list[list[str]] = [[] for _ in agent_names]
    stands_for = getattr(agent_names, "stands_for", None)
    for step in plan:
        name, args = parse_action(step)
        if stands_for is not None:
            acting = next((a for a in args if a in index), None)
            if acting is None:
                raise ValueError(f"multi-agent plan step {step} names no agent")
            renamed = (stands_for if a in index else a for a in args)
            plans[index[acting]].append("(" + " ".join((name, *renamed)) + ")")
            continue
        if not args or args[0] not in index:
            raise ValueError(f"multi-agent plan step {step} does not start with an agent")
        plans[index[args[0]]].append("(" + " ".join((name, *args[1:])) + ")")
    return plans
