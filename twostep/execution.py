"""Parallel execution length: how many time steps N sequential agent plans take together.

This is the paper's execution-length metric (its Algorithm 1), made exact for every N.

Model
    ``plans[i]`` is agent i's sequential plan. Plans come in hand-off order: each was planned
    from the environment state the previous ones left, so running them one after the other
    is a valid schedule when the plans are right, and where that run breaks is the
    diagnosis when no schedule exists (plans that only work interleaved, such as a
    multi-agent plan split per agent, are scored all the same). Facts whose predicate is
    agent-specific (``arm-empty``, ``holding`` in blocksworld) are private: every agent has
    its own copy, initialised to the agent-specific facts of the initial state, and only its
    own actions read or write it.
    All other facts form one shared environment. Because an agent's copy changes only
    through its own actions, its content after k actions is fixed in advance; the search
    state is therefore (plan indices, environment state).

Interference (Graphplan, extended to negative preconditions)
    Several agents may take their next actions in the same time step when every action's
    preconditions hold in the current state and no action deletes a positive precondition
    of another, adds a negative precondition of another, or adds what another deletes. Only
    environment facts can interfere: agent copies are private. A step applies all deletes
    and then all adds; with no interference this equals applying the actions in any order.
    After the last step every goal literal must hold: environment literals on the shared
    state, agent-specific literals in every agent's copy.

Search
    Both modes run A* over (plan indices, environment state) with unit step cost. The bound
    h is the larger of the longest remaining plan and, for every pair of agents whose plans
    interact, the exact makespan of those two plans with the other agents abstracted away
    (:class:`_PairProjection`, solved once up front, then a dict lookup per node). Both
    parts are admissible and consistent, so the first goal node popped is optimal and a
    closed set is safe; a pair that cannot reach its goal marks a dead end, which also
    refutes impossible cases quickly. The pair bound is what sees a main agent waiting for
    a helper's effect, the usual shape of hand-off plans. Ties on f go to the node with
    more progress (larger g, then fewer actions left), so cases without contention go
    straight down.

    * ``paper`` -- the successors of the paper's recursion: one agent alone, or all agents
      that still have actions together. Its memoised recursion computes the shortest path in
      exactly this graph, which A* finds without visiting every index tuple.
    * ``exact`` -- any non-empty set of applicable, pairwise non-interfering agents. One
      dominance rule keeps it fast; see :func:`_free_agents` for why it is safe.

Facts are numbered and states are Python ints used as bit sets, so a joint step is a few
integer operations. :func:`check_schedule` re-validates a schedule with plain frozensets,
independently of the search, and :func:`parallel_length` runs it on every result.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass

from twostep.pddl import Fact, Goal, fact_to_pddl
from twostep.strips import GroundAction, PlanError, parse_action

MODES = ("exact", "paper")

Schedule = tuple[tuple[tuple[int, str], ...], ...]
"""Per time step, the (agent index, action text) pairs that act in it, in agent order."""


@dataclass(frozen=True)
class ParallelExecution:
    """A joint schedule of per-agent plans and its makespan."""

    length: int
    """Makespan: the number of time steps."""
    steps: Schedule
    """Per time step: (agent index, action text), agents in index order."""
    mode: str
    """``"exact"`` or ``"paper"``."""
    nodes_expanded: int
    """Search nodes expanded, a measure of effort for benchmarks."""


class ScheduleError(Exception):
    """No schedule of the plans reaches the goal, or a given schedule is invalid.

    ``agent`` is the agent index, ``step`` the 1-based step in that agent's plan, ``action``
    its text and ``precondition`` the failing precondition as PDDL; a failure at the end
    names the goal literal in ``goal`` instead. ``time_step`` (1-based) is set when a
    given joint schedule is checked.
    """

    def __init__(
        self,
        message: str,
        *,
        agent: int | None = None,
        step: int | None = None,
        action: str | None = None,
        precondition: str | None = None,
        goal: str | None = None,
        time_step: int | None = None,
    ):
        super().__init__(message)
        self.message = message
        self.agent = agent
        self.step = step
        self.action = action
        self.precondition = precondition
        self.goal = goal
        self.time_step = time_step


def split_state(
    state: Iterable[Fact], agent_predicates: Collection[str]
) -> tuple[frozenset[Fact], frozenset[Fact]]:
    """Split ``state`` into (environment facts, agent-specific facts) by predicate."""
    environment: set[Fact] = set()
    agent: set[Fact] = set()
    for fact in state:
        (agent if fact[0] in agent_predicates else environment).add(fact)
    return frozenset(environment), frozenset(agent)


# ------------------------------------------------------------------ diagnosis


def _missing(
    positive: frozenset[Fact], negative: frozenset[Fact], state: frozenset[Fact]
) -> str | None:
    for fact in sorted(positive - state):
        return fact_to_pddl(fact)
    for fact in sorted(negative & state):
        return f"(not {fact_to_pddl(fact)})"
    return None


def _precondition_error(agent: int, step: int, action: str, missing: str) -> ScheduleError:
    return ScheduleError(
        f"agent {agent} step {step} {action}: precondition {missing} does not hold",
        agent=agent,
        step=step,
        action=action,
        precondition=missing,
    )


def _agent_copies(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> None:
    """Fail early on what no schedule can fix: an agent's own copy breaks its plan or goal.

    Each copy evolves only through its owner's actions, so an agent-specific precondition
    that fails here fails in every schedule, and each copy's final content is fixed.
    """
    _, agent_init = split_state(init, agent_predicates)
    _, goal_positive = split_state(goal.positive, agent_predicates)
    _, goal_negative = split_state(goal.negative, agent_predicates)
    for agent, plan in enumerate(plans):
        copy = agent_init
        for step, action in enumerate(plan, start=1):
            _, positive = split_state(action.pre_positive, agent_predicates)
            _, negative = split_state(action.pre_negative, agent_predicates)
            missing = _missing(positive, negative, copy)
            if missing is not None:
                raise _precondition_error(agent, step, str(action), missing)
            _, delete = split_state(action.delete, agent_predicates)
            _, add = split_state(action.add, agent_predicates)
            copy = (copy - delete) | add
        unmet = Goal(goal_positive, goal_negative).unmet(copy)
        if unmet:
            raise ScheduleError(
                f"goal literal {unmet[0]} does not hold for agent {agent} at the end "
                "(agent-specific goal literals must hold for every agent)",
                agent=agent,
                goal=unmet[0],
            )


def _diagnose(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> ScheduleError:
    """Why no schedule exists, found by running the plans in hand-off order.

    Hand-off order is itself a schedule, so when the search finds none, this simulation
    must fail somewhere; its first failure is what a user can act on.
    """
    environment, agent_init = split_state(init, agent_predicates)
    for agent, plan in enumerate(plans):
        copy = agent_init
        for step, action in enumerate(plan, start=1):
            view = environment | copy
            missing = action.failing_precondition(view)
            if missing is not None:
                return _precondition_error(agent, step, str(action), missing)
            environment, copy = split_state(action.apply(view), agent_predicates)
    environment_goal = Goal(
        split_state(goal.positive, agent_predicates)[0],
        split_state(goal.negative, agent_predicates)[0],
    )
    unmet = environment_goal.unmet(environment)
    if unmet:
        return ScheduleError(f"goal literal {unmet[0]} does not hold at the end", goal=unmet[0])
    return ScheduleError("no joint schedule of the plans reaches the goal")


# --------------------------------------------------------------- compiled form


@dataclass(frozen=True)
class _Step:
    """The environment part of one plan step, as bit sets over numbered facts."""

    pre_positive: int
    pre_negative: int
    add: int
    delete: int

    @property
    def reads(self) -> int:
        return self.pre_positive | self.pre_negative

    @property
    def writes(self) -> int:
        return self.add | self.delete

    @property
    def touched(self) -> int:
        return self.reads | self.writes

    def applicable(self, state: int) -> bool:
        return self.pre_positive & state == self.pre_positive and not self.pre_negative & state

    def interferes(self, other: _Step) -> bool:
        return bool(
            self.delete & (other.pre_positive | other.add)
            | self.add & (other.pre_negative | other.delete)
            | other.delete & self.pre_positive
            | other.add & self.pre_negative
        )


@dataclass(frozen=True)
class _Task:
    steps: tuple[tuple[_Step, ...], ...]
    reads_from: tuple[tuple[int, ...], ...]
    """reads_from[i][k]: facts that agent i's actions k.. read (0 when done)."""
    writes_from: tuple[tuple[int, ...], ...]
    """writes_from[i][k]: facts that agent i's actions k.. add or delete (0 when done)."""
    initial: int
    goal_positive: int
    goal_negative: int
    all_facts: int
    """The bit set of every numbered fact."""

    @property
    def lengths(self) -> tuple[int, ...]:
        return tuple(len(plan) for plan in self.steps)


