"""The entry point: the shortest joint schedule of per-agent plans (see :mod:`twostep.makespan`)."""

from __future__ import annotations

from collections.abc import Collection, Sequence

from twostep.makespan.check import check_schedule
from twostep.makespan.compiled import compile_task, is_simple
from twostep.makespan.diagnosis import check_agent_copies, diagnose
from twostep.makespan.model import (
    DEFAULT_MAX_NODES,
    DEFAULT_TIME_LIMIT_S,
    MODES,
    ParallelExecution,
)
from twostep.makespan.search import search
from twostep.pddl import Fact, Goal
from twostep.plans.simulate import GroundAction


def _parallel_length(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
    mode: str,
    plain: bool = False,
    max_nodes: int | None = DEFAULT_MAX_NODES,
    time_limit_s: float | None = DEFAULT_TIME_LIMIT_S,
) -> ParallelExecution:
    if mode not in MODES:
        raise ValueError(f"unknown mode {mode!r}; expected one of {', '.join(MODES)}")
    if is_simple(plans):  # agent copies fixed by the plans alone: check them up front
        check_agent_copies(plans, init, goal, agent_predicates)
    task = compile_task(plans, init, goal, agent_predicates)
    found = search(task, mode, plain, max_nodes, time_limit_s)
    sets = found.sets
    if sets is None:
        raise diagnose(plans, init, goal, agent_predicates)
    indices = [0] * len(plans)
    steps = []
    for chosen in sets:
        joint = []
        for agent in chosen:
            joint.append((agent, str(plans[agent][indices[agent]])))
            indices[agent] += 1
        steps.append(tuple(joint))
    schedule = tuple(steps)
    check_schedule(schedule, plans, init, goal, agent_predicates)
    return ParallelExecution(
        len(schedule), schedule, mode, found.expanded, found.exact, found.lower_bound
    )


def parallel_length(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
    mode: str = "exact",
    max_nodes: int | None = DEFAULT_MAX_NODES,
    time_limit_s: float | None = DEFAULT_TIME_LIMIT_S,
) -> ParallelExecution:
    """The shortest joint schedule of per-agent plans that reaches ``goal``.

    ``mode="exact"`` minimises over any set of agents per step; ``mode="paper"`` allows
    only one agent or all remaining agents per step (the paper's Algorithm 1), so its
    length is never shorter. With one agent the length is its plan length.
    Raises :class:`ScheduleError` when no schedule reaches the goal, naming the agent, the
    1-based step, the action and the failing precondition (or the failing goal literal).

    The search expands at most ``max_nodes`` nodes and runs at most ``time_limit_s``
    seconds (None: no limit) once it has a schedule in hand; past either it returns the
    best schedule found with ``exact=False`` and a proven ``lower_bound`` (see
    :func:`~twostep.makespan.search.search`). The schedule is re-validated by
    :func:`check_schedule` in every case.
    """
    return _parallel_length(
        plans,
        init,
        goal,
        agent_predicates,
        mode,
        max_nodes=max_nodes,
        time_limit_s=time_limit_s,
    )
