"""Walking in plan-deal: which actions are walks, and an agent's shortest walk to where an
action applies.

An action *walks* when its agent effects only say where the agent stands (positional
predicates: some action both adds and deletes them) and its environment effects, if any,
only touch positional facts too (a hoist that leaves an area makes it ``clear``). The SA
plan's walks are not dealt: before each action it replays, an agent walks by
breadth-first search over the task's moves, taken from its grounding (Fast Downward
grounds every action reachable from the initial state, so walks may go where the SA plan
never went). A move is a walking action, or one whose other environment effects can harm
nobody: facts it adds that no action deletes or needs false (a cell ``visited``). An
action's possible effects count, conditional ones included.
"""

from __future__ import annotations

from collections import Counter, defaultdict, deque
from collections.abc import Callable, Collection, Sequence

from twostep.dealing.encoding import FactSpace, GoalBits, Step
from twostep.dealing.model import DealError, cpu_seconds
from twostep.decomposers.goal_split import positional_predicates
from twostep.pddl import Domain, Fact, Problem
from twostep.pddl.model import ActionSchema
from twostep.plans.simulate import GroundAction, Grounder

WALK_LIMIT = 20_000
"""States the walking search may visit for one action before the deal gives up."""


def walking_space(problem: Problem, agent_predicates: Collection[str]) -> FactSpace:
    """The task's facts as bits, with the positional and harmless predicates walks use."""
    domain = problem.domain
    return FactSpace(
        problem,
        agent_predicates,
        positional_predicates(domain),
        harmless_predicates(domain, agent_predicates),
    )


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
    conditional = {
        p for s in actions if not s.is_strips for p in _negated([s.precondition, s.effect])
    }
    return added - deleted - forbidden - conditional - set(agent_predicates)


def _negated(formula: object) -> set[str]:
    """Predicates under a ``not`` anywhere in an s-expression (a precondition or an effect
    condition beyond the top-level conjunction)."""
    found: set[str] = set()
    if isinstance(formula, list):
        if formula[:1] == ["not"] and len(formula) == 2 and isinstance(formula[1], list):
            inner = formula[1]
            if inner and isinstance(inner[0], str):
                found.add(inner[0])
        for part in formula:
            found |= _negated(part)
    return found


def _may_move(schema: ActionSchema, space: FactSpace) -> bool:
    """Whether some grounding of ``schema`` may be a move (its effects, as written, change
    positional agent facts): the grounded actions of other schemas are not looked at."""
    agent, positional = space.agent_predicates, space.positional
    own = [a.predicate for a in (*schema.add, *schema.delete) if a.predicate in agent]
    return bool(own) and all(p in positional for p in own)


def is_move(action: GroundAction, space: FactSpace) -> bool:
    """A walking action, or one whose other environment effects are harmless additions
    (module docstring)."""
    agent, positional = space.agent_predicates, space.positional
    own = [f[0] for f in action.possible_add | action.possible_delete if f[0] in agent]
    env_add = [f[0] for f in action.possible_add if f[0] not in agent]
    env_del = [f[0] for f in action.possible_delete if f[0] not in agent]
    return (
        bool(own)
        and all(p in positional for p in own)
        and all(p in positional for p in env_del)
        and all(p in positional or p in space.harmless for p in env_add)
    )


def _rank(entry: tuple[int, Step]) -> int:
    return entry[0]


def slot(fact: Fact) -> Fact:
    """What an agent fact is about, leaving out where: ``(robot-at robot1 t3)`` is about
    ``robot-at robot1``, termes' ``(at p3)`` about ``at``."""
    return fact[:-1] if len(fact) > 1 else fact


