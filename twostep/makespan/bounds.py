"""Lower bounds for the A* search: longest remaining plan, fact contention, pair projections."""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence

from twostep.makespan.compiled import CompiledStep, CompiledTask
from twostep.makespan.symmetry import Symmetry


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

    def __init__(
        self, task: CompiledTask, first: int, second: int, limit: int | None = None
    ) -> None:
        """Raises :class:`ProjectionTooLarge` past ``limit`` explored nodes (None: no limit)."""
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
            if limit is not None and len(children) > limit:
                raise ProjectionTooLarge
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
        distance: dict[tuple[int, int, int], int] = {}
        for node in sorted(children, key=lambda n: -(n[0] + n[1])):
            if node in settled:
                steps = settled[node]
            else:
                reachable = [distance[c] for c in children[node] if c in distance]
                steps = 1 + min(reachable) if reachable else None
            if steps is not None:
                distance[node] = steps
        # Keys keep only the shared facts the pair touches: its private facts follow from
        # its indices, and facts it never touches never change the answer. Pairs that a
        # symmetry maps onto each other then have the same table (see interacting_pairs).
        touched = task.touched
        pair_touches = touched[first] | touched[second]
        others_touch = 0
        for agent, facts in enumerate(touched):
            if agent not in (first, second):
                others_touch |= facts
        private = (touched[first] ^ touched[second]) & ~others_touch
        self.key_mask = key_mask = tracked & pair_touches & ~private
        self.explored = {(k, m, state & key_mask) for k, m, state in children}
        self.distance = {(k, m, state & key_mask): d for (k, m, state), d in distance.items()}

    def __call__(self, indices: Sequence[int], state: int) -> int | None:
        """Steps the pair still needs, or None when the node is a dead end."""
        return self.at(indices[self.first], indices[self.second], state)

    def at(self, first_index: int, second_index: int, state: int) -> int | None:
        """:meth:`__call__` with the pair's two indices given: for this pair, or for a
        pair the symmetry maps onto it (its agents in the same order)."""
        node = (first_index, second_index, state & self.key_mask)
        steps = self.distance.get(node)
        if steps is None and node not in self.explored:
            return 0  # unreachable in theory; a bound of 0 is always safe
        return steps


class ProjectionTooLarge(Exception):
    """A pair projection would explore more nodes than its budget allows."""


PAIR_NODE_BUDGET = 20_000
"""Projection nodes explored over all pairs before the rest are left out (many agents
sharing cells give N (N - 1) / 2 projections of thousands of nodes each: seconds)."""


PairLookup = tuple[PairProjection, int, int]
"""A projection and the two agents whose indices it is looked up with (in its order)."""


def interacting_pairs(
    task: CompiledTask,
    node_budget: int | None = PAIR_NODE_BUDGET,
    symmetry: Symmetry | None = None,
    deadline: float | None = None,
) -> list[PairLookup]:
    """Projections for the pairs of agents whose plans share a fact one of them writes.

    With a ``symmetry``, pairs it maps onto each other (same classes of interchangeable
    agents) share one projection, built for the first of them: the tables agree once the
    agents are matched up (keys hold only shared facts, which the symmetry fixes).
    Projections are built in order until ``node_budget`` projection nodes are explored or
    the clock passes ``deadline`` (a ``time.perf_counter`` value); the pairs left get no
    projection, which keeps the bound admissible (each pair only raises it) but gives up
    their dead-end detection. Every pair of a kind is kept or none, so the bound has the
    same value on every node of an orbit.
    """

    def kind(agent: int) -> tuple[int, int]:
        if symmetry is not None and agent in symmetry.class_of:
            return 0, symmetry.class_of[agent]
        return 1, agent

    kinds: dict[tuple[tuple[int, int], tuple[int, int]], list[tuple[int, int]]] = {}
    for i, j in itertools.combinations(range(len(task.steps)), 2):
        reads_i, writes_i = task.reads_from[i][0], task.writes_from[i][0]
        reads_j, writes_j = task.reads_from[j][0], task.writes_from[j][0]
        if writes_i & (reads_j | writes_j) or writes_j & reads_i:
            first, second = (i, j) if kind(i) <= kind(j) else (j, i)
            kinds.setdefault((kind(first), kind(second)), []).append((first, second))
    lookups: list[PairLookup] = []
    left = node_budget
    for members in kinds.values():
        if deadline is not None and time.perf_counter() >= deadline:
            break
        try:
            pair = PairProjection(task, *members[0], left)
        except ProjectionTooLarge:
            break
        if left is not None:
            left -= len(pair.explored)
        lookups += [(pair, first, second) for first, second in members]
    return lookups


