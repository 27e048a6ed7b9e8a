"""Walking in plan-deal: which actions are walks, and an agent's shortest walk to where an
action applies.

An action *walks* when it has no environment effect and its agent effects only say where
the agent stands (positional predicates: some action both adds and deletes them); its
possible effects count, conditional ones included. The SA plan's walks are not dealt:
before each action it replays, an agent walks by breadth-first search over the task's
walking actions, taken from its grounding (Fast Downward grounds every action reachable
from the initial state, so walks may go where the SA plan never went).
"""

from __future__ import annotations

from collections import defaultdict, deque
from collections.abc import Collection, Iterator

from twostep.dealing.model import DealError
from twostep.decomposers.goal_split import positional_predicates
from twostep.pddl import Fact, Problem
from twostep.progression import agent_part, environment_part
from twostep.strips import GroundAction

WALK_LIMIT = 20_000
"""States the walking search may visit for one action before the deal gives up."""


def is_walking(
    action: GroundAction, agent_predicates: Collection[str], positional: Collection[str]
) -> bool:
    """No environment effect, and the agent effects only say where the agent stands."""
    effects = action.possible_add | action.possible_delete
    return bool(effects) and all(f[0] in agent_predicates and f[0] in positional for f in effects)


class Walker:
    """Shortest walks of one agent: breadth-first over the task's walking actions.

    ``universe`` holds every environment fact a walk may meet (the facts of the SA plan's
    states: a replay only runs that plan's actions, and walks change no environment
    fact). The walking actions that could apply where an agent stands are found once per
    place (indexed by the agent facts they need) and filtered by the current state.
    """

    def __init__(
        self, problem: Problem, agent_predicates: Collection[str], universe: frozenset[Fact]
    ):
        self.problem = problem
        self.agent_predicates = frozenset(agent_predicates)
        positional = positional_predicates(problem.domain)
        walking = sorted(
            (
                a
                for a in problem.grounded.actions.values()
                if (a.possible_add or a.possible_delete)
                and is_walking(a, self.agent_predicates, positional)
            ),
            key=str,  # set order varies per process: walks must not
        )
        # index: an agent fact a walking action needs -> the action (actions that need
        # none are always candidates)
        self._needing: dict[Fact, list[GroundAction]] = defaultdict(list)
        self._anywhere: list[GroundAction] = []
        for action in walking:
            needs = sorted(f for f in action.pre_positive if f[0] in self.agent_predicates)
            (self._needing[needs[0]] if needs else self._anywhere).append(action)
        self.universe = environment_part(universe, agent_predicates)
        self._candidates: dict[frozenset[Fact], list[GroundAction]] = {}

    def candidates(self, own: frozenset[Fact]) -> list[GroundAction]:
        """Walking actions whose preconditions hold in the universe plus ``own``."""
        found = self._candidates.get(own)
        if found is None:
            state = self.problem.close(self.universe | own)
            pool = [*self._anywhere, *(a for f in own for a in self._needing.get(f, ()))]
            found = sorted((a for a in pool if a.applicable(state)), key=str)
            self._candidates[own] = found
        return found

    def successors(
        self, environment: frozenset[Fact], own: frozenset[Fact]
    ) -> Iterator[GroundAction]:
        state = self.problem.close(environment | own)
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
            if target.applicable(self.problem.close(environment | node)):
                path: list[GroundAction] = []
                while (entry := parents[node]) is not None:
                    node, step = entry
                    path.append(step)
                return path[::-1]
            if len(parents) > WALK_LIMIT:
                break
            for action in self.successors(environment, node):
                view = self.problem.close(environment | node)
                child = agent_part(action.apply(view), self.agent_predicates)
                if child not in parents:
                    parents[child] = (node, action)
                    queue.append(child)
        raise DealError(f"no walk to where {target} applies")