class Walker:
    """Shortest walks of one agent: breadth-first over the task's moves.

    ``universe`` holds every environment fact a walk may meet (the facts of the SA plan's
    states, and what moves may add). The moves that could apply where an agent stands are
    indexed by an agent fact they need (one per slot, :func:`slot`, in a floortile agent's
    two robots); which of them apply is cached per own state and the environment facts
    they read. A walk moves only what the target action needs of the agent (robot1 walks
    for robot1's painting).
    """

    def __init__(self, problem: Problem, space: FactSpace, universe: frozenset[Fact]):
        self.problem = problem
        self.space = space
        agent = space.agent_predicates
        schemas = {s.name for s in problem.domain.actions.values() if _may_move(s, space)}
        moves = sorted(  # set order varies per process: walks must not
            (
                a
                for a in problem.grounded.actions.values()
                if a.name in schemas and is_move(a, space)
            ),
            key=str,
        )
        universe = universe.union(*(a.possible_add for a in moves))
        self.universe_env, _ = space.bits(f for f in universe if f[0] not in agent)
        # index: an agent fact a move needs -> the move as bits, with its rank in the
        # order above (moves that need none: anywhere)
        steps = [space.step(a) for a in moves]
        self._needing: dict[Fact, list[tuple[int, int, Step]]] = defaultdict(list)
        self._anywhere: list[tuple[int, Step]] = []
        # each under the agent fact it needs that the fewest moves need (a car's place,
        # not that some other car stands at the curb): the fewest candidates to look at
        needs = [sorted(f for f in a.pre_positive if f[0] in agent) for a in moves]
        needed_by = Counter(f for facts in needs for f in facts)
        for rank, (facts, step) in enumerate(zip(needs, steps, strict=True)):
            if step.exact and step.pre_env & ~self.universe_env:
                continue  # it needs a fact no state met has: never a candidate
            if not facts:
                self._anywhere.append((rank, step))
                continue
            key = min(facts, key=lambda f: (needed_by[f], f))
            self._needing[key].append((rank, step.pre_own if step.exact else 0, step))
        # what moves can change at all: a walk never makes true what no move adds (a
        # tent put up, a car at the curb), nor false what no move deletes
        self.adds_env = self.adds_own = self.dels_env = self.dels_own = 0
        for step in steps:
            self.adds_env |= step.add_env
            self.adds_own |= step.add_own
            self.dels_env |= step.del_env
            self.dels_own |= step.del_own
        self._candidates: dict[int, tuple[list[Step], int]] = {}
        self._successors: dict[tuple[int, int], list[Step]] = {}
        self._moved: dict[Step, frozenset[Fact]] = {}  # per move: the slots it changes
        self._walks: dict[tuple[int, int, Step], list[Step] | None] = {}
        # per move, what the relaxed check reads: the positive preconditions it needs (none
        # for a move not exact as bits: as if it always applied) and what it adds
        self._relaxed_moves = [
            (s.pre_env, s.pre_own, s.add_env, s.add_own)
            if s.exact
            else (0, 0, s.add_env, s.add_own)
            for s in steps
        ]
        self._relaxed: dict[tuple[int, int], tuple[int, int]] = {}
        self.search_s = 0.0
        """Seconds spent in :meth:`walk_to` so far."""
        self.work = 0
        """What the searches so far cost, as a count: states reached, and moves looked at
        by the relaxed check."""

    def candidates(self, own: int) -> tuple[list[Step], int]:
        """The moves whose positive preconditions hold in the universe plus ``own``, and
        the environment bits they read."""
        found = self._candidates.get(own)
        if found is None:
            pool = [
                (rank, step)
                for fact in self.space.own_facts(own)
                for rank, needs_own, step in self._needing.get(fact, ())
                if not needs_own & ~own
            ]
            # a move not exact as bits reads more than it needs: the state decides
            steps = [step for _, step in sorted([*self._anywhere, *pool], key=_rank)]
            reads = 0
            for step in steps:
                reads |= step.pre_env | step.neg_env
            found = self._candidates[own] = (steps, reads)
        return found

    def moved(self, move: Step) -> frozenset[Fact]:
        """The slots of the agent facts ``move`` changes."""
        found = self._moved.get(move)
        if found is None:
            changed = move.action.possible_add | move.action.possible_delete
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

    def relaxed(self, env: int, own: int) -> tuple[int, int]:
        """The facts (environment, own bits) that moves may make true from ``env`` and
        ``own`` if they deleted nothing and forbade nothing (a move not exact as bits: as
        if it always applied), and those already true: a superset of what any walk
        reaches, so a fact outside it needs no search. Kept per state."""
        found = self._relaxed.get((env, own))
        if found is None:
            found = self._relax(env, own, -1, -1)
        return found

    def reaches(self, env: int, own: int, pos_env: int, pos_own: int) -> bool:
        """Whether :meth:`relaxed` from ``env`` and ``own`` holds the facts ``pos_env`` and
        ``pos_own``: the fixpoint is cut short once it does (the usual case), and kept
        when it is complete."""
        found = self._relaxed.get((env, own)) or self._relax(env, own, pos_env, pos_own)
        return not (pos_env & ~found[0] or pos_own & ~found[1])

    def _relax(self, env: int, own: int, pos_env: int, pos_own: int) -> tuple[int, int]:
        """The facts of :meth:`relaxed`, or (when ``pos_env`` and ``pos_own`` are reached
        before the end) the ones reached by then."""
        reached_env, reached_own, pending = env, own, self._relaxed_moves
        while pos_env & ~reached_env or pos_own & ~reached_own:
            waiting = []
            self.work += len(pending)
            for move in pending:  # the hot loop of the check: bits only
                needs_env, needs_own, adds_env, adds_own = move
                if needs_env & ~reached_env or needs_own & ~reached_own:
                    waiting.append(move)
                else:
                    reached_env |= adds_env
                    reached_own |= adds_own
            if len(waiting) == len(pending):
                self._relaxed[(env, own)] = (reached_env, reached_own)
                break
            pending = waiting
        return reached_env, reached_own

    def out_of_reach(self, env: int, own: int, pos: tuple[int, int], neg: tuple[int, int]) -> bool:
        """Whether no walk from ``env`` and ``own`` can make the facts ``pos`` (environment
        and own bits) true and ``neg`` false: one of them needs a change no move makes."""
        return bool(
            pos[0] & ~env & ~self.adds_env
            | pos[1] & ~own & ~self.adds_own
            | neg[0] & env & ~self.dels_env
            | neg[1] & own & ~self.dels_own
        )

    def walk_to(self, env: int, own: int, target: Step) -> list[Step]:
        """The shortest walk after which ``target`` applies (raise :class:`DealError`).
        Remembered: the deals of one plan ask for the same walks again and again, and a
        walk that is not there costs a whole search."""
        key = (env, own, target)
        if key not in self._walks:
            began = cpu_seconds()
            try:
                self._walks[key] = self._walk_to(env, own, target)
            except DealError:
                self._walks[key] = None
            finally:
                self.search_s += cpu_seconds() - began
        found = self._walks[key]
        if found is None:
            raise DealError(f"no walk to where {target} applies")
        return list(found)

    def _walk_to(self, env: int, own: int, target: Step) -> list[Step]:
        agent = self.space.agent_predicates
        needed = {slot(f) for f in target.action.pre_positive if f[0] in agent}
        pos, neg = (target.pre_env, target.pre_own), (target.neg_env, target.neg_own)
        if target.exact and self.out_of_reach(env, own, pos, neg):
            raise DealError(f"no walk to where {target} applies")
        # a fact it needs that no walk reaches, even without deletes
        if target.exact and not self.reaches(env, own, target.pre_env, target.pre_own):
            raise DealError(f"no walk to where {target} applies")
        try:
            return self._search(env, own, target.applicable, needed, str(target))
        except DealError:
            if all(needed >= self.moved(s) for s in self.candidates(own)[0]):
                raise  # every move was tried already
            return self._search(env, own, target.applicable, None, str(target))

    def walk_until(self, env: int, own: int, reached: Callable[[int, int], bool]) -> list[Step]:
        """The shortest walk (any move) to a state where ``reached`` holds (raise
        :class:`DealError`)."""
        began = cpu_seconds()
        try:
            return self._search(env, own, reached, None, "the goal")
        finally:
            self.search_s += cpu_seconds() - began

    def _search(
        self,
        env: int,
        own: int,
        reached: Callable[[int, int], bool],
        needed: set[Fact] | None,
        target: str,
    ) -> list[Step]:
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
            self.work += 1
            if reached(*node):
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


