"""Walking in plan-deal: which actions are walks, and an agent's shortest walk to where an
action applies.

An action *walks* when its agent effects only say where the agent stands (positional
predicates: some action both adds and deletes them) and its environment effects, if any,
only touch positional facts too (a hoist that leaves an area makes it ``clear``). The SA
plan's walks are not dealt: before each action it replays, an agent walks by
breadth-first search over the domain's moves, grounded here by joining their
preconditions against the state (a grounder of its own, since walks go where the SA plan
never went). A move is a walking action, or one whose other environment effects can harm
nobody: facts it adds that no action deletes or needs false (a cell ``visited``).
"""

from __future__ import annotations

import time
from collections import defaultdict, deque
from collections.abc import Collection, Iterator, Mapping
from typing import TypeAlias

from twostep.dealing.encoding import FactSpace, Step
from twostep.dealing.model import DealError
from twostep.decomposers.goal_split import positional_predicates
from twostep.pddl import Domain, Fact, Problem
from twostep.pddl.model import ActionSchema, Atom
from twostep.strips import Grounder, PlanError

WALK_LIMIT = 20_000
"""States the walking search may visit for one action before the deal gives up."""

Binding: TypeAlias = dict[str, str]


def is_walking(step: Step, space: FactSpace) -> bool:
    """Agent effects only where the agent stands, environment effects only positional."""
    own = step.add_own | step.del_own
    return bool(own) and not own & ~space.where and not step.writes_env & ~space.where_env


def harmless_predicates(domain: Domain, agent_predicates: Collection[str]) -> set[str]:
    """Environment predicates that actions only add: no action deletes them or needs them
    false, so having more of them never stops an action."""
    actions = domain.actions.values()
    added = {a.predicate for s in actions for a in s.add}
    deleted = {a.predicate for s in actions for a in s.delete}
    forbidden = {a.predicate for s in actions for a in s.pre_negative}
    return added - deleted - forbidden - set(agent_predicates)


def move_schemas(problem: Problem, agent_predicates: frozenset[str]) -> list[ActionSchema]:
    """The domain's moves (module docstring)."""
    domain = problem.domain
    positional = positional_predicates(domain)
    harmless = harmless_predicates(domain, agent_predicates)

    def moves(schema: ActionSchema) -> bool:
        own = [
            a.predicate for a in (*schema.add, *schema.delete) if a.predicate in agent_predicates
        ]
        env = [a for a in (*schema.add, *schema.delete) if a.predicate not in agent_predicates]
        return (
            bool(own)
            and all(p in positional for p in own)
            and all(
                a.predicate in positional or (a in schema.add and a.predicate in harmless)
                for a in env
            )
        )

    return [s for s in domain.actions.values() if moves(s)]


def slot(fact: Fact) -> Fact:
    """What an agent fact is about, leaving out where: ``(robot-at robot1 t3)`` is about
    ``robot-at robot1``, termes' ``(at p3)`` about ``at``."""
    return fact[:-1] if len(fact) > 1 else fact


