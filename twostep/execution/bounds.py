"""Lower bounds for the A* search: longest remaining plan, fact contention, pair projections."""

from __future__ import annotations

import itertools
from collections.abc import Sequence

from twostep.execution.compiled import CompiledStep, CompiledTask


class PairProjection:
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

    def __init__(self, task: CompiledTask, first: int, second: int):
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

        def applicable(step: CompiledStep, state: int) -> bool:
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


def interacting_pairs(task: CompiledTask) -> list[PairProjection]:
    """Projections for the pairs of agents whose plans share a fact one of them writes."""
    pairs = []
    for i, j in itertools.combinations(range(len(task.steps)), 2):
        reads_i, writes_i = task.reads_from[i][0], task.writes_from[i][0]
        reads_j, writes_j = task.reads_from[j][0], task.writes_from[j][0]
        if writes_i & (reads_j | writes_j) or writes_j & reads_i:
            pairs.append(PairProjection(task, i, j))
    return pairs


class ContentionBound:
    """Agents that consume the same exclusive fact must take turns: a makespan bound.

    A *consumer* of environment fact f needs f and deletes it (and does not add it back),
    like entering a cell that must be free. Two consumers of f cannot share a step (one
    deletes what the other needs), and after one runs f is false until some action adds it
    again in a later step, which cannot be the step of the next consumer either (adding and
    deleting f interfere). So consumers of f run at least two steps apart, whichever agents
    they belong to and whoever adds f back. For a consumer that is action k of an agent at
    index i with n actions, it runs no earlier than step k - i + 1 from now (step 2 if f is
    false now) and leaves n - k - 1 actions after it. For any set S of remaining consumers
    of f, the last of them runs no earlier than min release + 2 (|S| - 1), and its agent
    still has at least min tail to do: the bound is the maximum of that over S (the sets
    of consumers with release at least r and tail at least q suffice). This is the
    single-machine "heads and tails" bound with every job taking two steps.

    Consistent: releases drop by at most one per step, and when a member of the best set
    is consumed now (release 1), the rest now have release at least 2 while the set lost
    one member, so the value drops by at most one (a lone member falls back on its tail,
    which the longest-remaining-plan bound covers).
    """

    def __init__(self, task: CompiledTask):
        self.lengths = task.lengths
        consumers: dict[int, list[tuple[int, tuple[int, ...]]]] = {}
        for agent, plan in enumerate(task.steps):
            by_fact: dict[int, list[int]] = {}
            for k, step in enumerate(plan):
                consumed = step.pre_positive & step.delete & ~step.add
                while consumed:
                    bit = consumed & -consumed
                    consumed ^= bit
                    by_fact.setdefault(bit, []).append(k)
            for bit, ks in by_fact.items():
                consumers.setdefault(bit, []).append((agent, tuple(ks)))
        self.facts = [
            (bit, agents)
            for bit, agents in consumers.items()
            if sum(len(ks) for _, ks in agents) >= 2
        ]

    def __call__(self, indices: Sequence[int], state: int) -> int:
        lengths = self.lengths
        best = 0
        for bit, agents in self.facts:
            earliest = 1 if state & bit else 2
            events: list[tuple[int, int]] = []
            for agent, ks in agents:
                index = indices[agent]
                for k in ks:
                    if k >= index:
                        events.append((max(k - index + 1, earliest), lengths[agent] - k - 1))
            if len(events) < 2:
                continue
            events.sort()
            for first, (release, _) in enumerate(events):
                if first and release == events[first - 1][0]:
                    continue
                tails = sorted((tail for _, tail in events[first:]), reverse=True)
                for later, tail in enumerate(tails):
                    best = max(best, release + 2 * later + tail)
        return best


class LowerBound:
    """An admissible, consistent lower bound on the steps left from a search node.

    The maximum of the longest remaining plan (each step advances an agent by at most one
    action), the contention bound of :class:`ContentionBound` and the pair projections of
    :class:`PairProjection`; None for a dead end. Each part drops by at most one per real
    step, so the maximum is consistent too. ``pairs=False`` skips the projections (cheap
    to build, no dead-end detection), ``contention=False`` the contention bound.
    """

    def __init__(self, task: CompiledTask, pairs: bool = True, contention: bool = True):
        self.lengths = task.lengths
        self.contention = ContentionBound(task) if contention else None
        self.pairs = interacting_pairs(task) if pairs else []

    def __call__(self, indices: Sequence[int], state: int) -> int | None:
        bound = max((n - i for n, i in zip(self.lengths, indices, strict=True)), default=0)
        if self.contention is not None:
            bound = max(bound, self.contention(indices, state))
        for pair in self.pairs:
            steps = pair(indices, state)
            if steps is None:
                return None
            bound = max(bound, steps)
        return bound
