"""Deals of one SA plan to N agents: steps 0-4 of :mod:`twostep.dealing`, in order.

A :class:`Dealer` does once what every deal of the plan shares: it cleans the plan
(:mod:`~twostep.dealing.cleanup`), finds the order the plan needs and its pieces per cut
(:func:`order_edges`, :func:`pieces_of`), and keeps the walks it has searched. Each
:meth:`Dealer.deal` then deals the pieces to k agents (:mod:`~twostep.dealing.schedule`),
replays them (:mod:`~twostep.dealing.replay`) and cleans the joint run again.
:attr:`Dealer.seconds` says where the time went.
"""

from __future__ import annotations

import bisect
import functools
from collections import defaultdict
from collections.abc import Callable, Collection, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from itertools import pairwise

from twostep.dealing.cleanup import Elimination, JointRun
from twostep.dealing.copies import mover_pieces, piece_copies, task_movers
from twostep.dealing.encoding import Step
from twostep.dealing.improve import search_owners, work_bound
from twostep.dealing.model import Deal, DealError, SearchKey, cpu_seconds
from twostep.dealing.replay import Replay
from twostep.dealing.schedule import ListScheduler, PieceOrder, Schedule, WalkEstimate
from twostep.dealing.timeline import JointSteps, Timeline, earliest_steps
from twostep.dealing.walks import Walker, is_walking, walking_space
from twostep.decomposers.plan_split import (
    free_pieces,
    free_states,
    holding_pieces,
    merge_cycles,
    plan_order,
    topological_pieces,
)
from twostep.pddl import Problem
from twostep.plans.simulate import GroundAction, Grounder, effects_along

CUTS = ("free", "holding", "mover")
"""Where the plan is cut into pieces: at free agent states, by what the agent holds, or
at each mover's free states (:func:`~twostep.dealing.copies.mover_pieces`; the free cut
where the task has no movers)."""
ORDERS = ("critical", "plan")
"""Which ready piece is dealt next: the longest path to the end first, or the plan's order."""


@dataclass(frozen=True)
class Way:
    """One way to deal: the cut, the order, and whether idle agents take pieces dealt to
    others while the agents act (:mod:`~twostep.dealing.timeline`)."""

    cut: str
    order: str
    steal: bool


def ways(cut: str | None = None) -> tuple[Way, ...]:
    """The ways :mod:`twostep.methods.plan_deal` tries, of one cut or (None) of every cut:
    on the 100 tasks the first three do as well as all eight free and holding cuts x
    orders x stealing together, but for 0.001 of the macro exec/SA at N = 4
    (``bench/bench_dealing.py``); the fourth, the mover cut, is dealt only where its pieces
    are not the free cut's (robots that work at once in the SA plan)."""
    return (
        Way(cut or "free", "critical", False),
        Way(cut or "holding", "critical", True),
        Way(cut or "holding", "plan", False),
        Way(cut or "mover", "critical", False),
    )


PHASES = ("clean-up", "order", "dealing", "walks", "replay", "joint clean-up", "owner search")
"""Where :class:`Dealer` spends its time (:attr:`Dealer.seconds`); walks are the walking
searches of dealing, replay and the owner search, counted apart from them."""


def order_edges(
    problem: Problem,
    grounded: Sequence[GroundAction],
    walking: Sequence[bool],
    agent_predicates: Collection[str],
    keep_walks: bool,
) -> set[tuple[int, int]]:
    """Step 1's order between the acting actions (indices into ``grounded``).

    Walking is left out (it is found again at replay); with ``keep_walks`` the walks'
    own causal links are kept instead, each walk standing for the acting action it leads
    to (or, after the last one, the action before it)."""
    acting = [i for i in range(len(grounded)) if not walking[i]]
    if not keep_walks:
        # the acting actions' effects as they fire in the whole plan: without the walks
        # between them they need not apply from the initial state (a lift's stop at a
        # floor it has not driven to), and conditional effects depend on where they run
        fired = effects_along(problem.init, grounded)
        sub_edges, _ = plan_order(
            problem, [grounded[i] for i in acting], agent_predicates, [fired[i] for i in acting]
        )
        return {(acting[i], acting[j]) for i, j in sub_edges}
    edges_all, _ = plan_order(problem, grounded, agent_predicates)
    leads = {}
    for i in range(len(grounded)):
        k = bisect.bisect_left(acting, i)  # the first acting action from i on
        leads[i] = acting[k] if k < len(acting) else (acting[-1] if acting else i)
    return {(leads[i], leads[j]) for i, j in edges_all if leads[i] != leads[j]}


