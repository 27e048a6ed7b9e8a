"""Walking in plan-deal: which actions are walks, and an agent's shortest walk to where an
action applies.

An action *walks* when it has no environment effect and its agent effects only say where
the agent stands (positional predicates: some action both adds and deletes them). The SA
plan's walks are not dealt: before each action it replays, an agent walks by
breadth-first search over the domain's walking actions, grounded here by joining their
preconditions against the state (a grounder of its own, since walks go where the SA plan
never went).
"""

from __future__ import annotations

from collections import defaultdict, deque
from collections.abc import Collection, Iterator, Mapping
from typing import TypeAlias

from twostep.dealing.model import DealError
from twostep.decomposers.goal_split import positional_predicates
from twostep.pddl import Fact, Problem
from twostep.pddl.model import ActionSchema, Atom
from twostep.progression import agent_part, environment_part
from twostep.strips import GroundAction, Grounder, PlanError

WALK_LIMIT = 20_000
"""States the walking search may visit for one action before the deal gives up."""

Binding: TypeAlias = dict[str, str]


def is_walking(
    action: GroundAction, agent_predicates: Collection[str], positional: Collection[str]
) -> bool:
    """No environment effect, and the agent effects only say where the agent stands."""
    effects = action.add | action.delete
    return all(f[0] in agent_predicates and f[0] in positional for f in effects)


class Walker:
    """Shortest walks of one agent: breadth-first over the domain's walking actions.

    ``universe`` holds every environment fact a walk may meet (the facts of the SA plan's
    states: a replay only runs that plan's actions, and walks change no environment
    fact). The walking actions that could apply where an agent stands are found once per
    place, by joining their preconditions against it, and filtered by the current state.
    """

    def __init__(
        self, problem: Problem, agent_predicates: Collection[str], universe: frozenset[Fact]
    ):
        self.problem = problem
        self.grounder = Grounder(problem)
        self.agent_predicates = frozenset(agent_predicates)
        positional = positional_predicates(problem.domain)
        self.schemas = [
            s
            for s in problem.domain.actions.values()
            if (s.add or s.delete)
            and all(a.predicate in self.agent_predicates and a.predicate in positional
                    for a in (*s.add, *s.delete))
        ]  # fmt: skip
        self.objects = problem.all_objects
        self.universe = environment_part(universe, agent_predicates)
        self._candidates: dict[frozenset[Fact], list[GroundAction]] = {}

    def candidates(self, own: frozenset[Fact]) -> list[GroundAction]:
        """Walking actions whose preconditions hold in the universe plus ``own``."""
        found = self._candidates.get(own)
        if found is None:
            state = self.universe | own
            by_predicate: dict[str, list[Fact]] = defaultdict(list)
            for fact in state:
                by_predicate[fact[0]].append(fact)
            found = []
            for schema in self.schemas:
                for binding in _bindings(schema, by_predicate, self.objects, self.problem):
                    names = (binding[v] for v, _ in schema.parameters)
                    try:
                        action = self.grounder.ground("(" + " ".join((schema.name, *names)) + ")")
                    except PlanError:
                        continue
                    if action.applicable(state):
                        found.append(action)
            found.sort(key=str)  # set order varies per process: walks must not
            self._candidates[own] = found
        return found

    def successors(
        self, environment: frozenset[Fact], own: frozenset[Fact]
    ) -> Iterator[GroundAction]:
        state = environment | own
        return (a for a in self.candidates(own) if a.applicable(state))

    def walk_to(
        self, environment: frozenset[Fact], own: frozenset[Fact], target: GroundAction
    ) -> list[GroundAction]:
        """The shortest walk after which ``target`` applies (raise :class:`DealError`)."""
        start = own
        parents: dict[frozenset[Fact], tuple[frozenset[Fact], GroundAction] | None] = {start: None}
        queue = deque([start])
        while queue:
            node = queue.popleft()
            if target.applicable(environment | node):
                path: list[GroundAction] = []
                while (entry := parents[node]) is not None:
                    node, step = entry
                    path.append(step)
                return path[::-1]
            if len(parents) > WALK_LIMIT:
                break
            for action in self.successors(environment, node):
                child = agent_part(action.apply(environment | node), self.agent_predicates)
                if child not in parents:
                    parents[child] = (node, action)
                    queue.append(child)
        raise DealError(f"no walk to where {target} applies")


def _bindings(
    schema: ActionSchema,
    by_predicate: Mapping[str, list[Fact]],
    objects: Mapping[str, str],
    problem: Problem,
) -> Iterator[Binding]:
    """Variable bindings under which every positive precondition is in the state (a join)."""
    atoms = sorted(schema.pre_positive, key=lambda a: len(by_predicate.get(a.predicate, ())))

    def extend(k: int, binding: Binding) -> Iterator[Binding]:
        if k == len(atoms):
            yield from _free_variables(schema, binding, objects, problem)
            return
        atom: Atom = atoms[k]
        for fact in by_predicate.get(atom.predicate, ()):
            if len(fact) != len(atom.terms) + 1:
                continue
            new = dict(binding)
            if all(
                _unify(term, value, new) for term, value in zip(atom.terms, fact[1:], strict=True)
            ):
                yield from extend(k + 1, new)

    yield from extend(0, {})


def _unify(term: str, value: str, binding: Binding) -> bool:
    if not term.startswith("?"):
        return term == value
    if term in binding:
        return binding[term] == value
    binding[term] = value
    return True


def _free_variables(
    schema: ActionSchema, binding: Binding, objects: Mapping[str, str], problem: Problem
) -> Iterator[Binding]:
    """Bind parameters no precondition mentions to every object of their type (rare)."""
    free = [(v, t) for v, t in schema.parameters if v not in binding]
    if not free:
        yield binding
        return
    variable, kind = free[0]
    for name, its_type in objects.items():
        if problem.domain.is_subtype(its_type, kind):
            yield from _free_variables(schema, {**binding, variable: name}, objects, problem)
