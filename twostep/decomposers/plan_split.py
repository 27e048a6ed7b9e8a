"""``plan-split``: an LLM-free decomposer guided by the single-agent plan.

goal-split (:mod:`twostep.decomposers.goal_split`) only looks at the goal, so it finds no
helper for one termes tower or one blocksworld tower. plan-split looks at how the SA plan
reaches the goal and hands helpers whole stretches of that plan, including partial
progress (lower tower levels, cleared blocks). Algorithm, for an SA plan a_1..a_n and N
agents:

1. *Order the plan needs* (deordering over environment facts; agent-specific facts are
   private to each agent and create no order). For every environment precondition p of
   a_j, its causal link comes from the latest earlier action that adds p (or from the
   initial state). Each link (a_i, p, a_j) orders a_i before a_j, and every action a_k
   that deletes p is kept off the link: before a_i when it comes earlier in the plan,
   after a_j when it comes later. Goal literals are links to the end of the plan. A
   negative precondition keeps its action in plan order with every action that adds or
   deletes that fact (conservative; rare in the five domains). Any order of the actions
   that respects these edges reaches the same goal.
2. *Pieces an agent can do alone.* The plan is cut at every *free* state: the agent holds
   nothing, i.e. its non-positional agent facts (``arm-empty``, ``handempty``, ``free``,
   ``(not (has-block))``) equal the initial ones; positional facts (where it stands) are
   left out, as in goal-split. A piece runs from one free state to the next, so it can be
   handed to another agent whole. Piece P precedes piece Q when an edge of step 1 goes
   from an action of P to an action of Q. A plan with no agent facts (tyreworld) is cut
   after every action. Variant ``cut="holding"`` (:func:`holding_pieces`): a piece is the
   actions tied together by what the agent holds (a shot from grasp to leave), so the
   pieces need not be contiguous; where they must interleave (a cycle in the order of
   step 1) they are merged, and actions that change no environment fact (walking) are
   left to the agents' planners and counted as travel time of the next piece.
3. *Assignment* (list scheduling). Pieces, in an order the edges allow (earliest first
   action first), go one by one to the agent on which they would finish earliest: a piece of k actions starts when its agent is free
   and its predecessor pieces have finished. The agents also have to be planned one after
   the other (TwoStep's hand-off): an agent whose piece needs another agent's piece must
   come later in that order, so an assignment that would make the agents' dependencies
   cyclic is skipped. The hand-off order is then a topological order of the agents (ties:
   whoever starts first goes first) and the last agent is the main agent, which always
   plans for the full goal. Variant ``assign="chunks"``: N consecutive stretches of equal
   length in that order instead; the agents then mostly follow one another, but each
   plans a shorter part of the task, which on long chains (termes) gives shorter plans.
4. *Subgoals.* Simulating the environment effects of the pieces of the first k agents
   gives the state helper k leaves behind. Its subgoal is the environment facts its own
   pieces added that still hold there and that are goal literals or the source of a causal
   link to a later agent (partial progress: a tower's lower levels, a cleared block), plus
   goal-split's release conditions (:func:`~twostep.decomposers.goal_split.release_literals`:
   hands empty, nothing carried). A helper whose pieces leave nothing of that kind gets no
   subgoal. Variant ``keep="goal"``: goal literals only (no partial progress), for tasks
   where the SA plan's intermediate facts tie helpers to one reused tool (barman's shot).

The result is deterministic given the SA plan. The pipeline passes that plan in
:attr:`~twostep.decomposers.base.DecompositionRequest.sa_plan` (it plans SA first when the
decomposer says :attr:`PlanSplitDecomposer.needs_sa_plan`).
"""

from __future__ import annotations

import heapq
import itertools
from collections import defaultdict
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field

from twostep.decomposers.base import DecompositionRequest, SubgoalProposal
from twostep.decomposers.goal_split import positional_predicates, release_literals
from twostep.pddl import Fact, Goal, Problem
from twostep.plans.progression import agent_part, environment_part
from twostep.plans.simulate import GroundAction, Grounder, effects_along, simulate


@dataclass(frozen=True)
class CausalLink:
    """``producer`` (an action index, or -1 for the initial state) gives ``fact`` to ``consumer``
    (an action index, or n for the goal)."""

    producer: int
    fact: Fact
    consumer: int


