"""The dealt pieces run in time steps (step 3): every agent acts at once, as in the
parallel schedule, so the walks an agent takes are found in the environment it meets then.

At each time step, in the order of their pieces' longest paths to the end (the critical
piece first), each agent takes its next action: the next action of its current piece when
it applies and every action it needs from other pieces (the plan's order) is done, else a
step of the shortest walk to where it applies (:class:`~twostep.dealing.walks.Walker`),
else, where no move changes a shared fact, a step of its shortest walk to where it stands
for the action (*walking ahead*: a termes robot with a block for a ramp not yet built
waits beside the ramp, not on the depot), else it waits. An agent without a piece takes
its next one in the deal; one that begins a piece whose first action does not apply where
it stands may do a *copy* of it instead, the same actions by another of its own robots
that stands there
(:mod:`~twostep.dealing.copies`). Actions of one time step are applicable before it and
interfere with none another agent took in it (the scorer's rule: none deletes what another
needs or adds, none adds what another needs false), so the time steps are a valid joint
schedule and, one after the other, a valid run. Walking needs no order: an agent may walk
to its next piece while another finishes the piece before.

When no agent can act, the first piece whose agent cannot reach it is *handed* to an agent
that can (an idle one, the least busy first); when there is none, the deal fails
(:class:`~twostep.dealing.model.DealError`). When the SA plan's walks reached goal facts
themselves, an agent walks there after the last piece (:func:`~twostep.dealing.walks.closing_walk`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from twostep.dealing.copies import carries_through
from twostep.dealing.encoding import GoalBits, Step
from twostep.dealing.model import DealError
from twostep.dealing.walks import Walker, closing_walk

JointSteps = list[list[tuple[int, Step]]]
"""Per time step: the (agent, step) pairs that act in it."""


@dataclass
class _Agent:
    """One agent during the run: its pieces still to do, and where it is in the current."""

    queue: list[int]  # pieces, in the order it takes them
    piece: int | None = None
    position: int = 0  # index of the next action in the current piece
    path: list[Step] = field(default_factory=list)  # the walk it is on
    ahead: bool = False  # the walk goes where the action's own facts hold, not where it applies
    busy: int = 0  # actions taken so far


class Timeline:
    """Step 3 for one deal (module docstring)."""

    def __init__(
        self,
        walker: Walker,
        steps: Sequence[Step],
        pieces: Sequence[Sequence[int]],
        action_preds: dict[int, list[int]],
        goal: GoalBits,
        start: tuple[int, int],
        copies: dict[int, list[list[Step]]] | None = None,
        walks_ahead: bool = True,
    ) -> None:
        self.walker, self.steps, self.pieces = walker, steps, pieces
        self.action_preds = action_preds
        self.goal = goal
        self.start = start
        self.copies = copies or {}
        """Per piece, the same piece done with another of the agent's movers
        (:mod:`~twostep.dealing.copies`)."""
        self.piece_of = {i: p for p in self.copies for i in pieces[p]}
        self.walks_ahead = walks_ahead and not (walker.adds_env or walker.dels_env)
        """Whether agents walk ahead (module docstring): asked, and no move changes a
        shared fact (a storage hoist walking ahead would stand in another's way)."""
        self.work = 0  # what the runs so far cost, as a count (:attr:`_Run.work`)

    def run(
        self,
        owner: Sequence[int],
        start: Sequence[int],
        level: Sequence[int],
        agents: int,
        steal: bool = True,
    ) -> tuple[JointSteps, list[int]]:
        """The time steps, and each piece's agent (module docstring); ``steal``: an idle
        agent may take a piece dealt to another."""
        run = _Run(self, owner, start, level, agents, steal)
        try:
            return run.run()
        finally:
            self.work += run.work


class _Run:
    """One run of a :class:`Timeline`: the agents, the state and what is done."""

    def __init__(
        self,
        timeline: Timeline,
        owner: Sequence[int],
        start: Sequence[int],
        level: Sequence[int],
        agents: int,
        steal: bool,
    ) -> None:
        self.steal = steal
        self.walker, self.steps = timeline.walker, timeline.steps
        self.pieces, self.action_preds = timeline.pieces, timeline.action_preds
        self.goal = timeline.goal
        self.copies, self.piece_of = timeline.copies, timeline.piece_of
        self.chosen: dict[int, tuple[int, list[Step]]] = {}  # piece -> (agent, its copy)
        self.owner, self.level = list(owner), level
        order = sorted(range(len(self.pieces)), key=lambda p: (start[p], p))
        self.crew = [_Agent([p for p in order if owner[p] == a]) for a in range(agents)]
        self.env, own = timeline.start
        self.owns = [own] * agents
        self.done: dict[int, int] = {}  # acting action -> the time step it was taken in
        self._paths: dict[tuple[int, int, int, Step], list[Step] | None] = {}
        self._aheads: dict[tuple[int, int, int], list[Step]] = {}
        self.walks_ahead = timeline.walks_ahead
        self.work = 0  # agents' turns, and pieces looked at when an idle agent looks for one

    def run(self) -> tuple[JointSteps, list[int]]:
        crew = self.crew
        timeline: JointSteps = []
        left = sum(len(piece) for piece in self.pieces)
        limit = 10 * len(self.steps) + 100  # time steps: beyond, agents only go round
        while left:
            if len(timeline) > limit:
                raise DealError(f"no end after {limit} time steps")
            for agent in crew:
                if agent.piece is None and agent.queue:
                    agent.piece, agent.position, agent.path = agent.queue.pop(0), 0, []
            taken: list[tuple[int, Step]] = []
            idle = []
            self.work += len(crew)
            for a in sorted(range(len(crew)), key=self._rank):
                step = self._next(a)
                if step is None:
                    idle.append(a)
                elif not any(_interfere(step, other) for _, other in taken):
                    taken.append((a, step))
            for a in idle if self.steal else ():  # take a ready piece another has not begun
                if self._steal(a):
                    step = self._next(a)
                    if step is not None and not any(_interfere(step, o) for _, o in taken):
                        taken.append((a, step))
            if not taken:
                self._hand_over()
                continue
            for a, step in taken:
                left -= self._take(a, step, len(timeline))
            timeline.append(taken)
        if not self.goal.holds(self.env, self.owns):
            busy = [agent.busy for agent in crew]
            for a, step in closing_walk(self.walker, self.goal, self.env, self.owns, busy):
                self.env, self.owns[a] = step.apply(self.env, self.owns[a])
                timeline.append([(a, step)])
        return timeline, self.owner

    def _take(self, a: int, step: Step, now: int) -> int:
        """Agent ``a`` takes ``step``; 1 when it was an action of its piece, 0 a walk."""
        self.env, self.owns[a] = step.apply(self.env, self.owns[a])
        agent = self.crew[a]
        agent.busy += 1
        if agent.path and agent.path[0] is step:
            agent.path.pop(0)
            agent.ahead = agent.ahead and bool(agent.path)
            return 0
        assert agent.piece is not None
        self.done[self.pieces[agent.piece][agent.position]] = now
        agent.position += 1
        agent.path = []
        if agent.position == len(self.pieces[agent.piece]):
            agent.piece = None
        return 1

    def _rank(self, a: int) -> tuple[int, int]:
        piece = self.crew[a].piece
        return (-self.level[piece] if piece is not None else 1, a)

    def _ready(self, i: int) -> bool:
        """Every action of other pieces that ``i`` needs was done in an earlier step."""
        return all(j in self.done for j in self.action_preds.get(i, ()))

    def _next(self, a: int) -> Step | None:
        """Agent ``a``'s action in this time step (module docstring), or None: it waits."""
        agent, env, own = self.crew[a], self.env, self.owns[a]
        if agent.piece is None:
            return None
        i = self.pieces[agent.piece][agent.position]
        step = self.steps[i]
        if agent.piece in self.copies:  # the piece, or the copy its agent took
            if agent.position == 0:
                self._choose(a, agent.piece)
            step = self._step(a, agent.piece, agent.position)
        if step.applicable(env, own):
            agent.path = []
            return step if self._ready(i) else None
        if agent.ahead or not (agent.path and agent.path[0].applicable(env, own)):
            agent.path, agent.ahead = list(self._path(own, i, step) or ()), False
            if not agent.path and self.walks_ahead:
                agent.path, agent.ahead = self._ahead(own, step), True
        return agent.path[0] if agent.path else None

    def _ahead(self, own: int, step: Step) -> list[Step]:
        """The shortest walk from ``own`` to where the agent stands as ``step`` needs
        (empty: it stands there, or no walk goes there now); remembered like :meth:`_path`."""
        want = step.pre_own & self.walker.space.where
        if not step.exact or own & want == want:
            return []
        key = (self.env, own, want)
        if key not in self._aheads:
            try:
                self._aheads[key] = self.walker.walk_until(
                    self.env, own, lambda _, own: own & want == want
                )
            except DealError:
                self._aheads[key] = []
        return list(self._aheads[key])

    def _step(self, a: int, p: int, position: int) -> Step:
        """The action at ``position`` of piece ``p`` as agent ``a`` does it: of the copy
        it took, if any."""
        chosen = self.chosen.get(p)
        if chosen is not None and chosen[0] == a:
            return chosen[1][position]
        return self.steps[self.pieces[p][position]]

    def _copy(self, a: int, p: int) -> list[Step] | None:
        """The first copy of piece ``p`` that agent ``a`` can begin where it stands and
        carry through (None: none); asked only where the piece itself does not apply."""
        env, own = self.env, self.owns[a]
        where = self.walker.space.where
        for copy in self.copies.get(p, ()):
            if copy[0].applicable(env, own) and carries_through(own, copy, where):
                return copy
        return None

    def _choose(self, a: int, p: int) -> None:
        """Agent ``a``, about to begin piece ``p``: the piece itself where it applies, else
        a copy it can begin where it stands (:meth:`_copy`), else the piece itself unless
        the agent is on its way to a copy."""
        if self.steps[self.pieces[p][0]].applicable(self.env, self.owns[a]):
            self.chosen.pop(p, None)
        elif (copy := self._copy(a, p)) is not None:
            self.chosen[p] = (a, copy)
        elif self.chosen.get(p, (a,))[0] != a:
            del self.chosen[p]

    def _path(self, own: int, i: int, step: Step) -> list[Step] | None:
        """The shortest walk from ``own`` to where ``step`` (action ``i`` or its copy)
        applies in the current environment (None: none now); remembered, since waiting
        agents ask every step."""
        key = (self.env, own, i, step)
        if key not in self._paths:
            try:
                self._paths[key] = self.walker.walk_to(self.env, own, step)
            except DealError:
                self._paths[key] = None
        return self._paths[key]

    def _free(self, a: int) -> bool:
        """Agent ``a`` holds nothing of a piece: none, or one not begun."""
        agent = self.crew[a]
        return agent.piece is None or agent.position == 0

    def _walk(self, a: int, i: int) -> int | None:
        """Agent ``a``'s walk to where action ``i`` applies (None: no way there now)."""
        if self.steps[i].applicable(self.env, self.owns[a]):
            return 0
        if self.copies:
            p = self.piece_of.get(i)
            if p is not None and self.pieces[p][0] == i and self._copy(a, p) is not None:
                return 0
        path = self._path(self.owns[a], i, self.steps[i])
        return None if path is None else len(path)

    def _give(self, p: int, b: int) -> None:
        """Piece ``p`` (not begun) becomes agent ``b``'s current piece."""
        for agent in self.crew:
            if agent.piece == p:
                agent.piece, agent.path = None, []
            elif p in agent.queue:
                agent.queue.remove(p)
        taker = self.crew[b]
        if taker.piece is not None:
            taker.queue.insert(0, taker.piece)
        taker.piece, taker.position, taker.path = p, 0, []
        self.owner[p] = b

    def _wait(self, i: int) -> int:
        """About how many time steps action ``i`` waits for the actions it needs: the
        actions still ahead of them in their agents' work."""
        missing = {j for j in self.action_preds.get(i, ()) if j not in self.done}
        wait = 0
        for agent in self.crew:
            ahead = 0
            self.work += len(agent.queue)
            work = [] if agent.piece is None else [self.pieces[agent.piece][agent.position :]]
            for piece in [*work, *(self.pieces[p] for p in agent.queue)]:
                for j in piece:
                    ahead += 1
                    if j in missing:
                        wait = max(wait, ahead)
        return wait

    def _steal(self, a: int) -> bool:
        """Idle agent ``a`` takes the most critical ready piece that it can walk to and end
        before its own current piece can start, and that its agent would not reach sooner
        (its own queued pieces first)."""
        if not self._free(a):
            return False
        mine = self.crew[a].piece
        spare = None if mine is None else self._wait(self.pieces[mine][0])
        offers = []
        for b, agent in enumerate(self.crew):
            backlog = 0 if agent.piece is None else len(self.pieces[agent.piece]) - agent.position
            self.work += len(agent.queue)
            for p in agent.queue:
                if p != mine and self._ready(self.pieces[p][0]):
                    offers.append((b != a, -self.level[p], p, backlog))
                backlog += len(self.pieces[p])
        for other, _, p, backlog in sorted(offers):
            if spare is not None and len(self.pieces[p]) > spare:
                continue
            walk = self._walk(a, self.pieces[p][0])
            if walk is None or (other and walk >= backlog):
                continue
            if spare is not None and walk + len(self.pieces[p]) > spare:
                continue
            self._give(p, a)
            return True
        return False

    def _hand_over(self) -> None:
        """Nobody can act: give the most critical piece that is ready but not begun to an
        agent that can reach it and has not begun its own (the least busy first)."""
        crew = self.crew
        waiting = [p for agent in crew for p in agent.queue]
        waiting += [
            agent.piece for agent in crew if agent.piece is not None and agent.position == 0
        ]
        free = sorted((b for b in range(len(crew)) if self._free(b)),
                      key=lambda b: (crew[b].busy, b))  # fmt: skip
        for p in sorted(waiting, key=lambda p: (-self.level[p], p)):
            first = self.pieces[p][0]
            if not self._ready(first):
                continue
            for b in free:
                if self.owner[p] != b and self._walk(b, first) is not None:
                    self._give(p, b)
                    return
        raise DealError("no agent can walk to where the next piece applies")


def _interfere(one: Step, other: Step) -> bool:
    """The scorer's rule: one deletes what the other needs or adds, or adds what it needs
    false (environment facts; each agent's own facts are its own)."""
    return bool(
        one.del_env & (other.pre_env | other.add_env)
        | other.del_env & (one.pre_env | one.add_env)
        | one.add_env & other.neg_env
        | other.add_env & one.neg_env
    )


def earliest_steps(joint: Sequence[tuple[int, Step]], agents: int) -> JointSteps:
    """The time steps of a valid run of several agents, each action as early as the run
    allows: after its agent's previous action and after every earlier action of the run
    that it interferes with or that sets what it needs (so it meets the facts it met in the
    run). Never longer than the run's own time steps, once actions are dropped from it."""
    last = [-1] * agents
    timeline: JointSteps = []
    marks: list[list[int]] = []  # per time step: facts its actions need, forbid, add, delete
    for a, step in joint:
        reads = step.pre_env | step.neg_env
        t = len(timeline) - 1
        while t > last[a]:
            needs, forbids, adds, deletes = marks[t]
            if (
                adds & reads
                | deletes & (reads | step.add_env)
                | step.del_env & (needs | adds)
                | step.add_env & forbids
            ):
                break
            t -= 1
        t = max(t, last[a]) + 1
        if t == len(timeline):
            timeline.append([])
            marks.append([0, 0, 0, 0])
        timeline[t].append((a, step))
        mark = marks[t]
        mark[0] |= step.pre_env
        mark[1] |= step.neg_env
        mark[2] |= step.add_env
        mark[3] |= step.del_env
        last[a] = t
    return timeline