class ContentionBound:
    """Agents that consume the same exclusive fact must take turns: a makespan bound.

    A *consumer* of environment fact f needs f and deletes it (and does not add it back),
    like entering a cell that must be free. Two consumers of f cannot share a step (one
    deletes what the other needs), and after one runs f is false until some action adds it
    again in a later step, which cannot be the step of the next consumer either (adding and
    deleting f interfere). So consumers of f run at least p = 2 steps apart, whichever
    agents they belong to and whoever adds f back.

    Holds: when every action that adds f is a *release*, preceded in its own plan by a
    consumer of f with no other adder in between, f works as a lock. Invariant: holders
    (agents past a consumer and before its release) plus [f true] is at most 1; a consumer
    needs f true, so no one holds, and a release is run by its holder. So the next
    consumer runs only after the current holder's release: p = release - consume + 1
    steps apart. While an agent holds f, no other consumer runs before the step after its
    release.

    For a remaining consumption of an agent at index i, action k (n actions), the release
    r = k - i + 1 is the earliest step it can run (later when f is false or held), and
    q = n - k - 1 actions follow it. For any set S of them, in any order, the last runs no
    earlier than min r + (sum of p over S) - its own p, and its agent then still has q to
    do, so the makespan is at least min r + sum p + min (q - p) over S; the maximum over
    the sets with r and q - p above thresholds is taken (single-machine "heads and tails").

    Consistent: releases drop by at most one per step; when a member of the best set is
    consumed now (release 1, hold p), the others now wait at least p steps for it, so the
    value of the rest drops by at most one (a lone member falls back on its tail, which the
    longest-remaining-plan bound covers).
    """

    def __init__(self, task: CompiledTask):
        self.lengths = task.lengths
        adders = 0
        for plan in task.steps:
            for step in plan:
                adders |= step.add
        # fact -> [(agent, ((consume index, hold p, release index or -1), ...))]
        events: dict[int, list[tuple[int, tuple[tuple[int, int, int], ...]]]] = {}
        locks = adders  # facts still possibly locks; cleared on a non-release adder
        per_agent: list[dict[int, list[list[int]]]] = []
        for plan in task.steps:
            by_fact: dict[int, list[list[int]]] = {}
            for k, step in enumerate(plan):
                consumed = step.pre_positive & step.delete & ~step.add
                added = step.add & adders
                while added:
                    bit = added & -added
                    added ^= bit
                    open_holds = by_fact.get(bit)
                    if open_holds and open_holds[-1][2] < 0:
                        open_holds[-1][2] = k
                    else:
                        locks &= ~bit
                while consumed:
                    bit = consumed & -consumed
                    consumed ^= bit
                    by_fact.setdefault(bit, []).append([k, 2, -1])
            per_agent.append(by_fact)
        for agent, by_fact in enumerate(per_agent):
            for bit, holds in by_fact.items():
                entries = []
                for k, _, release in holds:
                    lock = bool(locks & bit) and release >= 0
                    entries.append((k, release - k + 1 if lock else 2, release if lock else -1))
                events.setdefault(bit, []).append((agent, tuple(entries)))
        self.facts = [
            (bit, agents) for bit, agents in events.items() if sum(len(e) for _, e in agents) >= 2
        ]

    def __call__(self, indices: Sequence[int], state: int) -> int:
        lengths = self.lengths
        best = 0
        for bit, agents in self.facts:
            earliest = 1 if state & bit else 2
            for agent, entries in agents:
                index = indices[agent]
                for k, _, release in entries:
                    if k < index <= release:  # this agent holds the lock now
                        earliest = max(earliest, release - index + 2)
            events: list[tuple[int, int, int]] = []
            for agent, entries in agents:
                index = indices[agent]
                for k, hold, _ in entries:
                    if k >= index:
                        release_at = max(k - index + 1, earliest)
                        events.append((release_at, hold, lengths[agent] - k - 1 - hold))
            if len(events) < 2:
                continue
            events.sort()
            for first, (release_at, _, _) in enumerate(events):
                if first and release_at == events[first - 1][0]:
                    continue
                total = 0
                for _, hold, slack in sorted(events[first:], key=lambda e: -e[2]):
                    total += hold
                    best = max(best, release_at + total + slack)
        return best


class LowerBound:
    """An admissible, consistent lower bound on the steps left from a search node.

    The maximum of the longest remaining plan (each step advances an agent by at most one
    action), the contention bound of :class:`ContentionBound` and the pair projections of
    :class:`PairProjection`; None for a dead end. Each part drops by at most one per real
    step, so the maximum is consistent too. ``pairs=False`` skips the projections (cheap
    to build, no dead-end detection), ``contention=False`` the contention bound;
    ``symmetry`` and ``deadline`` go to :func:`interacting_pairs`.
    """

    def __init__(
        self,
        task: CompiledTask,
        pairs: bool = True,
        contention: bool = True,
        symmetry: Symmetry | None = None,
        deadline: float | None = None,
    ):
        self.lengths = task.lengths
        # Both reason about STRIPS steps (fixed effects, agent copies apart): a general
        # task keeps the longest remaining plan alone, which stays admissible.
        pairs = pairs and task.simple
        contention = contention and task.simple
        self.contention = ContentionBound(task) if contention else None
        self.pairs = interacting_pairs(task, symmetry=symmetry, deadline=deadline) if pairs else []
        # contact_until[a]: past this index agent a touches no fact another agent touches.
        # A pair with such an agent is past its last contact, where its projection is the
        # longer remaining plan (no more than the first part of the bound): skipped.
        self.contact_until = []
        touched = task.touched
        for agent, plan in enumerate(task.steps):
            others = 0
            for other, facts in enumerate(touched):
                if other != agent:
                    others |= facts
            last = [k for k, step in enumerate(plan) if step.touched & others]
            self.contact_until.append(last[-1] + 1 if last else 0)

    def __call__(self, indices: Sequence[int], state: int) -> int | None:
        bound = max((n - i for n, i in zip(self.lengths, indices, strict=True)), default=0)
        if self.contention is not None:
            bound = max(bound, self.contention(indices, state))
        until = self.contact_until
        for pair, first, second in self.pairs:
            k, m = indices[first], indices[second]
            if k >= until[first] or m >= until[second]:
                continue
            steps = pair.at(k, m, state)
            if steps is None:
                return None
            bound = max(bound, steps)
        return bound
