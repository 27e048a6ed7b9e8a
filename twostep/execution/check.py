"""Independent re-validation of a joint schedule with plain frozensets (not the bit sets)."""

from __future__ import annotations

import itertools
from collections.abc import Collection, Sequence

from twostep.execution.diagnosis import precondition_error
from twostep.execution.model import ScheduleError, split_state
from twostep.pddl import Fact, Goal, fact_to_pddl
from twostep.strips import GroundAction, PlanError, parse_action


def interference(
    first: GroundAction, second: GroundAction, agent_predicates: Collection[str]
) -> str | None:
    """The environment fact through which two actions interfere, as a phrase, or None."""

    def environment(facts: frozenset[Fact]) -> frozenset[Fact]:
        return split_state(facts, agent_predicates)[0]

    for a, b in ((first, second), (second, first)):
        for fact in sorted(environment(a.delete) & (b.pre_positive | b.add)):
            return f"{a} deletes {fact_to_pddl(fact)}, which {b} needs or adds"
        for fact in sorted(environment(a.add) & b.pre_negative):
            return f"{a} adds {fact_to_pddl(fact)}, which {b} requires to be false"
    return None


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
    is run to the end, and that the goal holds afterwards. Uses plain frozensets, not the
    search's encoding, so it is an independent check of :func:`parallel_length`.
    """
    environment, agent_init = split_state(init, agent_predicates)
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
        actions: list[tuple[int, GroundAction]] = []
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
            missing = action.failing_precondition(environment | copies[agent])
            if missing is not None:
                error = precondition_error(agent, index + 1, str(action), missing)
                error.time_step = time_step
                raise error
            actions.append((agent, action))
        for (a, first), (b, second) in itertools.combinations(actions, 2):
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
        for agent, action in actions:
            environment_delete, agent_delete = split_state(action.delete, agent_predicates)
            environment_add, agent_add = split_state(action.add, agent_predicates)
            delete |= environment_delete
            add |= environment_add
            copies[agent] = (copies[agent] - agent_delete) | agent_add
            indices[agent] += 1
        environment = (environment - delete) | add
    for agent, plan in enumerate(plans):
        if indices[agent] != len(plan):
            raise ScheduleError(
                f"agent {agent} stops after {indices[agent]} of its {len(plan)} actions",
                agent=agent,
                step=indices[agent] + 1,
            )
    environment_goal = Goal(
        split_state(goal.positive, agent_predicates)[0],
        split_state(goal.negative, agent_predicates)[0],
    )
    unmet = environment_goal.unmet(environment)
    if unmet:
        raise ScheduleError(f"goal literal {unmet[0]} does not hold at the end", goal=unmet[0])
    agent_goal = Goal(
        split_state(goal.positive, agent_predicates)[1],
        split_state(goal.negative, agent_predicates)[1],
    )
    for agent, copy in enumerate(copies):
        unmet = agent_goal.unmet(copy)
        if unmet:
            raise ScheduleError(
                f"goal literal {unmet[0]} does not hold for agent {agent} at the end",
                agent=agent,
                goal=unmet[0],
            )