def closing_walk(
    walker: Walker, goal: GoalBits, env: int, owns: Sequence[int], load: Sequence[int]
) -> list[tuple[int, Step]]:
    """Walks after which the goal holds: when the SA plan's walks reach goal facts
    themselves (an aircraft's last flight, a robot stepping off a cell that must end up
    empty), no acting action leads there. Each agent whose own goal facts fail walks to
    where they hold; then, for each environment goal literal still false, an agent walks
    to where it holds, keeping the goal literals that hold already (the least busy agent
    first); last, if the goal still fails (a goal that reads derived facts), one agent
    walks to where it holds.
    :class:`DealError` when there is no such walk."""
    owns, joint = list(owns), []
    order = sorted(range(len(owns)), key=lambda a: (load[a], a))

    def walk(a: int, reached: Callable[[int, int], bool]) -> bool:
        nonlocal env
        try:
            path = walker.walk_until(env, owns[a], reached)
        except DealError:
            return False
        for step in path:
            env, owns[a] = step.apply(env, owns[a])
            joint.append((a, step))
        return True

    if goal.space is None:
        for a in order:
            if goal.own_holds(owns[a]):
                continue
            hopeless = walker.out_of_reach(env, owns[a], (0, goal.pos_own), (0, goal.neg_own))
            if hopeless or not walk(a, lambda _, own: goal.own_holds(own)):
                raise DealError("the dealt plans do not reach the goal")
        missing = (goal.pos_env | goal.neg_env) & ~goal.env_met(env)
        while missing:
            bit = missing & -missing
            missing &= ~bit
            if walker.out_of_reach(env, 0, (bit & goal.pos_env, 0), (bit & goal.neg_env, 0)):
                raise DealError("the dealt plans do not reach the goal")
            want = goal.env_met(env) | bit

            def kept(env: int, own: int, want: int = want) -> bool:
                return goal.env_met(env) & want == want and goal.own_holds(own)

            if not any(walk(a, kept) for a in order):  # nor does any walk to the whole goal
                raise DealError("the dealt plans do not reach the goal")
    if goal.holds(env, owns):
        return joint
    for a in order:

        def reached(env: int, own: int, a: int = a) -> bool:
            return goal.holds(env, [own if b == a else o for b, o in enumerate(owns)])

        if walk(a, reached):
            return joint
    raise DealError("the dealt plans do not reach the goal")


def stitch(
    problem: Problem, plans: Sequence[Sequence[str]], agent_predicates: Collection[str]
) -> list[str]:
    """The plans one after the other as one agent's plan, with the shortest walk before
    each action that does not apply where the plans before left the agent (TwoStep's
    agents each start from the initial agent facts: a helper's robot ends in another room
    than the main agent's starts from). Plans that apply one after the other come back
    unchanged. Raise :class:`DealError` where no walk helps (an agent still holding
    something), :class:`~twostep.plans.simulate.PlanError` for an action the task does not have."""
    space = walking_space(problem, agent_predicates)
    grounder = Grounder(problem)
    plans_grounded = [grounder.ground_plan(plan) for plan in plans]
    universe = problem.init.union(*(a.possible_add for plan in plans_grounded for a in plan))
    walker = Walker(problem, space, universe)
    env, own = space.bits(problem.init)
    stitched: list[str] = []
    for action in (a for plan in plans_grounded for a in plan):
        step = space.step(action)
        if not step.applicable(env, own):
            for move in walker.walk_to(env, own, step):
                env, own = move.apply(env, own)
                stitched.append(str(move))
        env, own = step.apply(env, own)
        stitched.append(str(action))
    return stitched
