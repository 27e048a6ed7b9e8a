"""A* over (plan indices, environment state): successors per mode and dominance pruning."""

from __future__ import annotations

import heapq
import itertools
import time
from dataclasses import dataclass

from twostep.makespan.bounds import LowerBound
from twostep.makespan.compiled import CompiledTask, Node
from twostep.makespan.model import DEFAULT_MAX_NODES, DEFAULT_TIME_LIMIT_S
from twostep.makespan.symmetry import Permutation, Symmetry, relabel


def free_agents(task: CompiledTask, indices: tuple[int, ...], movable: list[int]) -> list[int]:
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


def compatible_sets(
    task: CompiledTask, indices: tuple[int, ...], agents: list[int]
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


def successor_sets(
    task: CompiledTask, indices: tuple[int, ...], state: int, mode: str, prune: bool
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
    free = free_agents(task, indices, movable) if prune else []
    rest = [i for i in movable if i not in free]
    return [
        tuple(sorted((*free, *chosen)))
        for chosen in compatible_sets(task, indices, rest)
        if free or chosen
    ]


def greedy_schedule(task: CompiledTask, mode: str) -> list[tuple[int, ...]] | None:
    """A quick schedule for an upper bound: list scheduling, longest remaining plan first.

    Each step takes the free agents (:func:`free_agents`) and then every applicable agent,
    longest remaining plan first, whose action interferes with none chosen so far (in
    ``paper`` mode: all remaining agents when they may act together, else the first one).
    When that gets stuck or misses the goal, the hand-off order (each plan in turn) is
    tried. Returns the agent sets per step, or None when neither works.
    """
    lengths = task.lengths
    indices = [0] * len(lengths)
    state = task.initial
    sets: list[tuple[int, ...]] = []
    while any(i < n for i, n in zip(indices, lengths, strict=True)):
        current = tuple(indices)
        active = [i for i, index in enumerate(current) if index < lengths[i]]
        movable = [i for i in active if task.steps[i][current[i]].applicable(state)]
        movable.sort(key=lambda i: (current[i] - lengths[i], i))
        if not movable:
            break
        if mode == "paper":
            options = successor_sets(task, current, state, mode, prune=False)
            chosen = max(options, key=len) if len(options[-1]) > 1 else (movable[0],)
        else:
            picked = free_agents(task, current, movable)
            for agent in movable:
                if agent in picked:
                    continue
                step = task.steps[agent][current[agent]]
                if not any(step.interferes(task.steps[o][current[o]]) for o in picked):
                    picked.append(agent)
            chosen = tuple(sorted(picked))
        state = advance(task, current, state, chosen)[1]
        for agent in chosen:
            indices[agent] += 1
        sets.append(chosen)
    else:
        if goal_holds(task, state):
            return sets
    # Hand-off order: each plan in turn, as planned.
    state = task.initial
    for plan in task.steps:
        for step in plan:
            if not step.applicable(state):
                return None
            state = task.successor(state, (step,))
    if not goal_holds(task, state):
        return None
    return [(agent,) for agent, n in enumerate(lengths) for _ in range(n)]


def bound_dive(
    task: CompiledTask, mode: str, bound: LowerBound, limit: int
) -> list[tuple[int, ...]] | None:
    """A schedule by always taking the successor with the smallest lower bound.

    Ties go to more agents acting. Unlike list scheduling it can hold an agent back for
    one with more work behind the same shared fact. None when stuck, when it misses the
    goal, or after ``limit`` steps.
    """
    lengths = task.lengths
    node: Node = (tuple(0 for _ in lengths), task.initial)
    sets: list[tuple[int, ...]] = []
    while any(i < n for i, n in zip(node[0], lengths, strict=True)):
        if len(sets) >= limit:
            return None
        best: tuple[int, int, tuple[int, ...], Node] | None = None
        for chosen in successor_sets(task, *node, mode, prune=True):
            child = advance(task, *node, chosen)
            h = bound(*child)
            if h is not None and (best is None or (h, -len(chosen)) < best[:2]):
                best = (h, -len(chosen), chosen, child)
        if best is None:
            return None
        sets.append(best[2])
        node = best[3]
    return sets if goal_holds(task, node[1]) else None


def goal_holds(task: CompiledTask, state: int) -> bool:
    return task.goal_positive & state == task.goal_positive and not task.goal_negative & state


def advance(
    task: CompiledTask, indices: tuple[int, ...], state: int, chosen: tuple[int, ...]
) -> Node:
    """The node after the agents in ``chosen`` take their next actions together."""
    if not task.simple:
        steps = [task.steps[agent][indices[agent]] for agent in chosen]
        advanced = list(indices)
        for agent in chosen:
            advanced[agent] += 1
        return tuple(advanced), task.successor(state, steps)
    delete = add = 0
    advanced = list(indices)
    for agent in chosen:
        step = task.steps[agent][indices[agent]]
        delete |= step.delete
        add |= step.add
        advanced[agent] += 1
    return tuple(advanced), (state & ~delete) | add


@dataclass(frozen=True)
class SearchResult:
    """What :func:`search` found: agent sets per step (None: no schedule) and its proof."""

    sets: list[tuple[int, ...]] | None
    expanded: int
    """Search nodes expanded, counting each step of the greedy schedule as one."""
    exact: bool
    """Whether ``sets`` is proven shortest."""
    lower_bound: int
    """A proven lower bound on the shortest makespan (``len(sets)`` when exact)."""


def search(
    task: CompiledTask,
    mode: str,
    plain: bool = False,
    max_nodes: int | None = DEFAULT_MAX_NODES,
    time_limit_s: float | None = DEFAULT_TIME_LIMIT_S,
) -> SearchResult:
    """A* over (plan indices, environment state) with an anytime stop.

    First a greedy schedule (:func:`greedy_schedule`, then :func:`bound_dive` when that is
    not proven optimal) gives an upper bound; when the cheap bounds (longest remaining
    plan, contention) already meet it at the start, it is optimal and no search runs.
    Otherwise A* runs with the pair projections too, over canonical nodes
    (:class:`~twostep.makespan.symmetry.Symmetry`: one node per relabelling of
    interchangeable agents), and stops at the first goal node (optimal), when the smallest
    f on the frontier reaches the greedy length (the greedy schedule is optimal), or after
    ``max_nodes`` expansions or ``time_limit_s`` seconds (None: no limit): then the greedy
    schedule is returned with ``exact=False`` and the smallest f on the frontier as lower
    bound (every path to a goal passes a frontier node, and f never overestimates). The
    time limit also cuts the building of pair projections short (the bound stays
    admissible without them). Without a greedy schedule neither budget applies (there is
    nothing to return), so plans that only work interleaved are still searched to the end.

    A node is expanded again when it is reached with a smaller g, so the result stays
    optimal even where the bound is not consistent across a relabelling.

    ``plain`` turns off every bound but the longest remaining plan, the dominance pruning,
    the symmetry reduction, the greedy schedule and the budgets (for benchmarks only).
    """
    deadline = None if time_limit_s is None or plain else time.perf_counter() + time_limit_s
    start: Node = (tuple(0 for _ in task.lengths), task.initial)
    incumbent = None if plain else greedy_schedule(task, mode)
    expanded = 0
    if incumbent is not None:
        expanded = len(incumbent) + 1  # the greedy run visited one node per step
        cheap_bound = LowerBound(task, pairs=False)
        cheap = cheap_bound(*start)
        assert cheap is not None
        if cheap >= len(incumbent):
            return SearchResult(incumbent, expanded, True, len(incumbent))
        if not _past(deadline):
            dive = bound_dive(task, mode, cheap_bound, len(incumbent) - 1)
            if dive is not None:
                expanded += len(dive) + 1
                incumbent = dive
                if cheap >= len(incumbent):
                    return SearchResult(incumbent, expanded, True, len(incumbent))
    # Symmetry, pair projections and the contention bound reason about STRIPS steps only.
    symmetry = None if plain or not task.simple else Symmetry(task)
    bound = LowerBound(
        task,
        pairs=not plain,
        contention=not plain,
        symmetry=symmetry,
        deadline=None if incumbent is None else deadline,
    )
    return astar(
        task,
        mode,
        bound,
        symmetry,
        prune=not plain,
        incumbent=incumbent,
        expanded=expanded,
        max_nodes=max_nodes,
        deadline=deadline,
    )


def astar(
    task: CompiledTask,
    mode: str,
    bound: LowerBound,
    symmetry: Symmetry | None = None,
    *,
    prune: bool = True,
    incumbent: list[tuple[int, ...]] | None = None,
    expanded: int = 0,
    max_nodes: int | None = None,
    deadline: float | None = None,
) -> SearchResult:
    """The A* part of :func:`search`, from the start node with the given bound.

    ``symmetry``: search canonical nodes only (None: every node). ``incumbent``: a known
    schedule, returned as soon as the frontier proves it optimal, or with ``exact=False``
    once ``max_nodes`` more nodes are expanded or the clock passes ``deadline`` (a
    ``time.perf_counter`` value); without one both limits are ignored. ``expanded`` is
    the count so far (the greedy runs).
    """
    if symmetry is not None and not symmetry:
        symmetry = None  # no interchangeable agents: skip the canonical forms
    lengths = task.lengths
    start: Node = (tuple(0 for _ in lengths), task.initial)
    h0 = bound(*start)
    if h0 is None:
        return SearchResult(None, expanded, True, 0)
    best: dict[Node, int] = {start: 0}
    parent: dict[Node, tuple[Node, tuple[int, ...], Permutation | None]] = {}
    closed: dict[Node, int] = {}
    counter = itertools.count()
    # Ties on f go to more progress: larger g (so smaller h), then fewer actions left.
    frontier = [(h0, 0, sum(lengths), next(counter), start)]
    budget = None if incumbent is None or max_nodes is None else expanded + max_nodes
    if incumbent is None:
        deadline = None
    while frontier:
        f, minus_g, left, _, node = frontier[0]
        if incumbent is not None and (
            f >= len(incumbent) or (budget is not None and expanded >= budget) or _past(deadline)
        ):
            proven = min(f, len(incumbent))
            return SearchResult(incumbent, expanded, proven == len(incumbent), max(h0, proven))
        heapq.heappop(frontier)
        g = -minus_g
        if closed.get(node, g + 1) <= g or best.get(node, g) < g:
            continue  # expanded already with this g or less, or a better entry is queued
        closed[node] = g
        expanded += 1
        indices, state = node
        if left == 0:
            if not goal_holds(task, state):
                continue
            path = []
            while node in parent:
                node, chosen, permutation = parent[node]
                path.append((chosen, permutation))
            return SearchResult(relabel(len(lengths), path[::-1]), expanded, True, g)
        for chosen in successor_sets(task, indices, state, mode, prune):
            child = advance(task, indices, state, chosen)
            permutation = None
            if symmetry is not None:
                child, permutation = symmetry.canonical(child)
            if best.get(child, g + 2) <= g + 1:
                continue
            h_child = bound(*child)
            if h_child is None:
                best[child] = -1  # a dead end stays one: never queued again
                continue
            best[child] = g + 1
            parent[child] = (node, chosen, permutation)
            entry = (g + 1 + h_child, -g - 1, left - len(chosen), next(counter), child)
            heapq.heappush(frontier, entry)
    if incumbent is not None:  # every other path was refuted: the greedy one is optimal
        return SearchResult(incumbent, expanded, True, len(incumbent))
    return SearchResult(None, expanded, True, 0)


def _past(deadline: float | None) -> bool:
    return deadline is not None and time.perf_counter() >= deadline
