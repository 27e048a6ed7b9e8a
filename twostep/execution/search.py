"""A* over (plan indices, environment state): successors per mode and dominance pruning."""

from __future__ import annotations

import heapq
import itertools

from twostep.execution.bounds import LowerBound
from twostep.execution.compiled import CompiledTask

Node = tuple[tuple[int, ...], int]
"""A search node: each agent's next plan index and the environment state."""


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


def search(
    task: CompiledTask, mode: str, plain: bool = False
) -> tuple[list[tuple[int, ...]] | None, int]:
    """A* over (plan indices, environment state); returns the agent sets per step, or None.

    ``plain`` turns off the pair bound and the dominance pruning (for benchmarks only).
    """
    lengths = task.lengths
    bound = LowerBound(task, pairs=not plain)
    start: Node = (tuple(0 for _ in lengths), task.initial)
    h0 = bound(*start)
    if h0 is None:
        return None, 0
    best: dict[Node, int] = {start: 0}
    parent: dict[Node, tuple[Node, tuple[int, ...]]] = {}
    closed: set[Node] = set()
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
        for chosen in successor_sets(task, indices, state, mode, prune=not plain):
            delete = add = 0
            advanced = list(indices)
            for agent in chosen:
                step = task.steps[agent][indices[agent]]
                delete |= step.delete
                add |= step.add
                advanced[agent] += 1
            child: Node = (tuple(advanced), (state & ~delete) | add)
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
