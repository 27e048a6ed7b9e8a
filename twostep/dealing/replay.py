"""The agents' plans in plan-deal when the time steps fail (step 3's fallback,
:mod:`~twostep.dealing.timeline`): the dealt pieces replayed one after the other.

The pieces are replayed in the order of their start times (a linearisation the plan's
order allows). Before each action its agent walks, where needed, to a place where the
action applies (:class:`~twostep.dealing.walks.Walker`). A piece whose agent cannot get
there yet *waits*: the next piece the order allows goes first. When no waiting piece can
go, the first one is *handed* to another agent that can reach it (the least busy first).
When the SA plan's walks reached goal facts themselves, an agent walks there at the end
(:func:`~twostep.dealing.walks.closing_walk`). The replay is a sequential run of all
agents' plans, checked step by step; its time steps
come from :func:`~twostep.dealing.timeline.earliest_steps`.
"""

from __future__ import annotations

from collections.abc import Sequence

from twostep.dealing.cleanup import JointRun
from twostep.dealing.encoding import GoalBits, Owns, Step
from twostep.dealing.model import DealError
from twostep.dealing.walks import Walker, closing_walk


def replay_piece(
    walker: Walker, piece: Sequence[int], steps: Sequence[Step], env: int, own: int
) -> tuple[list[Step], int, int]:
    """One agent runs one piece, walking before an action where needed: its steps and the
    state after them (raise :class:`DealError`)."""
    done: list[Step] = []
    for i in piece:
        step = steps[i]
        if not step.applicable(env, own):
            for move in walker.walk_to(env, own, step):
                env, own = move.apply(env, own)
                done.append(move)
        env, own = step.apply(env, own)
        done.append(step)
    return done, env, own


class Replay:
    """Step 3 for one deal: pieces, their order and owners in, the joint run out."""

    def __init__(
        self,
        walker: Walker,
        steps: Sequence[Step],
        pieces: Sequence[Sequence[int]],
        preds: Sequence[set[int]],
        goal: GoalBits,
        start: tuple[int, int],
    ) -> None:
        self.walker, self.steps, self.pieces, self.preds = walker, steps, pieces, preds
        self.goal = goal
        self.start = start

    def run(
        self, owner: Sequence[int], start: Sequence[int], agents: int
    ) -> tuple[JointRun, list[int]]:
        """The joint run of the dealt pieces (module docstring); :class:`DealError` when no
        piece can go on or the goal is missed."""
        owner = list(owner)
        pending = sorted(range(len(self.pieces)), key=lambda p: (start[p], p))
        env, own0 = self.start
        owns: Owns = (own0,) * agents
        load = [0] * agents  # actions each agent has so far
        done: set[int] = set()
        joint: JointRun = []
        while pending:
            ready = [p for p in pending if self.preds[p] <= done]
            found = self._first(ready, owner, env, owns) or self._handed(ready, load, env, owns)
            if found is None:
                raise DealError(f"piece {ready[0] if ready else pending[0]}: no agent can "
                                "walk to where it applies")  # fmt: skip
            p, agent, path, env, own = found
            owner[p] = agent
            joint.extend((agent, step) for step in path)
            owns = (*owns[:agent], own, *owns[agent + 1 :])
            load[agent] += len(path)
            pending.remove(p)
            done.add(p)
        if not self.goal.holds(env, owns):
            joint.extend(closing_walk(self.walker, self.goal, env, owns, load))
        return joint, owner

    def _try(
        self, p: int, agent: int, env: int, owns: Owns
    ) -> tuple[int, int, list[Step], int, int] | None:
        try:
            path, env, own = replay_piece(self.walker, self.pieces[p], self.steps, env, owns[agent])
        except DealError:
            return None
        return p, agent, path, env, own

    def _first(
        self, ready: Sequence[int], owner: Sequence[int], env: int, owns: Owns
    ) -> tuple[int, int, list[Step], int, int] | None:
        """The first ready piece its own agent can replay (the others wait)."""
        for p in ready:
            found = self._try(p, owner[p], env, owns)
            if found is not None:
                return found
        return None

    def _handed(
        self, ready: Sequence[int], load: Sequence[int], env: int, owns: Owns
    ) -> tuple[int, int, list[Step], int, int] | None:
        """The first ready piece another agent can replay, the least busy agent first."""
        agents = sorted(range(len(load)), key=lambda a: (load[a], a))
        for p in ready:
            for agent in agents:
                found = self._try(p, agent, env, owns)
                if found is not None:
                    return found
        return None

    def in_plan_order(self, owner: Sequence[int], agents: int, walking: Sequence[bool]) -> JointRun:
        """The plan's own run, action by action in its order, each acting action by the
        agent that owns its piece, walking first where needed; the plan's own walks are the
        first agent's. With every piece the first agent's this is the plan itself, walks
        and all: the start :meth:`~twostep.dealing.deal.Dealer.offload` falls back on when
        replaying whole pieces gets stuck (a hoist that must pass while another lifts the
        crate in its way, in the middle of that piece). :class:`DealError` when an agent
        cannot walk to where its action applies or the goal is missed."""
        piece_of = {i: p for p, piece in enumerate(self.pieces) for i in piece}
        env, own0 = self.start
        owns = [own0] * agents
        load = [0] * agents
        joint: JointRun = []
        for i, step in enumerate(self.steps):
            if walking[i]:  # the plan's own walk, by the first agent, where it still applies
                if step.applicable(env, owns[0]):
                    env, owns[0] = step.apply(env, owns[0])
                    joint.append((0, step))
                    load[0] += 1
                continue
            if i not in piece_of:
                continue
            a = owner[piece_of[i]]
            if not step.applicable(env, owns[a]):
                for move in self.walker.walk_to(env, owns[a], step):
                    env, owns[a] = move.apply(env, owns[a])
                    joint.append((a, move))
                    load[a] += 1
            env, owns[a] = step.apply(env, owns[a])
            joint.append((a, step))
            load[a] += 1
        if not self.goal.holds(env, owns):
            joint.extend(closing_walk(self.walker, self.goal, env, owns, load))
        return joint
