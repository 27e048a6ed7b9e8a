"""The MA-PDDL baseline: compile a single-agent task into an N-agent one.

As in the paper, an ``agent`` type is added, every action gets an agent parameter, every
agent-specific predicate gets an agent argument, and the agent-specific facts of the
initial state are duplicated for each agent. Agent-specific goal literals must hold for
every agent (as in :mod:`twostep.execution`). A sequential plan of the compiled task is
split per agent and written back in the single-agent task's own terms.

Domains that already model the agent (AlfWorld: an ``agent`` type, and every action takes
the acting agent as a parameter) are not given a second agent parameter: their one agent
object is replaced by N agent objects, every fact that names it is duplicated for each of
them, and a compiled plan is written back by naming the task's own agent object again.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

from twostep.pddl import ActionSchema, Atom, Domain, Fact, Goal, Problem
from twostep.strips import parse_action

AGENT_TYPE = "agent"
AGENT_VARIABLE = "?agent"


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


def _lift(atoms: Sequence[Atom], agent_predicates: Collection[str]) -> tuple[Atom, ...]:
    return tuple(
        Atom(a.predicate, (AGENT_VARIABLE, *a.terms)) if a.predicate in agent_predicates else a
        for a in atoms
    )


def compile_multi_agent_domain(domain: Domain, agent_predicates: Collection[str]) -> Domain:
    """The N-agent version of ``domain`` (independent of N: agents are objects)."""
    unknown = set(agent_predicates) - set(domain.predicates)
    if unknown:
        raise ValueError(
            f"agent predicates not in domain {domain.name}: {', '.join(sorted(unknown))}"
        )
    if AGENT_TYPE in domain.types:
        raise ValueError(f"domain {domain.name} already has a type named '{AGENT_TYPE}'")
    types = dict(domain.types)
    types.setdefault("object", None)
    types[AGENT_TYPE] = "object"
    predicates = {
        name: ((AGENT_TYPE, *params) if name in agent_predicates else params)
        for name, params in domain.predicates.items()
    }
    actions = {
        name: ActionSchema(
            name,
            ((AGENT_VARIABLE, AGENT_TYPE), *a.parameters),
            _lift(a.pre_positive, agent_predicates),
            _lift(a.pre_negative, agent_predicates),
            _lift(a.add, agent_predicates),
            _lift(a.delete, agent_predicates),
            a.equal,
            a.not_equal,
            a.cost,
        )
        for name, a in domain.actions.items()
    }
    requirements = tuple(sorted(set(domain.requirements) | {":typing"}))
    return Domain(
        f"{domain.name}-ma",
        requirements,
        types,
        dict(domain.constants),
        predicates,
        actions,
        None,
        dict(domain.origins),
    )


def _per_agent(
    facts: frozenset[Fact], agents: list[str], agent_predicates: Collection[str]
) -> set[Fact]:
    out: set[Fact] = set()
    for fact in facts:
        if fact[0] in agent_predicates:
            out.update((fact[0], agent, *fact[1:]) for agent in agents)
        else:
            out.add(fact)
    return out


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

    objects = {n: t for n, t in problem.objects.items() if n != single}
    objects.update({name: problem.objects[single] for name in names})
    compiled = Problem(
        f"{problem.name}-{agents}agents",
        domain,
        objects,
        per_agent(problem.init),
        Goal(per_agent(problem.goal.positive), per_agent(problem.goal.negative)),
        None,
    )
    return compiled, AgentNames(names, stands_for=single)


def compile_multi_agent_problem(
    problem: Problem, agents: int, agent_predicates: Collection[str]
) -> tuple[Problem, list[str]]:
    """The N-agent task and the names of its agents (agent0 first)."""
    unknown = set(agent_predicates) - set(problem.domain.predicates)
    if _agent_typed(problem.domain) and not unknown:
        return _replicate_agent(problem, agents)
    domain = compile_multi_agent_domain(problem.domain, agent_predicates)
    names = agent_names(agents, problem.all_objects)
    objects = {n: (t if problem.domain.typed else "object") for n, t in problem.objects.items()}
    objects.update({name: AGENT_TYPE for name in names})
    goal = Goal(
        frozenset(_per_agent(problem.goal.positive, names, agent_predicates)),
        frozenset(_per_agent(problem.goal.negative, names, agent_predicates)),
    )
    compiled = Problem(
        f"{problem.name}-{agents}agents",
        domain,
        objects,
        frozenset(_per_agent(problem.init, names, agent_predicates)),
        goal,
        None,
    )
    return compiled, names


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
