"""Dealing in plan-deal (step 2): list scheduling of the SA plan's pieces on N agents, at
the grain of actions, without TwoStep's hand-off constraint.

Ready pieces go one by one to the agent on which they end earliest. A piece may start
before its predecessor pieces end, as long as each of its actions ends after the actions
it needs (an agent fetches a block while another places the one before). An action takes
one step plus the walking before it in the SA plan; a piece's first action takes instead
the walk from where its agent will stand (:class:`WalkEstimate`). Ready pieces are taken
by their longest path to the end of the plan (``order="critical"``, HLFET: chains that
gate the most work start first) or in the SA plan's order (``order="plan"``); ties go to
an agent that made a predecessor piece. Any assignment is allowed, since no agent waits
for another to be *planned*.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass

from twostep.dealing.encoding import Step
from twostep.dealing.model import DealError
from twostep.dealing.walks import Walker

State = tuple[int, int]  # one agent's state: environment bits, own bits


@dataclass
class PieceOrder:
    """The order between pieces that the plan's order edges imply."""

    preds: list[set[int]]  # per piece: the pieces it needs
    succs: list[set[int]]  # per piece: the pieces that need it
    action_preds: dict[int, list[int]]  # per action: the actions of other pieces it needs

    @classmethod
    def of(cls, pieces: Sequence[Sequence[int]], edges: set[tuple[int, int]]) -> PieceOrder:
        piece_of = {i: p for p, members in enumerate(pieces) for i in members}
        preds: list[set[int]] = [set() for _ in pieces]
        action_preds: dict[int, list[int]] = defaultdict(list)
        for i, j in edges:
            if i in piece_of and j in piece_of and piece_of[i] != piece_of[j]:
                preds[piece_of[j]].add(piece_of[i])
                action_preds[j].append(i)
        succs: list[set[int]] = [set() for _ in pieces]
        for p, before in enumerate(preds):
            for q in before:
                succs[q].add(p)
        return cls(preds, succs, action_preds)


class WalkEstimate:
    """How far an agent walks to an action of the SA plan: from where it will stand, in
    the environment the SA plan has there (cached per place and action)."""

    def __init__(self, walker: Walker, steps: Sequence[Step], states: Sequence[State]) -> None:
        self.walker = walker
        self.steps = steps
        self.envs = [env for env, _ in states]
        where = walker.space.where
        # where the agent stands in each state of the SA plan, and what else it has
        self.standing = [own & where for _, own in states]
        self.resting = states[0][1] & ~where
        self._lengths: dict[tuple[int, int], int] = {}

    def length(self, position: int, i: int, default: int) -> int:
        """Walking steps from ``position`` to where action ``i`` applies (``default``: none)."""
        key = (position, i)
        found = self._lengths.get(key)
        if found is None:
            try:
                walk = self.walker.walk_to(self.envs[i], position | self.resting, self.steps[i])
                found = len(walk)
            except DealError:
                found = default
            self._lengths[key] = found
        return found


@dataclass
class Schedule:
    """The list schedule: each piece's agent and start time, and the makespan."""

    owner: list[int]
    start: list[int]
    makespan: int
    level: list[int]  # per piece: its longest path to the end of the plan, itself included


class ListScheduler:
    """Step 2 (module docstring) for one set of pieces and ``agents`` agents."""

    def __init__(
        self,
        pieces: Sequence[Sequence[int]],
        order: PieceOrder,
        walk_before: dict[int, int],
        walks: WalkEstimate,
        agents: int,
    ) -> None:
        self.pieces, self.order, self.walk_before, self.walks = pieces, order, walk_before, walks
        self.owner = [0] * len(pieces)
        self.start = [0] * len(pieces)
        self.done_at: dict[int, int] = {}  # action index -> the time step it ends
        self.free_at = [0] * agents
        self.at = [walks.standing[0]] * agents  # where each agent will stand

    def levels(self) -> list[int]:
        """Each piece's longest path to the end of the plan, itself included."""
        length = [sum(self.walk_before[i] + 1 for i in piece) for piece in self.pieces]
        level = [0] * len(self.pieces)
        for p in reversed(range(len(self.pieces))):  # pieces come in a topological order
            level[p] = length[p] + max((level[q] for q in self.order.succs[p]), default=0)
        return level

    def timing(self, agent: int, piece: Sequence[int]) -> tuple[int, list[int]]:
        """When ``agent`` could start the piece, and when each action would end (counted
        from the piece's start)."""
        offsets: list[int] = []
        elapsed = 0
        for k, i in enumerate(piece):
            walk = self.walk_before[i]
            if k == 0:  # from where the agent will stand, in the SA plan's environment
                walk = self.walks.length(self.at[agent], i, walk)
            elapsed += walk + 1
            offsets.append(elapsed)
        ready = max(
            (self.done_at[q] - offset + 1 for i, offset in zip(piece, offsets, strict=True)
             for q in self.order.action_preds[i]),
            default=0,
        )  # fmt: skip
        return max(ready, self.free_at[agent], 0), offsets

    def place(self, p: int) -> None:
        """Give piece ``p`` to the agent on which it ends earliest (ties: an agent that made
        a predecessor piece, then the one with the shortest walk to it, then the idlest,
        then the first)."""
        piece = self.pieces[p]
        timings = [self.timing(a, piece) for a in range(len(self.free_at))]
        best = min(
            range(len(self.free_at)),
            key=lambda a: (
                timings[a][0] + timings[a][1][-1],
                -sum(self.owner[q] == a for q in self.order.preds[p]),
                timings[a][1][0],
                self.free_at[a],
                a,
            ),
        )
        self.owner[p] = best
        self.start[p], offsets = timings[best]
        for i, offset in zip(piece, offsets, strict=True):
            self.done_at[i] = self.start[p] + offset
        self.free_at[best] = self.start[p] + offsets[-1]
        self.at[best] = self.walks.standing[piece[-1] + 1]

    def run(self, order: str) -> Schedule:
        """Place every piece, ready pieces by ``order`` (``"critical"`` or ``"plan"``)."""
        level = self.levels()
        waiting = [len(before) for before in self.order.preds]
        ready = [p for p in range(len(self.pieces)) if not waiting[p]]
        while ready:
            p = min(ready, key=lambda q: (-level[q], q) if order == "critical" else (q,))
            ready.remove(p)
            self.place(p)
            for q in self.order.succs[p]:
                waiting[q] -= 1
                if not waiting[q]:
                    ready.append(q)
        return Schedule(self.owner, self.start, max(self.free_at, default=0), level)