def _compile(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> _Task:
    bits: dict[Fact, int] = {}

    def mask(facts: Iterable[Fact]) -> int:
        value = 0
        for fact in facts:
            if fact[0] in agent_predicates:
                continue
            bit = bits.get(fact)
            if bit is None:
                bit = bits[fact] = 1 << len(bits)
            value |= bit
        return value

    compiled: dict[int, _Step] = {}
    steps = []
    for plan in plans:
        agent_steps = []
        for action in plan:
            step = compiled.get(id(action))
            if step is None:
                step = compiled[id(action)] = _Step(
                    mask(action.pre_positive),
                    mask(action.pre_negative),
                    mask(action.add),
                    mask(action.delete),
                )
            agent_steps.append(step)
        steps.append(tuple(agent_steps))
    goal_positive, goal_negative = mask(goal.positive), mask(goal.negative)
    # Facts no action or goal mentions never matter; leaving them out keeps states small.
    initial = sum(bit for fact, bit in bits.items() if fact in init)
    reads_from, writes_from = [], []
    for plan_steps in steps:
        reads = [0] * (len(plan_steps) + 1)
        writes = [0] * (len(plan_steps) + 1)
        for k in range(len(plan_steps) - 1, -1, -1):
            reads[k] = reads[k + 1] | plan_steps[k].reads
            writes[k] = writes[k + 1] | plan_steps[k].writes
        reads_from.append(tuple(reads))
        writes_from.append(tuple(writes))
    return _Task(
        tuple(steps),
        tuple(reads_from),
        tuple(writes_from),
        initial,
        goal_positive,
        goal_negative,
        (1 << len(bits)) - 1,
    )


# ---------------------------------------------------------------------- search

_Node = tuple[tuple[int, ...], int]
"""A search node: each agent's next plan index and the environment state."""


def _free_agents(task: _Task, indices: tuple[int, ...], movable: list[int]) -> list[int]:
    """Movable agents whose next action can be taken now without loss (dominance pruning).

    An agent's next action a is *free* when the other agents' remaining actions (from their
    current indices on) write none of the facts a reads or writes, and read none of the
    facts a writes. Facts that everyone only reads (static ones) do not count.
    Claim: some optimal schedule from here takes every free action in this step.
    Proof: take an optimal schedule in which free action a of agent i runs later, at step
    t. Agent i does nothing before t (a is its next action) and nobody else writes a's
    facts, so they are the same now as at t: a is applicable now. It interferes with no
    other action of this step, since interference needs one of the two to write a fact the
    other reads or writes. Moving a to now changes only facts that no other remaining
    action reads or writes, so every other action stays applicable and non-interfering,
    agent i's later actions still run after now, and the final state is the same. The
    length does not grow (it shrinks if step t becomes empty). Applying the claim at every
    node keeps an optimal path in the pruned graph, so A* stays exact.
    Larger sets of non-free agents are NOT preferred: acting with more agents can destroy
    a fact another agent needs later, so every compatible subset of them is kept.
    """
    free = []
    for agent in movable:
        step = task.steps[agent][indices[agent]]
        reads = writes = 0
        for other, index in enumerate(indices):
            if other != agent:
                reads |= task.reads_from[other][index]
                writes |= task.writes_from[other][index]
        if not (step.touched & writes or step.writes & reads):
            free.append(agent)
    return free


def _compatible_sets(
    task: _Task, indices: tuple[int, ...], agents: list[int]
) -> list[tuple[int, ...]]:
    """Every set of ``agents`` (the empty one included) whose next actions do not interfere."""
    sets: list[tuple[int, ...]] = [()]
    for agent in agents:
        step = task.steps[agent][indices[agent]]
        sets += [
            (*chosen, agent)
            for chosen in sets
            if not any(step.interferes(task.steps[o][indices[o]]) for o in chosen)
        ]
    return sets


def _successor_sets(
    task: _Task, indices: tuple[int, ...], state: int, mode: str, prune: bool
) -> list[tuple[int, ...]]:
    """The sets of agents that may act together in the next step, in agent order."""
    lengths = task.lengths
    active = [i for i, index in enumerate(indices) if index < lengths[i]]
    movable = [i for i in active if task.steps[i][indices[i]].applicable(state)]
    if mode == "paper":
        sets: list[tuple[int, ...]] = [(i,) for i in movable]
        if len(active) > 1 and len(movable) == len(active):
            next_steps = [task.steps[i][indices[i]] for i in active]
            if not any(a.interferes(b) for a, b in itertools.combinations(next_steps, 2)):
                sets.append(tuple(active))
        return sets
    free = _free_agents(task, indices, movable) if prune else []
    rest = [i for i in movable if i not in free]
    return [
        tuple(sorted((*free, *chosen)))
        for chosen in _compatible_sets(task, indices, rest)
        if free or chosen
    ]


class _PairProjection:
    """Exact makespans of two agents' plans with every other agent abstracted away.

    The projection keeps agents i and j, their plans and the facts no other agent writes
    ("tracked"); preconditions on the other facts are assumed to hold, since some other
    agent might make them so at the right time. Interference stays as it is (it depends on
    the actions alone). Every real schedule, restricted to i and j, is a schedule of the
    projection that ends in the real final values of the tracked facts, so the projection's
    shortest makespan from a node's projection is an admissible bound, and a projection
    with no way to its goal proves the real node a dead end. A real step maps to one
    projected step (or none when neither agent acts), so the bound is also consistent.

    The projected space is small (index pairs times the few tracked states each), so it
    is explored once, forwards from the start, and solved backwards; lookups are then a
    dict access per pair and node. Exploration stops at nodes past the pair's last point
    of contact (neither remaining plan writes a fact the other touches): there the answer
    is the longer remainder, after one run of both remainders to check they still work.
    This is what sees an agent waiting for another: the main agent's next action needs a
    fact only a helper adds, or must not run before a helper's action it would disable.
    """

    def __init__(self, task: _Task, first: int, second: int):
        self.first, self.second = first, second
        others = 0
        for agent, written in enumerate(task.writes_from):
            if agent not in (first, second):
                others |= written[0]
        tracked = self.tracked = task.all_facts & ~others
        plans = (task.steps[first], task.steps[second])
        lengths = (len(plans[0]), len(plans[1]))
        reads = (task.reads_from[first], task.reads_from[second])
        writes = (task.writes_from[first], task.writes_from[second])
        goal_positive = task.goal_positive & tracked
        goal_negative = task.goal_negative & tracked

        def applicable(step: _Step, state: int) -> bool:
            positive = step.pre_positive & tracked
            return positive & state == positive and not step.pre_negative & tracked & state

        def alone(k: int, m: int, state: int) -> int | None:
            """Steps to go once the rest of the two plans cannot affect each other."""
            for step in (*plans[0][k:], *plans[1][m:]):
                if not applicable(step, state):
                    return None
                state = ((state & ~step.delete) | step.add) & tracked
            if goal_positive & state != goal_positive or goal_negative & state:
                return None
            return max(lengths[0] - k, lengths[1] - m)

        start = (0, 0, task.initial & tracked)
        children: dict[tuple[int, int, int], list[tuple[int, int, int]]] = {}
        settled: dict[tuple[int, int, int], int | None] = {}
        frontier = [start]
        while frontier:
            node = frontier.pop()
            if node in children:
                continue
            k, m, state = node
            children[node] = []
            # Past the last point of contact the pair needs no search: both just run on.
            if not (writes[0][k] & (reads[1][m] | writes[1][m]) or writes[1][m] & reads[0][k]):
                settled[node] = alone(k, m, state)
                continue
            can_first = k < lengths[0] and applicable(plans[0][k], state)
            can_second = m < lengths[1] and applicable(plans[1][m], state)
            moves = []
            if can_first:
                moves.append((1, 0, plans[0][k].delete, plans[0][k].add))
            if can_second:
                moves.append((0, 1, plans[1][m].delete, plans[1][m].add))
            if can_first and can_second and not plans[0][k].interferes(plans[1][m]):
                delete = plans[0][k].delete | plans[1][m].delete
                moves.append((1, 1, delete, plans[0][k].add | plans[1][m].add))
            for step_first, step_second, delete, add in moves:
                child = (k + step_first, m + step_second, ((state & ~delete) | add) & tracked)
                children[node].append(child)
                if child not in children:
                    frontier.append(child)
        # Every move advances k + m, so deciding nodes by decreasing k + m sees children first.
        self.explored = children.keys()
        self.distance: dict[tuple[int, int, int], int] = {}
        for node in sorted(children, key=lambda n: -(n[0] + n[1])):
            if node in settled:
                steps = settled[node]
            else:
                reachable = [self.distance[c] for c in children[node] if c in self.distance]
                steps = 1 + min(reachable) if reachable else None
            if steps is not None:
                self.distance[node] = steps

    def __call__(self, indices: Sequence[int], state: int) -> int | None:
        """Steps the pair still needs, or None when the node is a dead end."""
        node = (indices[self.first], indices[self.second], state & self.tracked)
        steps = self.distance.get(node)
        if steps is None and node not in self.explored:
            return 0  # unreachable in theory; a bound of 0 is always safe
        return steps


def _interacting_pairs(task: _Task) -> list[_PairProjection]:
    """Projections for the pairs of agents whose plans share a fact one of them writes."""
    pairs = []
    for i, j in itertools.combinations(range(len(task.steps)), 2):
        reads_i, writes_i = task.reads_from[i][0], task.writes_from[i][0]
        reads_j, writes_j = task.reads_from[j][0], task.writes_from[j][0]
        if writes_i & (reads_j | writes_j) or writes_j & reads_i:
            pairs.append(_PairProjection(task, i, j))
    return pairs


class _Bound:
    """An admissible, consistent lower bound on the steps left from a search node.

    The maximum of the longest remaining plan (each step advances an agent by at most one
    action) and the pair projections of :class:`_PairProjection`; None for a dead end.
    Each part drops by at most one per real step, so the maximum is consistent too.
    """

    def __init__(self, task: _Task, pairs: bool = True):
        self.lengths = task.lengths
        self.pairs = _interacting_pairs(task) if pairs else []

    def __call__(self, indices: Sequence[int], state: int) -> int | None:
        bound = max((n - i for n, i in zip(self.lengths, indices, strict=True)), default=0)
        for pair in self.pairs:
            steps = pair(indices, state)
            if steps is None:
                return None
            bound = max(bound, steps)
        return bound


def _search(
    task: _Task, mode: str, plain: bool = False
) -> tuple[list[tuple[int, ...]] | None, int]:
    """A* over (plan indices, environment state); returns the agent sets per step, or None.

    ``plain`` turns off the pair bound and the dominance pruning (for benchmarks only).
    """
    lengths = task.lengths
    bound = _Bound(task, pairs=not plain)
    start: _Node = (tuple(0 for _ in lengths), task.initial)
    h0 = bound(*start)
    if h0 is None:
        return None, 0
    best: dict[_Node, int] = {start: 0}
    parent: dict[_Node, tuple[_Node, tuple[int, ...]]] = {}
    closed: set[_Node] = set()
    counter = itertools.count()
    # Ties on f go to more progress: larger g (so smaller h), then fewer actions left.
    frontier = [(h0, 0, sum(lengths), next(counter), start)]
    expanded = 0
    while frontier:
        _, minus_g, left, _, node = heapq.heappop(frontier)
        if node in closed:
            continue
        closed.add(node)
        expanded += 1
        g = -minus_g
        indices, state = node
        if left == 0:
            if task.goal_positive & state != task.goal_positive or task.goal_negative & state:
                continue
            sets = []
            while node in parent:
                node, chosen = parent[node]
                sets.append(chosen)
            return sets[::-1], expanded
        for chosen in _successor_sets(task, indices, state, mode, prune=not plain):
            delete = add = 0
            advanced = list(indices)
            for agent in chosen:
                step = task.steps[agent][indices[agent]]
                delete |= step.delete
                add |= step.add
                advanced[agent] += 1
            child: _Node = (tuple(advanced), (state & ~delete) | add)
            if child in closed or best.get(child, g + 2) <= g + 1:
                continue
            h_child = bound(*child)
            if h_child is None:
                closed.add(child)  # a dead end stays one
                continue
            best[child] = g + 1
            parent[child] = (node, chosen)
            entry = (g + 1 + h_child, -g - 1, left - len(chosen), next(counter), child)
            heapq.heappush(frontier, entry)
    return None, expanded


def _parallel_length(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
    mode: str,
    plain: bool = False,
) -> ParallelExecution:
    if mode not in MODES:
        raise ValueError(f"unknown mode {mode!r}; expected one of {', '.join(MODES)}")
    _agent_copies(plans, init, goal, agent_predicates)
    task = _compile(plans, init, goal, agent_predicates)
    sets, expanded = _search(task, mode, plain)
    if sets is None:
        raise _diagnose(plans, init, goal, agent_predicates)
    indices = [0] * len(plans)
    steps = []
    for chosen in sets:
        joint = []
        for agent in chosen:
            joint.append((agent, str(plans[agent][indices[agent]])))
            indices[agent] += 1
        steps.append(tuple(joint))
    schedule = tuple(steps)
    check_schedule(schedule, plans, init, goal, agent_predicates)
    return ParallelExecution(len(schedule), schedule, mode, expanded)


def parallel_length(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
    mode: str = "exact",
) -> ParallelExecution:
    """The shortest joint schedule of per-agent plans that reaches ``goal``.

    ``mode="exact"`` minimises over any set of agents per step; ``mode="paper"`` allows
    only one agent or all remaining agents per step (the paper's Algorithm 1), so its
    length is never shorter. With one agent the length is its plan length.
    Raises :class:`ScheduleError` when no schedule reaches the goal, naming the agent, the
    1-based step, the action and the failing precondition (or the failing goal literal).
    """
    return _parallel_length(plans, init, goal, agent_predicates, mode)


# ------------------------------------------------------------------ validation


def _interference(
    first: GroundAction, second: GroundAction, agent_predicates: Collection[str]
) -> str | None:
    """The environment fact through which two actions interfere, as a phrase, or None."""

    def environment(facts: frozenset[Fact]) -> frozenset[Fact]:
        return split_state(facts, agent_predicates)[0]

    for a, b in ((first, second), (second, first)):
        for fact in sorted(environment(a.delete) & (b.pre_positive | b.add)):
            return f"{a} deletes {fact_to_pddl(fact)}, which {b} needs or adds"
        for fact in sorted(environment(a.add) & b.pre_negative):
            return f"{a} adds {fact_to_pddl(fact)}, which {b} requires to be false"
    return None


def check_schedule(
    steps: Sequence[Sequence[tuple[int, str]]],
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> None:
    """Re-validate a joint schedule by simulation; raise :class:`ScheduleError` if invalid.

    Checks that each time step names distinct agents in index order, each taking its next
    plan action, that all preconditions hold and no two actions interfere, that every plan
    is run to the end, and that the goal holds afterwards. Uses plain frozensets, not the
    search's encoding, so it is an independent check of :func:`parallel_length`.
    """
    environment, agent_init = split_state(init, agent_predicates)
    copies = [agent_init] * len(plans)
    indices = [0] * len(plans)
    for time_step, joint in enumerate(steps, start=1):
        if not joint:
            raise ScheduleError(f"time step {time_step} is empty", time_step=time_step)
        agents = [agent for agent, _ in joint]
        if agents != sorted(set(agents)) or not all(0 <= a < len(plans) for a in agents):
            raise ScheduleError(
                f"time step {time_step}: agents {agents} must be distinct plan indices "
                "in increasing order",
                time_step=time_step,
            )
        actions: list[tuple[int, GroundAction]] = []
        for agent, text in joint:
            index = indices[agent]
            if index >= len(plans[agent]):
                raise ScheduleError(
                    f"time step {time_step}: agent {agent} has no action left for {text}",
                    agent=agent,
                    action=text,
                    time_step=time_step,
                )
            action = plans[agent][index]
            try:
                same = parse_action(text) == (action.name, action.args)
            except PlanError:
                same = False
            if not same:
                raise ScheduleError(
                    f"time step {time_step}: agent {agent} step {index + 1} is {action}, "
                    f"not {text}",
                    agent=agent,
                    step=index + 1,
                    action=text,
                    time_step=time_step,
                )
            missing = action.failing_precondition(environment | copies[agent])
            if missing is not None:
                error = _precondition_error(agent, index + 1, str(action), missing)
                error.time_step = time_step
                raise error
            actions.append((agent, action))
        for (a, first), (b, second) in itertools.combinations(actions, 2):
            reason = _interference(first, second, agent_predicates)
            if reason is not None:
                raise ScheduleError(
                    f"time step {time_step}: agents {a} and {b} interfere: {reason}",
                    agent=b,
                    step=indices[b] + 1,
                    action=str(second),
                    time_step=time_step,
                )
        delete: set[Fact] = set()
        add: set[Fact] = set()
        for agent, action in actions:
            environment_delete, agent_delete = split_state(action.delete, agent_predicates)
            environment_add, agent_add = split_state(action.add, agent_predicates)
            delete |= environment_delete
            add |= environment_add
            copies[agent] = (copies[agent] - agent_delete) | agent_add
            indices[agent] += 1
        environment = (environment - delete) | add
    for agent, plan in enumerate(plans):
        if indices[agent] != len(plan):
            raise ScheduleError(
                f"agent {agent} stops after {indices[agent]} of its {len(plan)} actions",
                agent=agent,
                step=indices[agent] + 1,
            )
    environment_goal = Goal(
        split_state(goal.positive, agent_predicates)[0],
        split_state(goal.negative, agent_predicates)[0],
    )
    unmet = environment_goal.unmet(environment)
    if unmet:
        raise ScheduleError(f"goal literal {unmet[0]} does not hold at the end", goal=unmet[0])
    agent_goal = Goal(
        split_state(goal.positive, agent_predicates)[1],
        split_state(goal.negative, agent_predicates)[1],
    )
    for agent, copy in enumerate(copies):
        unmet = agent_goal.unmet(copy)
        if unmet:
            raise ScheduleError(
                f"goal literal {unmet[0]} does not hold for agent {agent} at the end",
                agent=agent,
                goal=unmet[0],
            )
