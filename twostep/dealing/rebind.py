"""Rebinding: one object's reuse in the SA plan spread over interchangeable objects.

One agent has no reason to use two things where one will do. Barman's SA plan carries every
ingredient in one shot glass, cleaning it between ingredients, so every deal of that plan
is one chain through the glass, however many agents there are. Rebinding gives the deal
other plans to work with, in which the glass's rounds are spread over the glasses that
stand idle.

An object's *own facts* are the environment facts that mention it, leaving out the
*handling* predicates: those that actions which change agent facts change too
(``ontable``: grasping a glass takes it off the table). A *mover* (an object that stays in
an agent fact an action moves: a robot, not a room) also owns the agent facts that say
more than where it is (a robot's gripper ``free``). A *round* of an object is a stretch of
the plan from one of its actions that changes its own facts to the first of its actions
after which they are as they were before the round began (a glass filled, poured and
cleaned again; a robot's grippers free again). Another object of the same type whose own
facts, renamed, are the same as the round's object's when the round begins, and that no
action of the stretch mentions, can do the round instead: every later action meets the
same facts. A mover's round is renamed with the objects its own facts name (a robot's
grippers to the other robot's). Where an action then does not apply, because of who
holds what or where a mover stands, the shortest sequence of handling actions on the
objects involved that makes it apply is inserted before it (put the old glass down, pick
the new one up; drive the other robot over: walks move only the action's own movers).

With ``tails``, a round's *tails* are candidates too: from where the object comes back to
a state it had earlier in the round (a glass poured out, to be filled again with the same
ingredient) to the round's end. The object keeps the tail's last actions from that state
on (it is cleaned where it stands), and the other object does the whole tail; an action
that no longer applies there gives way to one on the same arguments that applies and adds
all it adds (a glass filled afresh where the plan refilled it).

With ``resets``, a round may also go to an object in another state, brought back first
(barman's SA plan makes every cocktail after the first few in one shaker: the other
shakers stand used, their last cocktail poured out). The reset is the shortest sequence
of the task's actions (at most :data:`RESET_DEPTH`) that changes only that object's facts
and the agent facts, and leaves its own facts as the round's object's were and every
other fact, the hands' too, as it found them (take the shaker, empty it, wash it, put it
down). It goes right after the object's last action before the round (else right before
the round), so the deal can give it to an idle agent long before the round needs the
object. Movers are not reset, and a reset's own actions do not count among those a
rename adds (below): an idle agent does them, and the rounds spread widest.

The rounds are taken in plan order. Each may go to an interchangeable object mentioned
longer ago than the round's own object; a rename counts only when the whole plan,
repaired, still applies and reaches the goal, and of those the one that adds the fewest
actions is kept (ties: the object mentioned longest ago). The searches are bounded by
counts (:data:`TRIALS`, :data:`REPAIR_DEPTH`, :data:`REPAIR_STATES`, :data:`MATCHED`,
:data:`RESET_DEPTH`), never by time, so the result is the same on every machine.
"""

from __future__ import annotations

import functools
import itertools
from collections import Counter, defaultdict, deque
from collections.abc import Callable, Collection, Sequence
from typing import TypeVar

from twostep.decomposers.goal_split import positional_predicates
from twostep.pddl import Fact, Problem
from twostep.plans.simulate import GroundAction, Grounder, PlanError, effects_along

T = TypeVar("T")

TRIALS = 400
"""Renames tried per plan, at most (each costs a replay of the plan's rest)."""
REPAIR_DEPTH = 4
"""Handling actions inserted before one action, at most."""
REPAIR_STATES = 2_000
"""States one repair search may visit."""
RESET_DEPTH = 6
"""Actions a reset may take, at most (handling included)."""
MATCHED = 4
"""A mover's further objects matched to another mover's, at most (a robot's grippers)."""


def handling_predicates(problem: Problem, agent_predicates: Collection[str]) -> frozenset[str]:
    """Environment predicates that actions which change agent facts also change."""
    agent = set(agent_predicates)
    found: set[str] = set()
    for action in problem.grounded.actions.values():
        changed = {f[0] for f in action.possible_add | action.possible_delete}
        if changed & agent:
            found |= changed - agent
    return frozenset(found)


def _args(action: str) -> list[str]:
    return action.strip("()").split()[1:]


def rename_action(action: str, names: dict[str, str]) -> str:
    """``action`` (as text) with its arguments renamed by ``names``."""
    name, *args = action.strip("()").split()
    return "(" + " ".join([name, *(names.get(a, a) for a in args)]) + ")"