def pieces_of(
    problem: Problem,
    grounded: Sequence[GroundAction],
    agent_predicates: Collection[str],
    edges: set[tuple[int, int]],
    cut: str,
    moving: frozenset[str] | None = None,
) -> list[list[int]]:
    """Step 1's pieces (plan-split's step 2), in an order the deordering allows
    (``moving``: the task's movers, when the caller has them)."""
    by_mover = None
    if cut == "mover":
        by_mover = mover_pieces(problem, grounded, agent_predicates, moving)
    if cut == "holding":
        free_states(problem, grounded, agent_predicates)  # the plan must be applicable
        pieces = merge_cycles(holding_pieces(problem, grounded, agent_predicates), edges)
    elif by_mover is not None:
        pieces = merge_cycles(by_mover, edges)
    else:
        pieces = free_pieces(problem, grounded, agent_predicates)
    return topological_pieces(pieces, edges)


def walks_before(walking: Sequence[bool]) -> dict[int, int]:
    """Per acting action: the walking actions just before it in the SA plan."""
    counts = {}
    for i in (i for i in range(len(walking)) if not walking[i]):
        j = i - 1
        while j >= 0 and walking[j]:
            j -= 1
        counts[i] = i - 1 - j
    return counts


class Dealer:
    """Every deal of one SA plan (module docstring); ``cleaned`` is step 0's result when
    the caller has it; ``copies``: agents may do a piece with another of their movers
    (:mod:`~twostep.dealing.copies`); ``walks_ahead``: an agent whose next action cannot
    apply yet walks to where it will (:mod:`~twostep.dealing.timeline`)."""

    def __init__(
        self,
        problem: Problem,
        plan: Sequence[str],
        agent_predicates: Collection[str],
        cleaned: Sequence[GroundAction] | None = None,
        copies: bool = True,
        walks_ahead: bool = True,
    ) -> None:
        self.problem = problem
        self.use_copies, self.walks_ahead = copies, walks_ahead
        self.agent_predicates = tuple(agent_predicates)
        self.seconds: defaultdict[str, float] = defaultdict(float)
        start = cpu_seconds()
        self.space = walking_space(problem, agent_predicates)
        grounded = Grounder(problem).ground_plan(plan)
        self.init = self.space.bits(problem.init)
        self.goal = self.space.goal()
        if cleaned is None:
            single = [(0, s) for s in self.space.steps(grounded)]
            run = Elimination(self.goal, self.init[0], (self.init[1],), single).run()
            cleaned = [step.action for _, step in run]
        self.cleaned = list(cleaned)
        self.steps = self.space.steps(self.cleaned)
        self.seconds["clean-up"] = cpu_seconds() - start
        self.walking = [is_walking(s, self.space) for s in self.steps]
        self.states = [self.init]
        for step in self.steps:
            self.states.append(step.apply(*self.states[-1]))
        universe = problem.init.union(*(a.possible_add for a in grounded))
        self.walker = Walker(problem, self.space, universe)
        self.estimate = WalkEstimate(self.walker, self.steps, self.states)
        self.cleanup_work = 0  # what the joint clean-ups cost, as a count (Elimination.work)
        self._orders: dict[tuple[str, bool], tuple[list[list[int]], PieceOrder]] = {}
        self._schedules: dict[tuple[int, str, str, bool], Schedule] = {}
        self._deals: dict[tuple[object, ...], Deal | DealError] = {}
        self._copies: dict[tuple[str, bool], dict[int, list[list[Step]]]] = {}
        # per owner search: its walks' links, the owners found, the list schedule it ran
        # with (its number of agents)
        self._found: dict[SearchKey, tuple[bool, list[int], int]] = {}
        self._timelines: list[Timeline] = []  # every run in time steps made (their work)

    @property
    def work(self) -> int:
        """What this dealer's deals and searches have cost so far, in their own counts: the
        runs in time steps (agents' turns), the walks' searches and the clean-ups (actions
        simulated); the unit of plan-deal's budget (:mod:`twostep.methods.plan_deal`)."""
        timelines = sum(timeline.work for timeline in self._timelines)
        return timelines + self.walker.work + self.cleanup_work

    @contextmanager
    def _phase(self, name: str) -> Iterator[None]:
        start = cpu_seconds()
        walking = self.walker.search_s
        try:
            yield
        finally:  # the walks searched meanwhile count as walks, not as this phase
            walked = self.walker.search_s - walking
            self.seconds[name] += cpu_seconds() - start - walked
            self.seconds["walks"] += walked

    def pieces(self, cut: str, keep_walks: bool) -> tuple[list[list[int]], PieceOrder]:
        """Step 1 for one cut: the acting pieces and their order (cached)."""
        key = (cut, keep_walks)
        if key not in self._orders:
            with self._phase("order"):
                preds = self.agent_predicates
                edges = order_edges(self.problem, self.cleaned, self.walking, preds, keep_walks)
                pieces = [[i for i in p if not self.walking[i]]
                          for p in pieces_of(self.problem, self.cleaned, preds, edges, cut,
                                             self.movers)]  # fmt: skip
                pieces = [p for p in pieces if p]
                self._orders[key] = (pieces, PieceOrder.of(pieces, edges))
        return self._orders[key]

    @functools.cached_property
    def movers(self) -> frozenset[str]:
        """The task's movers (:func:`~twostep.dealing.copies.task_movers`)."""
        return task_movers(self.problem, self.agent_predicates)

    def most_pieces(self, cuts: Collection[str]) -> int:
        """The most pieces any deal of these cuts has (with or without the walks' links):
        no deal keeps more agents busy, as each piece goes to one agent (0 when no cut
        can be made)."""
        most = 0
        for cut in cuts:
            for keep_walks in (False, True):
                try:
                    most = max(most, len(self.pieces(cut, keep_walks)[0]))
                except DealError:
                    continue
        return most

    def mover_cut_is_free(self) -> bool:
        """Whether the ``mover`` cut gives the ``free`` cut's pieces (a task without
        movers, or whose plan frees every mover before the next begins)."""
        return self.pieces("mover", False)[0] == self.pieces("free", False)[0]

    def chain(self, cut: str) -> int:
        """The longest chain of acting actions the order of step 1 (walks left out) and
        the pieces of ``cut`` impose, each action one time step: no run of these pieces
        in time steps is shorter."""
        pieces, piece_order = self.pieces(cut, keep_walks=False)
        after = {later: earlier for piece in pieces for earlier, later in pairwise(piece)}
        ends: dict[int, int] = {}
        for i in sorted(i for piece in pieces for i in piece):  # the order runs forward
            needs = [*piece_order.action_preds.get(i, ()), *([after[i]] if i in after else [])]
            ends[i] = 1 + max((ends[j] for j in needs), default=0)
        return max(ends.values(), default=0)

    def deal(
        self, agents: int, cut: str = "free", order: str = "critical", steal: bool = True
    ) -> Deal:
        """Steps 1-4 for ``agents`` agents. The order of step 1 leaves walking out; when
        the agents then find no way on (a ramp taken away before an agent crossed it), the
        deal is made again with the walks' own causal links kept (:func:`order_edges`); when
        that fails too, the pieces are replayed one after the other instead of in time steps
        (:mod:`~twostep.dealing.replay`), where a piece may wait for any other. When every
        replay is stuck (no agent can walk to a piece: the agents before it boxed the place
        in), the pieces are offloaded instead (:meth:`offload`)."""
        error = DealError("not dealt")
        for timed in (True, False):
            for keep_walks in (False, True):
                try:
                    return self._deal(agents, cut, order, keep_walks, timed and steal, timed)
                except DealError as failed:
                    error = failed
        try:
            return self.offload(agents, cut)
        except DealError:
            raise error from None

    def offload(self, agents: int, cut: str = "free") -> Deal:
        """The last resort of :meth:`deal`: every piece the first agent's, replayed in the
        plan's order (the SA plan's run, walks found again); then, piece by piece in that
        order, each other agent in turn takes the piece where the replay still works and
        the joint run gets shorter. A run of one agent when nothing gets shorter; made
        once per number of agents and cut (raise :class:`DealError` when even the first
        replay fails)."""
        return self._once(("offload", agents, cut), lambda: self._offload(agents, cut))

    def _offload(self, agents: int, cut: str) -> Deal:
        pieces, piece_order = self.pieces(cut, keep_walks=True)
        start = [min(piece) for piece in pieces]  # the plan's order
        replay = Replay(self.walker, self.steps, pieces, piece_order.preds, self.goal, self.init)
        owner = [0] * len(pieces)
        with self._phase("replay"):
            try:
                best, owner = self._replayed(replay, owner, start, agents)
                replayed = self._replayed
            except DealError:  # whole pieces get stuck: the plan's own run, action by action
                best, owner = self._in_plan_order(replay, owner, start, agents)
                replayed = self._in_plan_order
            length = len(earliest_steps(best, agents))
            for p in sorted(range(len(pieces)), key=lambda p: start[p]):
                for a in range(1, agents):
                    trial = [*owner[:p], a, *owner[p + 1 :]]
                    try:
                        run, got = replayed(replay, trial, start, agents)
                    except DealError:
                        continue
                    steps = len(earliest_steps(run, agents))
                    if steps < length:
                        best, owner, length = run, got, steps
                        break
        deal = self._finish(pieces, owner, start, best, agents, length)
        deal.offloaded = True
        return deal

    def improve(
        self,
        agents: int,
        cut: str = "free",
        order: str = "critical",
        steal: bool = True,
        after: SearchKey | None = None,
        limit: int | None = None,
    ) -> Deal:
        """The deal of :meth:`deal` in time steps (the order without walks; with the walks'
        own causal links kept when the agents find no way on without them, as :meth:`deal`
        does), its owners then searched for a shorter run (:mod:`~twostep.dealing.improve`,
        bounded by :func:`~twostep.dealing.improve.work_bound`); raise :class:`DealError`
        when both fail. With ``after`` (the :attr:`Deal.search` of an
        earlier search of this dealer, for fewer agents), the search starts instead from the
        owners that one found, the other agents idle. ``moves`` says how many pieces changed
        agent; made once per search. ``limit``: a lower bound on the search's work than
        :func:`~twostep.dealing.improve.work_bound` (what is left of plan-deal's budget)."""
        key: SearchKey = (agents, cut, order, steal, after)
        bound = work_bound(agents) if limit is None else min(work_bound(agents), limit)
        return self._once(("improve", key), lambda: self._improve(key, bound))

    def _improve(self, key: SearchKey, bound: int) -> Deal:
        agents, after = key[0], key[4]
        if after is not None:
            keep_walks, owner, base = self._found[after]
            return self._search(key, keep_walks, base, bound, owner)
        try:
            return self._search(key, False, agents, bound)
        except DealError:  # the agents find no way on: the walks' own causal links kept
            return self._search(key, True, agents, bound)

    def _search(
        self,
        key: SearchKey,
        keep_walks: bool,
        base: int,
        bound: int,
        first: Sequence[int] | None = None,
    ) -> Deal:
        """One attempt of :meth:`improve`, with or without the walks' links, from the list
        schedule for ``base`` agents (its owners, or ``first``)."""
        agents, cut, order, steal, _ = key
        pieces, _ = self.pieces(cut, keep_walks)
        schedule = self._list_schedule(base, order, cut, keep_walks)
        with self._phase("owner search"):
            timeline = self._timeline(cut, keep_walks)
            ended: dict[tuple[int, ...], list[int]] = {}  # per trial: the owners it ended with

            def simulate(owner: Sequence[int]) -> JointSteps:
                steps, ended[tuple(owner)] = timeline.run(
                    owner, schedule.start, schedule.level, agents, steal
                )
                return steps

            def clean(steps: JointSteps) -> JointSteps:
                joint = self._joint_cleanup([pair for step in steps for pair in step], agents)
                return earliest_steps(joint, agents)

            cleaned_before, walked_before = self.cleanup_work, self.walker.work

            def spent() -> int:
                walked = self.walker.work - walked_before
                return timeline.work + self.cleanup_work - cleaned_before + walked

            start = schedule.owner if first is None else first
            found = search_owners(start, schedule.start, agents, simulate,
                                  clean, spent, self.chain(cut), bound)  # fmt: skip
            joint = self._joint_cleanup([pair for step in found.steps for pair in step], agents)
        self._found[key] = (keep_walks, found.owner, base)
        owner = ended[tuple(found.owner)]
        deal = self._finish(pieces, owner, schedule.start, joint, agents, schedule.makespan)
        deal.moves, deal.search = found.moves, key
        return deal

    def _replayed(
        self, replay: Replay, owner: Sequence[int], start: Sequence[int], agents: int
    ) -> tuple[JointRun, list[int]]:
        """The replay of the pieces with these owners, after the joint clean-up; the owners
        it ended with (it hands a piece on where its agent cannot get there)."""
        run, got = replay.run(owner, start, agents)
        return self._joint_cleanup(run, agents), got

    def _in_plan_order(
        self, replay: Replay, owner: Sequence[int], start: Sequence[int], agents: int
    ) -> tuple[JointRun, list[int]]:
        """:meth:`_replayed` in the plan's own order, action by action
        (:meth:`Replay.in_plan_order`); the owners stay as given."""
        run = replay.in_plan_order(owner, agents, self.walking)
        return self._joint_cleanup(run, agents), list(owner)

    def _joint_cleanup(self, run: JointRun, agents: int) -> JointRun:
        """What several agents no longer need of a joint run (a block parked for want of a
        second hand): action elimination from the initial state."""
        env, own = self.init
        elimination = Elimination(self.goal, env, (own,) * agents, run)
        try:
            return elimination.run()
        finally:
            self.cleanup_work += elimination.work

    def _once(self, key: tuple[object, ...], make: Callable[[], Deal]) -> Deal:
        """The deal made under ``key``, or its :class:`DealError` raised again: each is made
        once."""
        if key not in self._deals:
            try:
                self._deals[key] = make()
            except DealError as error:
                self._deals[key] = error
        found = self._deals[key]
        if isinstance(found, DealError):
            raise found
        return found

    def _deal(
        self, agents: int, cut: str, order: str, keep_walks: bool, steal: bool, timed: bool
    ) -> Deal:
        """One attempt of :meth:`deal`; cuts that give the same pieces give the same deal,
        made once."""
        pieces, _ = self.pieces(cut, keep_walks)
        key = (agents, order, keep_walks, steal, timed, tuple(map(tuple, pieces)))
        return self._once(
            key, lambda: self._deal_pieces(agents, order, cut, keep_walks, steal, timed)
        )

    def _list_schedule(self, agents: int, order: str, cut: str, keep_walks: bool) -> Schedule:
        """Step 2 for ``agents`` agents and the pieces of ``cut`` (cached: the owner search
        starts from the schedule its way's deal made)."""
        key = (agents, order, cut, keep_walks)
        if key not in self._schedules:
            pieces, piece_order = self.pieces(cut, keep_walks)
            with self._phase("dealing"):
                before = walks_before(self.walking)
                scheduler = ListScheduler(pieces, piece_order, before, self.estimate, agents)
                self._schedules[key] = scheduler.run(order)
        return self._schedules[key]

    def _timeline(self, cut: str, keep_walks: bool) -> Timeline:
        """Step 3's runs of the pieces of ``cut``."""
        pieces, piece_order = self.pieces(cut, keep_walks)
        key = (cut, keep_walks)
        if key not in self._copies:
            with self._phase("order"):  # the pieces' copies
                made: dict[int, list[list[Step]]] = {}
                if self.use_copies:
                    made = piece_copies(self.problem, self.space, self.steps, pieces,
                                        self.agent_predicates, self.movers)  # fmt: skip
                self._copies[key] = made
        timeline = Timeline(self.walker, self.steps, pieces, piece_order.action_preds,
                            self.goal, self.init, self._copies[key], self.walks_ahead)  # fmt: skip
        self._timelines.append(timeline)
        return timeline

    def _deal_pieces(
        self, agents: int, order: str, cut: str, keep_walks: bool, steal: bool, timed: bool
    ) -> Deal:
        pieces, piece_order = self.pieces(cut, keep_walks)
        schedule = self._list_schedule(agents, order, cut, keep_walks)
        with self._phase("replay"):
            if timed:
                timeline = self._timeline(cut, keep_walks)
                steps, owner = timeline.run(
                    schedule.owner, schedule.start, schedule.level, agents, steal
                )
                run = [pair for step in steps for pair in step]
            else:
                replay = Replay(self.walker, self.steps, pieces, piece_order.preds, self.goal,
                                self.init)  # fmt: skip
                run, owner = replay.run(schedule.owner, schedule.start, agents)
        with self._phase("joint clean-up"):
            joint = self._joint_cleanup(run, agents)
        return self._finish(pieces, owner, schedule.start, joint, agents, schedule.makespan)

    def _finish(
        self,
        pieces: Sequence[list[int]],
        owner: Sequence[int],
        start: Sequence[int],
        joint: JointRun,
        agents: int,
        estimate: int,
    ) -> Deal:
        """The deal of a cleaned joint run: the agents' plans and its time steps."""
        with self._phase("joint clean-up"):
            steps = earliest_steps(joint, agents)
        plans: list[list[str]] = [[] for _ in range(agents)]
        for a, step in joint:
            plans[a].append(str(step))
        started = sorted(range(len(pieces)), key=lambda p: (start[p], p))
        return Deal(
            [pieces[p] for p in started],
            [owner[p] for p in started],
            plans,
            estimate,
            sum(is_walking(step, self.space) for _, step in joint),
            len(self.cleaned),
            [[(a, str(step)) for a, step in pairs] for pairs in steps],
        )


def deal_plan(
    problem: Problem,
    plan: Sequence[str],
    agents: int,
    agent_predicates: Collection[str],
    cut: str = "free",
    order: str = "critical",
    cleaned: Sequence[GroundAction] | None = None,
) -> Deal:
    """One deal of an SA plan to ``agents`` agents (:meth:`Dealer.deal`)."""
    return Dealer(problem, plan, agent_predicates, cleaned).deal(agents, cut, order)