class Walker:
    """Shortest walks of one agent: breadth-first over the domain's moves.

    ``universe`` holds every environment fact a walk may meet (the facts of the SA plan's
    states). The moves that could apply where an agent stands are found by joining their
    preconditions against it, once per agent fact they read (per :func:`slot`: a floortile
    agent's two robots are grounded apart, not once per pair of cells); which of them apply
    is cached per own state and the environment facts they read. A walk moves only what
    the target action needs of the agent (robot1 walks for robot1's painting).
    """

    def __init__(self, problem: Problem, space: FactSpace, universe: frozenset[Fact]):
        self.problem = problem
        self.space = space
        self.grounder = Grounder(problem)
        self.schemas = move_schemas(problem, space.agent_predicates)
        self.objects = problem.all_objects
        self.universe = frozenset(f for f in universe if f[0] not in space.agent_predicates)
        self._by_predicate: dict[str, list[Fact]] = defaultdict(list)
        for fact in sorted(self.universe):
            self._by_predicate[fact[0]].append(fact)
        self._candidates: dict[int, tuple[list[Step], int]] = {}
        self._grounded: dict[frozenset[Fact], dict[str, Step]] = {}
        # the agent facts the moves read: moves are grounded once per such facts
        self.reads_own = {a.predicate for s in self.schemas
                          for a in (*s.pre_positive, *s.pre_negative)} & space.agent_predicates  # fmt: skip
        self._successors: dict[tuple[int, int], list[Step]] = {}
        self._moved: dict[Step, frozenset[Fact]] = {}  # per move: the slots it changes
        self.search_s = 0.0
        """Seconds spent in :meth:`walk_to` so far."""

    def candidates(self, own: int) -> tuple[list[Step], int]:
        """The moves whose preconditions hold in the universe plus ``own``, and the
        environment bits they read."""
        found = self._candidates.get(own)
        if found is None:
            by_slot: dict[Fact, set[Fact]] = defaultdict(set)
            for fact in self.space.own_facts(own):
                if fact[0] in self.reads_own:
                    by_slot[slot(fact)].add(fact)
            moves: dict[str, Step] = {}
            for facts in map(frozenset, by_slot.values()):
                if facts not in self._grounded:
                    self._grounded[facts] = self._ground(facts)
                moves.update(self._grounded[facts])
            steps = [moves[t] for t in sorted(moves)]  # set order varies: walks must not
            reads = 0
            for step in steps:
                reads |= step.pre_env | step.neg_env
            found = self._candidates[own] = (steps, reads)
        return found

    def _ground(self, mine: frozenset[Fact]) -> dict[str, Step]:
        """The moves whose preconditions hold in the universe plus ``mine``, by name."""
        state = self.universe | mine
        by_predicate = dict(self._by_predicate)
        for fact in sorted(mine):
            by_predicate[fact[0]] = [*by_predicate.get(fact[0], ()), fact]
        by_first: dict[tuple[str, str], list[Fact]] = defaultdict(list)
        for facts in by_predicate.values():
            for fact in facts:
                if len(fact) > 1:
                    by_first[(fact[0], fact[1])].append(fact)
        moves: dict[str, Step] = {}
        for schema in self.schemas:
            for binding in _bindings(schema, by_predicate, by_first, self.objects, self.problem):
                names = (binding[v] for v, _ in schema.parameters)
                text = "(" + " ".join((schema.name, *names)) + ")"
                try:
                    action = self.grounder.ground(text)
                except PlanError:
                    continue
                if action.applicable(state):
                    moves[text] = self.space.step(action)
        return moves

    def moved(self, move: Step) -> frozenset[Fact]:
        """The slots of the agent facts ``move`` changes."""
        found = self._moved.get(move)
        if found is None:
            changed = move.action.add | move.action.delete
            found = self._moved[move] = frozenset(
                slot(f) for f in changed if f[0] in self.space.agent_predicates
            )
        return found

    def successors(self, env: int, own: int) -> list[Step]:
        """The moves that apply in ``env`` for an agent with ``own``."""
        steps, reads = self.candidates(own)
        key = (own, env & reads)
        found = self._successors.get(key)
        if found is None:
            found = self._successors[key] = [s for s in steps if s.applicable(env, own)]
        return found

    def walk_to(self, env: int, own: int, target: Step) -> list[Step]:
        """The shortest walk after which ``target`` applies (raise :class:`DealError`)."""
        began = time.perf_counter()
        agent = self.space.agent_predicates
        needed = {slot(f) for f in target.action.pre_positive if f[0] in agent}
        try:
            return self._search(env, own, target, needed)
        except DealError:
            if all(needed >= self.moved(s) for s in self.candidates(own)[0]):
                raise  # every move was tried already
            return self._search(env, own, target, None)
        finally:
            self.search_s += time.perf_counter() - began

    def _search(self, env: int, own: int, target: Step, needed: set[Fact] | None) -> list[Step]:
        """Breadth-first search over the moves that change ``needed`` slots (None: all)."""
        # states that differ in harmless facts alone count as one (a walk that visits
        # cells would otherwise make every path a state of its own)
        relevant = ~self.space.harmless_env
        start = (env, own)
        parents: dict[tuple[int, int], tuple[tuple[int, int], Step] | None] = {
            (env & relevant, own): None
        }
        queue = deque([start])
        while queue:
            node = queue.popleft()
            if target.applicable(*node):
                path: list[Step] = []
                key = (node[0] & relevant, node[1])
                while (entry := parents[key]) is not None:
                    key, step = entry
                    path.append(step)
                return path[::-1]
            if len(parents) > WALK_LIMIT:
                break
            for step in self.successors(*node):
                if needed is not None and not self.moved(step) & needed:
                    continue
                child = step.apply(*node)
                key = (child[0] & relevant, child[1])
                if key not in parents:
                    parents[key] = ((node[0] & relevant, node[1]), step)
                    queue.append(child)
        raise DealError(f"no walk to where {target} applies")


def _bindings(
    schema: ActionSchema,
    by_predicate: Mapping[str, list[Fact]],
    by_first: Mapping[tuple[str, str], list[Fact]],
    objects: Mapping[str, str],
    problem: Problem,
) -> Iterator[Binding]:
    """Variable bindings under which every positive precondition is in the state (a join:
    next the atom with the most terms bound, its facts looked up by their first term)."""

    def bound(term: str, binding: Binding) -> str | None:
        return binding.get(term) if term.startswith("?") else term

    def cost(atom: Atom, binding: Binding) -> tuple[int, int]:
        known = sum(bound(t, binding) is not None for t in atom.terms)
        return (-known, len(by_predicate.get(atom.predicate, ())))

    def extend(atoms: list[Atom], binding: Binding) -> Iterator[Binding]:
        if not atoms:
            yield from _free_variables(schema, binding, objects, problem)
            return
        atom = min(atoms, key=lambda a: cost(a, binding))
        rest = [a for a in atoms if a is not atom]
        first = bound(atom.terms[0], binding) if atom.terms else None
        facts = (
            by_first.get((atom.predicate, first), ())
            if first is not None
            else (by_predicate.get(atom.predicate, ()))
        )
        for fact in facts:
            if len(fact) != len(atom.terms) + 1:
                continue
            new = dict(binding)
            if all(
                _unify(term, value, new) for term, value in zip(atom.terms, fact[1:], strict=True)
            ):
                yield from extend(rest, new)

    yield from extend(sorted(schema.pre_positive, key=str), {})


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
    """Bind parameters no precondition mentions to every object of their type (rare); a
    binding with an object of another type is no action of the domain (storage's
    ``go-out`` from the transit area would match ``go-in``'s preconditions)."""
    free = [(v, t) for v, t in schema.parameters if v not in binding]
    if not free:
        if all(problem.domain.is_subtype(objects[binding[v]], t) for v, t in schema.parameters):
            yield binding
        return
    variable, kind = free[0]
    for name, its_type in objects.items():
        if problem.domain.is_subtype(its_type, kind):
            yield from _free_variables(schema, {**binding, variable: name}, objects, problem)
