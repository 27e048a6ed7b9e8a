"""Rebinding: one object's reuse in the SA plan spread over interchangeable objects.

One agent has no reason to use two things where one will do. Barman's SA plan carries every
ingredient in one shot glass, cleaning it between ingredients, so every deal of that plan
is one chain through the glass, however many agents there are. Rebinding gives the deal a
second plan to work with, in which the glass's rounds are spread over the glasses that
stand idle.

An object's *environment facts* are the facts that mention it, leaving out agent facts
and the *handling* predicates: those that actions which change agent facts change too
(``ontable``: grasping a glass takes it off the table). A *round* of an object is a
stretch of the plan from one of its actions that changes those facts to the first of its
actions after which they are as they were before the round began (a glass filled, poured
and cleaned again). Another object of the same type whose environment facts, renamed,
are the same as the round's object's when the round begins, and that no action of the
stretch mentions, can do the round instead: every later action meets the same facts.
Only who holds what can differ; where an action then does not apply, the shortest
sequence of handling actions on the objects involved that makes it apply (put the old
glass down, pick the new one up) is inserted before it.

The rounds are taken in plan order. Each goes to the interchangeable object mentioned
longest ago, if that is longer ago than the round's own object; a rename is kept only
when the whole plan, repaired, still applies and reaches the goal. The searches are
bounded by counts (:data:`TRIALS`, :data:`REPAIR_DEPTH`, :data:`REPAIR_STATES`), never by
time, so the result is the same on every machine.
"""

from __future__ import annotations

from collections import defaultdict, deque
from collections.abc import Collection, Sequence

from twostep.pddl import Fact, Problem
from twostep.strips import GroundAction, Grounder, PlanError, effects_along

TRIALS = 400
"""Renames tried per plan, at most (each costs a replay of the plan's rest)."""
REPAIR_DEPTH = 4
"""Handling actions inserted before one action, at most."""
REPAIR_STATES = 2_000
"""States one repair search may visit."""


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


