"""Independent re-validation of a joint schedule with plain frozensets (not the bit sets)."""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Callable, Collection, Sequence
from typing import NamedTuple

from twostep.makespan.diagnosis import check_goal, precondition_error
from twostep.makespan.model import ScheduleError, split_state
from twostep.pddl import Fact, Goal, fact_to_pddl
from twostep.plans.simulate import GroundAction, PlanError, parse_action


def interference(
    first: GroundAction, second: GroundAction, agent_predicates: Collection[str]
) -> str | None:
    """The environment fact through which two actions interfere, as a phrase, or None.

    The rule of :mod:`twostep.makespan` on possible effects: one possibly deletes what the
    other needs or possibly adds, possibly adds what the other requires false, or possibly
    changes a fact the other's outcome depends on (effect conditions, derived facts).
    """

    def environment(facts: frozenset[Fact]) -> frozenset[Fact]:
        return split_state(facts, agent_predicates)[0]

    for a, b in ((first, second), (second, first)):
        for fact in sorted(environment(a.possible_delete) & (b.pre_positive | b.possible_add)):
            return f"{a} deletes {fact_to_pddl(fact)}, which {b} needs or adds"
        for fact in sorted(environment(a.possible_add) & (b.pre_negative | b.possible_delete)):
            return f"{a} adds {fact_to_pddl(fact)}, which {b} requires to be false"
        for fact in sorted(environment(a.writes) & b.condition_facts):
            return f"{a} changes {fact_to_pddl(fact)}, on which the effect of {b} depends"
    return None


class EnvironmentPart(NamedTuple):
    """An action's preconditions and possible effects on environment facts (agent facts
    left out), and the facts its outcome depends on beyond its precondition."""

    pre_positive: frozenset[Fact]
    pre_negative: frozenset[Fact]
    add: frozenset[Fact]
    delete: frozenset[Fact]
    conditions: frozenset[Fact] = frozenset()


def may_interfere(
    actions: Sequence[GroundAction], environment_of: Callable[[GroundAction], EnvironmentPart]
) -> bool:
    """Whether some two of ``actions`` may interfere (then the pairs are checked one by one).

    Counts, for every environment fact, the actions that need or add it, require it false
    or delete it, and write it; an action interferes with another when it deletes a fact
    some other action needs or adds, adds one some other action requires false, or
    depends on one some other action writes (the rules of :func:`interference`, both ways
    round). Linear in the step's size, where checking every pair is quadratic (16 agents:
    120 pairs per step).
    """
    needs_or_adds: Counter[Fact] = Counter()
    requires_false: Counter[Fact] = Counter()
    env = [environment_of(action) for action in actions]
    for part in env:
        needs_or_adds.update(part.pre_positive | part.add)
        requires_false.update(part.pre_negative)
    writers: Counter[Fact] = Counter()
    if any(part.conditions for part in env):
        for part in env:
            writers.update(part.add | part.delete)
    for part in env:
        own = part.pre_positive | part.add
        if any(needs_or_adds[f] > (f in own) for f in part.delete):
            return True
        if any(requires_false[f] > (f in part.pre_negative) for f in part.add):
            return True
        if part.conditions:
            written = part.add | part.delete
            if any(writers[f] > (f in written) for f in part.conditions):
                return True
    return False


def check_schedule(
    steps: Sequence[Sequence[tuple[int, str]]],
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> None:
    """Re-validate a joint schedule by simulation; raise :class:`ScheduleError` if invalid.

    Checks that each time step names distinct agents in index order, each taking its next
    plan action, that all preconditions hold and no two actions interfere, that every plan
    is run to the end, and that the goal holds afterwards. Each agent acts on its view of
    the state (the shared environment and its own agent-specific facts, closed under the
    task's axioms); the effects are evaluated there, and the goal must hold in every
    agent's view. Uses plain frozensets, not the search's encoding, so it is an
    independent check of :func:`parallel_length`.
    """
    axioms = next((a.axioms for plan in plans for a in plan if a.axioms), None)
    environment, agent_init = split_state(init, agent_predicates)
    parts: dict[int, EnvironmentPart] = {}

    def environment_of(action: GroundAction) -> EnvironmentPart:
        part = parts.get(id(action))
        if part is None:
            part = parts[id(action)] = EnvironmentPart(
                *(
                    split_state(facts, agent_predicates)[0]
                    for facts in (
                        action.pre_positive,
                        action.pre_negative,
                        action.possible_add,
                        action.possible_delete,
                        action.condition_facts,
                    )
                )
            )
        return part

    def view(copy: frozenset[Fact]) -> frozenset[Fact]:
        state = environment | copy
        return axioms.close(state) if axioms else state

    copies = [agent_init] * len(plans)
    indices = [0] * len(plans)
    for time_step, joint in enumerate(steps, start=1):
        if not joint:
            raise ScheduleError(f"time step {time_step} is empty", time_step=time_step)
        agents = [agent for agent, _ in joint]
        if agents != sorted(set(agents)) or not all(0 <= a < len(plans) for a in agents):
            raise ScheduleError(
                f"time step {time_step}: agents {agents} must be distinct plan indices "
                "in increasing order",
                time_step=time_step,
            )
        actions: list[tuple[int, GroundAction, frozenset[Fact]]] = []
        for agent, text in joint:
            index = indices[agent]
            if index >= len(plans[agent]):
                raise ScheduleError(
                    f"time step {time_step}: agent {agent} has no action left for {text}",
                    agent=agent,
                    action=text,
                    time_step=time_step,
                )
            action = plans[agent][index]
            try:
                same = parse_action(text) == (action.name, action.args)
            except PlanError:
                same = False
            if not same:
                raise ScheduleError(
                    f"time step {time_step}: agent {agent} step {index + 1} is {action}, "
                    f"not {text}",
                    agent=agent,
                    step=index + 1,
                    action=text,
                    time_step=time_step,
                )
            seen = view(copies[agent])
            missing = action.failing_precondition(seen)
            if missing is not None:
                error = precondition_error(agent, index + 1, str(action), missing)
                error.time_step = time_step
                raise error
            actions.append((agent, action, seen))
        if len(actions) > 1 and may_interfere([a for _, a, _ in actions], environment_of):
            for (a, first, _), (b, second, _) in itertools.combinations(actions, 2):
                reason = interference(first, second, agent_predicates)
                if reason is not None:
                    raise ScheduleError(
                        f"time step {time_step}: agents {a} and {b} interfere: {reason}",
                        agent=b,
                        step=indices[b] + 1,
                        action=str(second),
                        time_step=time_step,
                    )
        delete: set[Fact] = set()
        add: set[Fact] = set()
        for agent, action, seen in actions:
            added, deleted = action.effect_in(seen)
            environment_add, own_add = split_state(added, agent_predicates)
            environment_delete, own_delete = split_state(deleted, agent_predicates)
            delete |= environment_delete
            add |= environment_add
            copies[agent] = (copies[agent] - own_delete) | own_add
            indices[agent] += 1
        environment = (environment - delete) | add
    for agent, plan in enumerate(plans):
        if indices[agent] != len(plan):
            raise ScheduleError(
                f"agent {agent} stops after {indices[agent]} of its {len(plan)} actions",
                agent=agent,
                step=indices[agent] + 1,
            )
    check_goal(goal, environment, copies, agent_predicates, axioms)