def movers(problem: Problem, positional: Collection[str]) -> frozenset[str]:
    """Objects that stay in a positional fact an action moves: ``robot1`` in
    ``(at-robby robot1 room1)`` -> ``(at-robby robot1 room2)``; termes' ``(at p)`` has none."""
    found: set[str] = set()
    for action in problem.grounded.actions.values():
        added = [f for f in action.possible_add if f[0] in positional]
        for fact in action.possible_delete:
            if fact[0] in positional:
                for other in added:
                    if other[0] == fact[0]:
                        found |= set(fact[1:]) & set(other[1:])
    return frozenset(found)


class Rebinder:
    """Rebinding of plans of one task (module docstring)."""

    def __init__(self, problem: Problem, agent_predicates: Collection[str]):
        self.problem = problem
        self.agent = frozenset(agent_predicates)
        self.grounder = Grounder(problem)
        self.left_out = self.agent | handling_predicates(problem, agent_predicates)
        self.handling = sorted(
            (
                a
                for a in problem.grounded.actions.values()
                if {f[0] for f in a.possible_add | a.possible_delete} <= self.left_out
                and any(f[0] in self.agent for f in a.possible_add | a.possible_delete)
            ),
            key=str,
        )
        # each handling action under its argument the fewest of them have (a ball, not a
        # room): an action whose arguments are all among some objects is under one of them
        count = Counter(obj for action in self.handling for obj in set(action.args))
        self._handling_of: defaultdict[str, list[int]] = defaultdict(list)
        for rank, action in enumerate(self.handling):
            if action.args:
                rarest = min(action.args, key=lambda obj: (count[obj], obj))
                self._handling_of[rarest].append(rank)
            else:
                self._handling_of[""].append(rank)
        self.positional = frozenset(positional_predicates(problem.domain)) & self.agent
        self.movers = movers(problem, self.positional)
        self._walking = {  # handling actions that only move agents
            rank
            for rank, a in enumerate(self.handling)
            if {f[0] for f in a.possible_add | a.possible_delete if f[0] in self.agent}
            <= self.positional
        }
        self.types = problem.all_objects

    @functools.cached_property
    def siblings(self) -> dict[tuple[str, ...], list[GroundAction]]:
        """The task's actions by their arguments (made when a repair first needs them)."""
        found: defaultdict[tuple[str, ...], list[GroundAction]] = defaultdict(list)
        for action in sorted(self.problem.grounded.actions.values(), key=str):
            found[action.args].append(action)
        return found

    def rebind(
        self, plan: Sequence[str], tails: bool = False, resets: bool = False
    ) -> list[str] | None:
        """The plan with rounds (and with ``tails`` their tails) rebound and handling
        repaired, with ``resets`` to an object brought back to the round's state first
        where none is in it (module docstring); None when no round could be (the plan must
        apply from the initial state and reach the goal)."""
        current = list(plan)
        changed, start, trials = False, 0, 0
        while trials < TRIALS:
            grounded = self.grounder.ground_plan(current)
            states = self._states(grounded)
            for first, last, obj, facts, closing in self._rounds(current, grounded, tails):
                if first < start:
                    continue
                start = first + 1
                best: tuple[int, int, list[str], int] | None = None
                for rank, (names, reset) in enumerate(
                    self._candidates(current, states, first, last, obj, facts, resets)
                ):
                    if trials >= TRIALS:
                        break
                    trials += 1
                    before: list[str] = []
                    at, state = first, states[first]
                    if reset:
                        found = self._reset(current, states, first, obj, names[obj], facts)
                        if found is None:
                            continue
                        at, before, state = found
                    renamed = [*closing] + [
                        rename_action(a, names) if names.keys() & set(_args(a)) else a
                        for a in current[first : last + 1]
                    ]
                    repaired = self._repair(state, renamed, current[last + 1 :], len(closing))
                    if repaired is not None:  # the fewest actions added (a reset's not
                        # counted), then the object mentioned longest ago
                        tail, begin = repaired
                        if best is None or (len(tail), rank) < best[:2]:
                            best = (len(tail), rank, [*current[:at], *before, *tail],
                                    at + len(before) + begin)  # fmt: skip
                if best is None:
                    continue
                *_, current, begin = best
                changed = True
                start = begin + 1  # on after the round's first action
                break  # a round was rebound (or the trials ran out): the plan again
            else:
                break  # every round was tried
        return current if changed else None

    @functools.cached_property
    def _touching(self) -> dict[str, list[GroundAction]]:
        """Per object, the task's actions that name it (made when a reset first needs
        them)."""
        found: defaultdict[str, list[GroundAction]] = defaultdict(list)
        for action in sorted(self.problem.grounded.actions.values(), key=str):
            for obj in set(action.args):
                found[obj].append(action)
        return found

    def _reset(
        self,
        plan: Sequence[str],
        states: Sequence[frozenset[Fact]],
        first: int,
        obj: str,
        other: str,
        facts: frozenset[Fact],
    ) -> tuple[int, list[str], frozenset[Fact]] | None:
        """The shortest sequence of actions that changes only ``other``'s facts and the
        agent facts, after which ``other``'s own facts are ``obj``'s ``facts`` renamed and
        every other fact is as before (a used shaker emptied and cleaned, the hands as
        they were), placed right after ``other``'s last action before ``first`` or else
        right before ``first``: (where it goes, it and the plan's actions from there to
        ``first``, the state it leaves at ``first``); None when there is none within
        :data:`RESET_DEPTH` actions."""
        target = frozenset((f[0], *(other if x == obj else x for x in f[1:])) for f in facts)
        if any(  # a goal fact of the object's own that the reset would undo
            other in f[1:] and f not in target and f in states[first] and self._counts(f, other)
            for f in self.problem.goal.positive
        ):
            return None
        moves = self._resetting(other)
        last = max((t for t in range(first) if other in _args(plan[t])), default=-1)
        for at in dict.fromkeys((last + 1, first)):
            state = states[at]
            held = self._in_hand(state) | {other}
            goal = target | {f for f in state if other not in f[1:] or not self._counts(f, other)}
            path = self._search(state, frozenset(goal), [*moves, *self._held(held, other)])
            if path is None:
                continue
            before = [str(move) for move in path]
            for move in path:
                state = move.apply(state)
            for text in plan[at:first]:  # the plan's own actions up to the round
                action = self.grounder.ground(text)
                if not action.applicable(state):
                    break
                state = action.apply(state)
                before.append(text)
            else:
                return at, before, state
        return None

    @functools.cache  # noqa: B019 (one Rebinder per task)
    def _resetting(self, other: str) -> list[GroundAction]:
        """The task's actions that name ``other`` and change only facts that mention it
        and agent facts (take the shaker, empty it, wash it)."""
        return [
            a
            for a in self._touching.get(other, ())
            if all(other in f[1:] or f[0] in self.agent for f in a.possible_add | a.possible_delete)
        ]

    @functools.cache  # noqa: B019 (one Rebinder per task)
    def _held(self, held: frozenset[str], other: str) -> list[GroundAction]:
        """The handling actions on the objects the hands hold (put down and taken up
        again while ``other`` is reset), beside :meth:`_resetting`'s."""
        ranks = {r for obj in (*held, "") for r in self._handling_of.get(obj, ())}
        moves = set(self._resetting(other))
        return [
            self.handling[r]
            for r in sorted(ranks)
            if r not in self._walking
            and set(self.handling[r].args) <= held
            and self.handling[r] not in moves
        ]

    @staticmethod
    def _search(
        state: frozenset[Fact], goal: frozenset[Fact], moves: Sequence[GroundAction]
    ) -> list[GroundAction] | None:
        """The shortest sequence of ``moves`` from ``state`` to ``goal`` (breadth-first, at
        most :data:`RESET_DEPTH` of them and :data:`REPAIR_STATES` states)."""
        found = breadth_first(state, moves, RESET_DEPTH, lambda here: here == goal or None)
        return None if found is None else found[0]

    def _in_hand(self, state: frozenset[Fact]) -> frozenset[str]:
        """The objects the agent facts of ``state`` name (the hands and what they hold)."""
        return frozenset(o for f in state if f[0] in self.agent for o in f[1:])

    def _states(self, plan: Sequence[GroundAction]) -> list[frozenset[Fact]]:
        state = self.problem.init
        states = [state]
        for action in plan:
            if not action.applicable(state):
                raise PlanError(f"{action} does not apply")
            state = action.apply(state)
            states.append(state)
        return states

    def _counts(self, fact: Fact, obj: str) -> bool:
        """Whether ``fact`` is one of ``obj``'s own: an environment fact, or for a mover
        an agent fact that says more than where it is (a robot's gripper free)."""
        if fact[0] not in self.left_out:
            return True
        return obj in self.movers and fact[0] in self.agent and fact[0] not in self.positional

    def _facts(self, state: frozenset[Fact], obj: str) -> frozenset[Fact]:
        return frozenset(f for f in state if obj in f[1:] and self._counts(f, obj))

    def _rounds(
        self, plan: Sequence[str], grounded: Sequence[GroundAction], tails: bool
    ) -> list[tuple[int, int, str, frozenset[Fact], tuple[str, ...]]]:
        """Every object's rounds and tails: (first step, last step, object, its facts
        before the round, the closing actions the object keeps), in plan order. Each
        object's own facts are kept along the plan."""
        facts: defaultdict[str, set[Fact]] = defaultdict(set)
        for fact in self.problem.init:
            for obj in fact[1:]:
                if self._counts(fact, obj):
                    facts[obj].add(fact)
        seen: defaultdict[str, list[tuple[int, frozenset[Fact], frozenset[Fact]]]]
        seen = defaultdict(list)
        fired = effects_along(self.problem.init, grounded)
        for t, (action, (add, delete)) in enumerate(zip(plan, fired, strict=True)):
            changed = [(f, o) for f in add | delete for o in f[1:] if self._counts(f, o)]
            touched = set(_args(action)) | {o for _, o in changed}
            before = {obj: frozenset(facts[obj]) for obj in touched}
            for fact, obj in changed:
                if fact in delete:
                    facts[obj].discard(fact)
            for fact, obj in changed:
                if fact in add:
                    facts[obj].add(fact)
            for obj in touched:
                seen[obj].append((t, before[obj], frozenset(facts[obj])))
        found: list[tuple[int, int, str, frozenset[Fact], tuple[str, ...]]] = []
        for obj, steps in seen.items():
            k = 0
            while k < len(steps):
                first, start, after = steps[k]
                if after == start:
                    k += 1
                    continue
                m = next((m for m in range(k + 1, len(steps)) if steps[m][2] == start), None)
                if m is None:
                    break
                found.append((first, steps[m][0], obj, start, ()))
                # its tails: from where it comes back to a state it had on the way (a glass
                # poured out and filled again with the same ingredient) to its end; the
                # object keeps the tail's last actions from that state on (cleaned)
                reached = {after: k}  # each state on the way: where it was first met
                for r in range(k + 1, m if tails else k + 1):
                    back = steps[r][2]
                    if back not in reached:
                        reached[back] = r
                    elif r == max(q for q in range(r, m) if steps[q][2] == back):
                        closing = tuple(plan[steps[c][0]] for c in range(r + 1, m + 1))
                        tail = steps[reached[back] + 1][0]
                        found.append((tail, steps[m][0], obj, start, closing))
                k = m + 1
        return sorted(found)

    def _candidates(
        self,
        plan: Sequence[str],
        states: Sequence[frozenset[Fact]],
        first: int,
        last: int,
        obj: str,
        facts: frozenset[Fact],
        resets: bool = False,
    ) -> list[tuple[dict[str, str], bool]]:
        """Objects that can do the round ``first``..``last`` of ``obj``, the one mentioned
        longest ago first; only those mentioned before ``obj`` last was. Each as the
        renaming of the round's actions: ``obj`` to the other, and for a mover the objects
        its own facts name (a robot's grippers) to the other's; and whether it must be
        reset first. With ``resets``, objects in another state (not movers) are
        candidates too, to be reset."""
        busy = {o for a in plan[first : last + 1] for o in _args(a)}
        seen: dict[str, int] = {}
        for t, action in enumerate(plan[:first]):
            for o in _args(action):
                seen[o] = t
        own = seen.get(obj, -1)
        found, loose = [], []
        for other, kind in self.types.items():
            if other == obj or other in busy or kind != self.types[obj]:
                continue
            if seen.get(other, -1) >= own:
                continue
            others = self._facts(states[first], other)
            names = matching(facts, others, obj, other, busy, self.types, obj in self.movers)
            if names is not None:
                found.append((seen.get(other, -1), other, names))
            elif (  # with resets, one in another state, to be reset
                resets
                and obj not in self.movers
                and not any(obj in f[1:] for f in others)
                and not any(other in f[1:] for f in facts)
            ):
                loose.append((seen.get(other, -1), other, {obj: other}))
        both = [(*entry, False) for entry in found] + [(*entry, True) for entry in loose]
        return [(names, reset) for *_, names, reset in sorted(both, key=lambda e: e[:2])]

    def _repair(
        self, state: frozenset[Fact], renamed: Sequence[str], rest: Sequence[str], at: int
    ) -> tuple[list[str], int] | None:
        """``renamed`` then ``rest`` from ``state``, with handling inserted where an action
        does not apply, and where ``renamed[at]`` (the first renamed action, after the
        object's closing ones) is in it; None when a repair fails or the goal is not
        reached."""
        out: list[str] = []
        begin = 0
        for k, text in enumerate([*renamed, *rest]):
            try:
                action = self.grounder.ground(text)
            except PlanError:
                return None
            if not action.applicable(state):
                found = self._handling_to(state, action, text)
                if found is None:
                    return None
                path, action = found
                text = str(action)
                for move in path:
                    state = move.apply(state)
                    out.append(str(move))
            if k == at:
                begin = len(out)
            state = action.apply(state)
            out.append(text)
        if not self.problem.goal.holds(state):
            return None
        return out, begin

    def _handling_to(
        self, state: frozenset[Fact], target: GroundAction, text: str
    ) -> tuple[list[GroundAction], GroundAction] | None:
        """The shortest sequence of handling actions on the target's objects and those the
        agent facts mention, after which ``target`` applies, or an action on the same
        arguments that adds all it adds (a glass filled afresh where the plan refilled it);
        and the action that then applies."""
        objects = set(_args(text)) | self._in_hand(state)
        ranks = {r for obj in (*objects, "") for r in self._handling_of.get(obj, ())}
        own = set(_args(text))  # walks only of the target's own movers (not every robot)
        moves = [
            self.handling[r]
            for r in sorted(ranks)
            if set(self.handling[r].args) <= objects
            and (r not in self._walking or own & set(self.handling[r].args))
        ]
        goals = [target] + [
            other
            for other in self.siblings.get(target.args, ())
            if other is not target and other.add >= target.add
        ]
        return breadth_first(
            state,
            moves,
            REPAIR_DEPTH,
            lambda here: next((g for g in goals if g.applicable(here)), None),
        )