def _renamed(action: str, old: str, new: str) -> str:
    name, *args = action.strip("()").split()
    return "(" + " ".join([name, *(new if a == old else a for a in args)]) + ")"


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
        self.types = problem.all_objects

    def rebind(self, plan: Sequence[str]) -> list[str] | None:
        """The plan with rounds rebound and handling repaired; None when no round could be
        (the plan must apply from the initial state and reach the goal)."""
        current = list(plan)
        changed, start, trials = False, 0, 0
        while trials < TRIALS:
            states = self._states(current)
            for first, last, obj, facts in self._rounds(current, states):
                if first < start:
                    continue
                start = first + 1
                for other in self._candidates(current, states, first, last, obj, facts):
                    trials += 1
                    renamed = [
                        _renamed(a, obj, other) if obj in _args(a) else a
                        for a in current[first : last + 1]
                    ]
                    repaired = self._repair(states[first], renamed, current[last + 1 :])
                    if repaired is not None:  # on after the round's first action
                        tail, begin = repaired
                        current, changed = current[:first] + tail, True
                        start = first + begin + 1
                        break
                    if trials >= TRIALS:
                        break
                else:
                    continue
                break  # a round was rebound (or the trials ran out): the plan again
            else:
                break  # every round was tried
        return current if changed else None

    def _states(self, plan: Sequence[str]) -> list[frozenset[Fact]]:
        state = self.problem.init
        states = [state]
        for action in self.grounder.ground_plan(plan):
            if not action.applicable(state):
                raise PlanError(f"{action} does not apply")
            state = action.apply(state)
            states.append(state)
        return states

    def _facts(self, state: frozenset[Fact], obj: str) -> frozenset[Fact]:
        return frozenset(f for f in state if obj in f[1:] and f[0] not in self.left_out)

    def _rounds(
        self, plan: Sequence[str], states: Sequence[frozenset[Fact]]
    ) -> list[tuple[int, int, str, frozenset[Fact]]]:
        """Every object's rounds: (first step, last step, object, its facts before), in
        plan order. Each object's environment facts are kept along the plan."""
        facts: defaultdict[str, set[Fact]] = defaultdict(set)
        for fact in self.problem.init:
            if fact[0] not in self.left_out:
                for obj in fact[1:]:
                    facts[obj].add(fact)
        seen: defaultdict[str, list[tuple[int, frozenset[Fact], frozenset[Fact]]]]
        seen = defaultdict(list)
        fired = effects_along(self.problem.init, self.grounder.ground_plan(plan))
        for t, (action, (add, delete)) in enumerate(zip(plan, fired, strict=True)):
            env_add = [f for f in add if f[0] not in self.left_out]
            env_delete = [f for f in delete if f[0] not in self.left_out]
            touched = set(_args(action)).union(*(f[1:] for f in (*env_add, *env_delete)))
            before = {obj: frozenset(facts[obj]) for obj in touched}
            for fact in env_delete:
                for obj in fact[1:]:
                    facts[obj].discard(fact)
            for fact in env_add:
                for obj in fact[1:]:
                    facts[obj].add(fact)
            for obj in touched:
                seen[obj].append((t, before[obj], frozenset(facts[obj])))
        found = []
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
                found.append((first, steps[m][0], obj, start))
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
    ) -> list[str]:
        """Objects that can do the round ``first``..``last`` of ``obj``, the one mentioned
        longest ago first; only those mentioned before ``obj`` last was."""
        busy = {o for a in plan[first : last + 1] for o in _args(a)}
        seen: dict[str, int] = {}
        for t, action in enumerate(plan[:first]):
            for o in _args(action):
                seen[o] = t
        own = seen.get(obj, -1)
        found = []
        for other, kind in self.types.items():
            if other == obj or other in busy or kind != self.types[obj]:
                continue
            if seen.get(other, -1) >= own:
                continue
            mapped = {
                (f[0], *(obj if x == other else other if x == obj else x for x in f[1:]))
                for f in self._facts(states[first], other)
            }
            if mapped == facts:
                found.append((seen.get(other, -1), other))
        return [other for _, other in sorted(found)]

    def _repair(
        self, state: frozenset[Fact], renamed: Sequence[str], rest: Sequence[str]
    ) -> tuple[list[str], int] | None:
        """``renamed`` then ``rest`` from ``state``, with handling inserted where an action
        does not apply, and where the first renamed action is in it; None when a repair
        fails or the goal is not reached."""
        out: list[str] = []
        begin = 0
        for k, text in enumerate([*renamed, *rest]):
            try:
                action = self.grounder.ground(text)
            except PlanError:
                return None
            if not action.applicable(state):
                path = self._handling_to(state, action, text)
                if path is None:
                    return None
                for move in path:
                    state = move.apply(state)
                    out.append(str(move))
            if k == 0:
                begin = len(out)
            state = action.apply(state)
            out.append(text)
        if not self.problem.goal.holds(state):
            return None
        return out, begin

    def _handling_to(
        self, state: frozenset[Fact], target: GroundAction, text: str
    ) -> list[GroundAction] | None:
        """The shortest sequence of handling actions on the target's objects and those the
        agent facts mention, after which ``target`` applies."""
        objects = set(_args(text)) | {o for f in state if f[0] in self.agent for o in f[1:]}
        moves = [m for m in self.handling if set(m.args) <= objects]
        queue: deque[tuple[frozenset[Fact], list[GroundAction]]] = deque([(state, [])])
        seen = {state}
        while queue:
            here, path = queue.popleft()
            if target.applicable(here):
                return path
            if len(path) >= REPAIR_DEPTH:
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


def rebind(
    problem: Problem, plan: Sequence[str], agent_predicates: Collection[str]
) -> list[str] | None:
    """``plan`` with its objects' rounds spread over interchangeable objects (module
    docstring), or None when nothing changes."""
    return Rebinder(problem, agent_predicates).rebind(plan)