def plan_order(
    problem: Problem,
    plan: Sequence[GroundAction],
    agent_predicates: Collection[str],
    effects: Sequence[tuple[frozenset[Fact], frozenset[Fact]]] | None = None,
) -> tuple[set[tuple[int, int]], list[CausalLink]]:
    """Step 1: the order edges (i, j), i < j, the plan needs, and its causal links.

    ``effects``: each action's (adds, deletes) as they fired where the plan was run, for a
    ``plan`` that does not apply from the initial state by itself (plan-deal's actions with
    the walks between them left out); by default the plan is run from the initial state."""
    n = len(plan)
    if effects is None:
        effects = effects_along(problem.init, plan)
    adds = [environment_part(add, agent_predicates) for add, _ in effects]
    dels = [environment_part(delete, agent_predicates) for _, delete in effects]
    deleters: dict[Fact, list[int]] = defaultdict(list)
    writers: dict[Fact, list[int]] = defaultdict(list)
    for k in range(n):
        for fact in dels[k]:
            deleters[fact].append(k)
        for fact in adds[k] | dels[k]:
            writers[fact].append(k)
    links: list[CausalLink] = []
    latest: dict[Fact, int] = {f: -1 for f in environment_part(problem.init, agent_predicates)}
    edges: set[tuple[int, int]] = set()
    for j, action in enumerate(plan):
        for fact in sorted(environment_part(action.pre_positive, agent_predicates)):
            links.append(CausalLink(latest.get(fact, -1), fact, j))
        for fact in environment_part(action.pre_negative, agent_predicates):
            for k in writers[fact]:
                if k != j:
                    edges.add((min(j, k), max(j, k)))
        # delete before add, as in PDDL: a fact both deleted and added ends up added
        for fact in dels[j]:
            latest.pop(fact, None)
        for fact in adds[j]:
            latest[fact] = j
    for fact in sorted(environment_part(problem.goal.positive, agent_predicates)):
        links.append(CausalLink(latest.get(fact, -1), fact, n))
    for link in links:
        if link.producer >= 0 and link.consumer < n:
            edges.add((link.producer, link.consumer))
        for k in deleters[link.fact]:
            if k < link.producer:
                edges.add((k, link.producer))
            elif k > link.consumer and link.consumer < n:
                edges.add((link.consumer, k))
    if not all(a.is_strips and not a.axioms for a in plan):
        edges |= _conflicts(plan, agent_predicates)
    return {(i, j) for i, j in edges if i != j}, links


def _conflicts(
    plan: Sequence[GroundAction], agent_predicates: Collection[str]
) -> set[tuple[int, int]]:
    """Order edges between every two actions that may interact: one may write a shared fact
    the other reads or may write. With conditional effects, precondition variants or
    derived facts, what an action does depends on the state it meets, so the plan's own
    order of interacting actions is kept (any order the edges allow then runs as the plan
    does)."""
    reads = [environment_part(a.reads, agent_predicates) for a in plan]
    writes = [environment_part(a.writes, agent_predicates) for a in plan]
    return {
        (i, j)
        for i, j in itertools.combinations(range(len(plan)), 2)
        if writes[i] & (reads[j] | writes[j]) or writes[j] & reads[i]
    }


def free_states(
    problem: Problem, plan: Sequence[GroundAction], agent_predicates: Collection[str]
) -> list[int]:
    """Step 2: the indices t (0..n) after which the agent holds nothing (see the docstring)."""
    capacity = set(agent_predicates) - positional_predicates(problem.domain)

    def holding(state: frozenset[Fact]) -> frozenset[Fact]:
        return agent_part(state, capacity)

    free = holding(problem.init)
    state = problem.init
    result = [0]
    for t, action in enumerate(plan, start=1):
        state = simulate(state, [action])
        if holding(state) == free:
            result.append(t)
    if result[-1] != len(plan):
        result.append(len(plan))  # the plan ends where it ends, free or not
    return result


def free_pieces(
    problem: Problem, plan: Sequence[GroundAction], agent_predicates: Collection[str]
) -> list[list[int]]:
    """Step 2, ``cut="free"``: the stretches between free states (every action alone when
    the plan has no agent facts at all)."""
    cuts = free_states(problem, plan, agent_predicates)
    if not any(f[0] in agent_predicates for a in plan for f in a.facts):
        cuts = list(range(len(plan) + 1))  # no agent state at all: every action alone
    return [list(range(a, b)) for a, b in itertools.pairwise(cuts) if b > a]