def breadth_first(
    state: frozenset[Fact],
    moves: Sequence[GroundAction],
    depth: int,
    reached: Callable[[frozenset[Fact]], T | None],
) -> tuple[list[GroundAction], T] | None:
    """The shortest sequence of ``moves`` from ``state`` (at most ``depth`` of them, and
    :data:`REPAIR_STATES` states) to a state where ``reached`` gives something, and what it
    gave; None when there is none within those bounds."""
    queue: deque[tuple[frozenset[Fact], list[GroundAction]]] = deque([(state, [])])
    seen = {state}
    while queue:
        here, path = queue.popleft()
        hit = reached(here)
        if hit is not None:
            return path, hit
        if len(path) >= depth:
            continue
        for move in moves:
            if move.applicable(here):
                there = move.apply(here)
                if there not in seen:
                    if len(seen) >= REPAIR_STATES:
                        return None
                    seen.add(there)
                    queue.append((there, [*path, move]))
    return None


def matching(
    facts: frozenset[Fact],
    others: frozenset[Fact],
    obj: str,
    other: str,
    busy: Collection[str],
    types: dict[str, str],
    mover: bool = True,
) -> dict[str, str] | None:
    """A renaming from ``obj``'s objects to ``other``'s under which ``others`` (facts of
    ``other``) are ``facts`` (facts of ``obj``): ``obj`` to ``other``, and (a ``mover``)
    the further objects of ``facts`` to those of ``others``, of the same types, none of
    them ``busy``; None when there is none."""
    swap = {obj: other, other: obj}
    if {(f[0], *(swap.get(x, x) for x in f[1:])) for f in others} == facts:
        return {obj: other}
    if not mover:
        return None
    mine = sorted({x for f in facts for x in f[1:]} - {obj})
    theirs = sorted({x for f in others for x in f[1:]} - {other})
    if len(mine) != len(theirs) or len(mine) > MATCHED or set(theirs) & set(busy):
        return None
    for order in itertools.permutations(theirs):
        names = {obj: other, **dict(zip(mine, order, strict=True))}
        if any(types[a] != types[b] for a, b in names.items()):
            continue
        back = {b: a for a, b in names.items()}
        if {(f[0], *(back.get(x, x) for x in f[1:])) for f in others} == facts:
            return names
    return None


def rebind(
    problem: Problem,
    plan: Sequence[str],
    agent_predicates: Collection[str],
    tails: bool = False,
    resets: bool = False,
) -> list[str] | None:
    """``plan`` with its objects' rounds (and with ``tails`` their tails) spread over
    interchangeable objects (module docstring), or None when nothing changes."""
    return Rebinder(problem, agent_predicates).rebind(plan, tails, resets)