def holding_pieces(
    problem: Problem, plan: Sequence[GroundAction], agent_predicates: Collection[str]
) -> list[list[int]]:
    """Step 2, ``cut="holding"``: actions tied together by what the agent holds.

    Two actions are tied when one gives the other an agent fact that a fresh agent does
    not have (``holding h c``, ``has-block``, ``carry b g``), the latest such producer as
    in step 1. Facts a fresh agent has (its initial non-positional facts: empty hands) and
    positional facts (where it stands: it can walk) tie nothing. So a barman agent's shot
    and shaker are separate pieces even where the SA plan held one while using the other.
    """
    positional = positional_predicates(problem.domain)
    own = agent_part(problem.init, agent_predicates)
    parent = list(range(len(plan)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    latest: dict[Fact, int] = {}
    for j, (action, (add, delete)) in enumerate(
        zip(plan, effects_along(problem.init, plan), strict=True)
    ):
        for fact in action.pre_positive | delete:
            tying = fact[0] in agent_predicates and fact[0] not in positional
            if tying and fact not in own and fact in latest:
                parent[find(j)] = find(latest[fact])
        for fact in delete:
            latest.pop(fact, None)
        for fact in add:
            latest[fact] = j
    groups: dict[int, list[int]] = defaultdict(list)
    for i in range(len(plan)):
        groups[find(i)].append(i)
    return sorted(groups.values())


def merge_cycles(pieces: list[list[int]], edges: set[tuple[int, int]]) -> list[list[int]]:
    """Merge pieces that must interleave (a cycle between them in the order of step 1)."""
    piece_of = {i: p for p, members in enumerate(pieces) for i in members}
    succ: dict[int, set[int]] = defaultdict(set)
    for i, j in edges:
        if piece_of[i] != piece_of[j]:
            succ[piece_of[i]].add(piece_of[j])
    index: dict[int, int] = {}
    low: dict[int, int] = {}
    stack: list[int] = []
    on_stack: set[int] = set()
    components: list[list[int]] = []

    def strongconnect(v: int) -> None:  # Tarjan; pieces are few (tens to hundreds)
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in succ[v]:
            if w not in index:
                strongconnect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            components.append(component)

    for v in range(len(pieces)):
        if v not in index:
            strongconnect(v)
    merged = [sorted(i for p in component for i in pieces[p]) for component in components]
    return sorted(merged)


@dataclass
class Split:
    """What the algorithm decided, for tests and reports: pieces, owners, subgoals."""

    pieces: list[list[int]]  # action indices of each piece, in the order scheduled
    owner: list[int]  # per piece: its agent's position in the hand-off order
    makespan: int  # the list schedule's estimated length, in actions
    subgoals: list[Goal] = field(default_factory=list)  # per helper, in hand-off order


def _cyclic(edges: set[tuple[int, int]], nodes: int) -> bool:
    succ: dict[int, set[int]] = defaultdict(set)
    for a, b in edges:
        succ[a].add(b)
    state = [0] * nodes  # 0 unseen, 1 on the stack, 2 done

    def visit(u: int) -> bool:
        state[u] = 1
        for v in succ[u]:
            if state[v] == 1 or (state[v] == 0 and visit(v)):
                return True
        state[u] = 2
        return False

    return any(state[u] == 0 and visit(u) for u in range(nodes))


def split_plan(
    problem: Problem,
    plan: Sequence[str],
    agents: int,
    agent_predicates: Collection[str],
    cut: str = "free",
    keep: str = "links",
    assign: str = "list",
) -> Split:
    """Steps 1-4 for one SA plan and ``agents`` agents.

    ``cut="free"`` cuts the plan at free states (step 2); ``cut="holding"`` ties actions by
    what the agent holds (:func:`holding_pieces`): finer pieces, not contiguous in the
    plan, with actions that change no environment fact (walking) left to the agents'
    own planners and counted as travel time of the next piece. ``keep="goal"`` keeps only
    the goal literals in the subgoals (no partial progress). ``assign="chunks"`` replaces the
    list schedule by N consecutive stretches of equal length in the pieces' order: the
    agents then mostly follow one another, and each plans a shorter stretch of the task.
    """
    grounded = Grounder(problem).ground_plan(plan)
    edges, links = plan_order(problem, grounded, agent_predicates)
    pieces, durations = _pieces(problem, grounded, agent_predicates, edges, cut)
    pieces = topological_pieces(pieces, edges)
    piece_of = {i: p for p, members in enumerate(pieces) for i in members}
    preds: list[set[int]] = [set() for _ in pieces]
    for i, j in edges:
        if i in piece_of and j in piece_of and piece_of[i] != piece_of[j]:
            preds[piece_of[j]].add(piece_of[i])
    lengths = [durations[piece[0]] for piece in pieces]
    total = sum(lengths)
    schedule = _HandOffSchedule(agents, len(grounded))
    for p, before in enumerate(preds):
        schedule.place(before, lengths[p], chunk=assign == "chunks", total=total)
    used = sorted(set(schedule.agent_of), key=lambda a: (schedule.first_start[a], a))
    order = _topological(used, schedule.agent_edges, schedule.first_start)
    position = {a: k for k, a in enumerate(order)}
    owner = [position[a] for a in schedule.agent_of]
    split = Split(pieces, owner, max(schedule.finish, default=0))
    split.subgoals = _subgoals(
        problem, grounded, agent_predicates, links, pieces, owner, len(order) - 1, keep
    )
    return split


def _pieces(
    problem: Problem,
    grounded: Sequence[GroundAction],
    agent_predicates: Collection[str],
    edges: set[tuple[int, int]],
    cut: str,
) -> tuple[list[list[int]], dict[int, int]]:
    """Step 2: the pieces, and their durations by first action (with ``cut="holding"``,
    walking counts towards the next piece that acts)."""
    durations: dict[int, int] = defaultdict(int)  # by first action of a piece
    if cut != "holding":
        pieces = free_pieces(problem, grounded, agent_predicates)
        for members in pieces:
            durations[members[0]] = len(members)
        return pieces, durations
    free_states(problem, grounded, agent_predicates)  # the plan must be applicable
    pieces = merge_cycles(holding_pieces(problem, grounded, agent_predicates), edges)
    acting = [
        members
        for members in pieces
        if any(environment_part(grounded[i].writes, agent_predicates) for i in members)
    ]
    acting_piece = {i: members[0] for members in acting for i in members}
    for members in acting:
        durations[members[0]] = len(members)
    for i in range(len(grounded)):  # walking counts towards the next action that acts
        if i not in acting_piece:
            after = [j for j in sorted(acting_piece) if j > i]
            if after:
                durations[acting_piece[after[0]]] += 1
    return acting, durations


class _HandOffSchedule:
    """Step 3: list scheduling under the hand-off constraint, one piece at a time (in an
    order the edges allow); or, with ``chunk``, consecutive stretches of equal length."""

    def __init__(self, agents: int, actions: int) -> None:
        self.agents = agents
        self.agent_of: list[int] = []  # per piece placed: its agent
        self.finish: list[int] = []  # per piece placed: when it ends
        self.free_at = [0] * max(agents, 1)
        self.first_start = [actions + 1] * max(agents, 1)
        self.agent_edges: set[tuple[int, int]] = set()  # agent a hands off to agent b
        self.done = 0  # chunks: the length placed so far

    def place(self, preds: set[int], length: int, chunk: bool, total: int) -> None:
        ready = max((self.finish[q] for q in preds), default=0)
        if chunk:  # the stretch the middle of this piece falls in
            agents = max(self.agents, 1)
            a = min(int((self.done + length / 2) * agents / max(total, 1)), self.agents - 1)
            self.done += length
            end = max(ready, self.free_at[a]) + length
        else:
            a, end = self._earliest(preds, length, ready)
        self.agent_edges |= {(self.agent_of[q], a) for q in preds if self.agent_of[q] != a}
        self.agent_of.append(a)
        self.finish.append(end)
        self.first_start[a] = min(self.first_start[a], end - length)
        self.free_at[a] = end

    def _earliest(self, preds: set[int], length: int, ready: int) -> tuple[int, int]:
        """The agent on which the piece ends earliest, then with the fewest hand-offs from
        other agents, then the idlest, without making the agents' hand-offs cyclic."""
        best: tuple[int, int, int, int] | None = None
        for a in range(max(self.agents, 1)):
            new = {(self.agent_of[q], a) for q in preds if self.agent_of[q] != a}
            if new - self.agent_edges and _cyclic(self.agent_edges | new, len(self.free_at)):
                continue
            start = max(ready, self.free_at[a])
            crossing = sum(self.agent_of[q] != a for q in preds)
            key = (start + length, crossing, self.free_at[a], a)
            if best is None or key < best:
                best = key
        # never None: the agent that comes last among the predecessors' agents closes no cycle
        assert best is not None
        return best[3], best[0]


def _subgoals(
    problem: Problem,
    grounded: Sequence[GroundAction],
    agent_predicates: Collection[str],
    links: Sequence[CausalLink],
    pieces: Sequence[Sequence[int]],
    owner: Sequence[int],
    helpers: int,
    keep: str,
) -> list[Goal]:
    """Step 4: the subgoal of each of the first ``helpers`` agents in hand-off order."""
    piece_of = {i: p for p, members in enumerate(pieces) for i in members}
    release = release_literals(problem, agent_predicates)
    goal_facts = environment_part(problem.goal.positive, agent_predicates)
    env = environment_part(problem.init, agent_predicates)
    effects = effects_along(problem.init, grounded)  # as the SA plan ran them
    subgoals: list[Goal] = []
    for k in range(helpers):
        mine = sorted(i for p, members in enumerate(pieces) if owner[p] == k for i in members)
        before = env
        added: set[Fact] = set()
        for i in mine:
            add, delete = effects[i]
            env = (env - environment_part(delete, agent_predicates)) | environment_part(
                add, agent_predicates
            )
            added |= environment_part(add, agent_predicates)
        later: set[Fact] = {
            link.fact
            for link in links
            if link.producer in mine
            and (
                link.consumer >= len(grounded)
                or (link.consumer in piece_of and owner[piece_of[link.consumer]] > k)
            )
        }
        if keep == "goal":
            later = set()
        wanted = frozenset(
            f for f in added & env if f not in before and (f in goal_facts or f in later)
        )
        if wanted:
            subgoals.append(Goal(wanted | release.positive, release.negative))
    return subgoals


def topological_pieces(pieces: list[list[int]], edges: set[tuple[int, int]]) -> list[list[int]]:
    """The pieces in an order their edges allow; among ready pieces, the earliest in the plan."""
    piece_of = {i: p for p, members in enumerate(pieces) for i in members}
    succ: dict[int, set[int]] = defaultdict(set)
    indegree = [0] * len(pieces)
    for i, j in edges:
        if i not in piece_of or j not in piece_of or piece_of[i] == piece_of[j]:
            continue
        if piece_of[j] not in succ[piece_of[i]]:
            succ[piece_of[i]].add(piece_of[j])
            indegree[piece_of[j]] += 1
    ready = [(pieces[p][0], p) for p in range(len(pieces)) if indegree[p] == 0]
    heapq.heapify(ready)
    order: list[list[int]] = []
    while ready:
        _, p = heapq.heappop(ready)
        order.append(pieces[p])
        for q in succ[p]:
            indegree[q] -= 1
            if indegree[q] == 0:
                heapq.heappush(ready, (pieces[q][0], q))
    return order


def _topological(
    nodes: list[int], edges: set[tuple[int, int]], first_start: list[int]
) -> list[int]:
    """Kahn's order of the agents; among ready agents, the one that starts first."""
    indegree = {a: 0 for a in nodes}
    for _, b in edges:
        indegree[b] += 1
    order: list[int] = []
    ready = [a for a in nodes if indegree[a] == 0]
    while ready:
        ready.sort(key=lambda a: (first_start[a], a))
        a = ready.pop(0)
        order.append(a)
        for x, b in edges:
            if x == a:
                indegree[b] -= 1
                if indegree[b] == 0:
                    ready.append(b)
    return order


class PlanSplitDecomposer:
    """Decomposer protocol wrapper around :func:`split_plan` (needs the SA plan)."""

    needs_sa_plan = True

    def __init__(
        self,
        agent_predicates: Collection[str],
        cut: str = "free",
        keep: str = "links",
        assign: str = "list",
    ):
        self.agent_predicates = frozenset(agent_predicates)
        self.cut, self.keep, self.assign = cut, keep, assign
        options = ((cut, "free"), (keep, "links"), (assign, "list"))
        suffix = "".join(f"-{x}" for x, default in options if x != default)
        self.name = f"plan-split{suffix}"

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        if request.agents < 2 or not request.sa_plan:
            return []
        split = split_plan(
            request.task.problem,
            request.sa_plan,
            request.agents,
            self.agent_predicates,
            self.cut,
            self.keep,
            self.assign,
        )
        return [
            SubgoalProposal(helper=i, pddl=goal.to_pddl())
            for i, goal in enumerate(split.subgoals, start=1)
        ]
