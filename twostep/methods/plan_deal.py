"""``plan-deal`` as a method: deal the SA plan to N agents with every cut and order of
:mod:`twostep.dealing`, score each deal, and keep the shortest schedule.

No planner call beyond the SA plan: the run's planning time is the SA plan's planner time
and the time spent dealing. Deals that give the same plans are scored once. The SA plan is
the outcome when no deal works, with one agent, or (``fallback_if_longer``) when the
shortest schedule is longer. result.json ``deal`` records every cut and order tried: its
pieces, walks, the cleaned SA plan's length, the agents used, its length or its error.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from twostep.dealing import CUTS, ORDERS, DealError, clean_plan, deal_plan
from twostep.execution import ParallelExecution, ScheduleError
from twostep.methods.request import MethodRequest
from twostep.methods.result import (
    AgentPlan,
    Fallback,
    FallbackReason,
    MethodName,
    RunResult,
    adopt_sa_plan,
    adopt_schedule,
    count_sa_time,
    longer_than_sa,
    new_run,
    solved_steps,
)
from twostep.methods.single_agent import single_agent_plan
from twostep.strips import GroundAction, PlanError

BEST = "best"
"""The default cut: every cut of :data:`twostep.dealing.CUTS`, the shorter schedule kept."""


def deal_name(cut: str = BEST) -> str:
    """The run's ``decomposer`` name: ``plan-deal``, or ``plan-deal-<cut>`` for one cut."""
    return "plan-deal" if cut == BEST else f"plan-deal-{cut}"


@dataclass
class Trials:
    """Every deal tried (result.json ``deal`` rows), the shortest schedule, the time spent."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    best: tuple[ParallelExecution, list[list[str]]] | None = None
    deal_time_s: float = 0.0
    score_time_s: float = 0.0


def check_cut(cut: str) -> None:
    """Raise :class:`ValueError` unless ``cut`` is one of :data:`~twostep.dealing.CUTS` or
    :data:`BEST`."""
    if cut not in (*CUTS, BEST):
        raise ValueError(f"plan-deal cut must be one of {(*CUTS, BEST)}, not {cut!r}")


def run_plan_deal(request: MethodRequest, cut: str = BEST) -> RunResult:
    """Deal the SA plan with ``cut`` (``free``, ``holding`` or ``best``: both) and each
    order; the shortest schedule wins (module docstring)."""
    check_cut(cut)
    start = time.perf_counter()
    run = new_run(request, MethodName.TWOSTEP)
    run.decomposer = deal_name(cut)
    sa_plan = single_agent_plan(request)
    sa_steps = solved_steps(sa_plan)
    if run.sa_length is None and sa_steps is not None:
        run.sa_length = len(sa_steps)
    trials = Trials()
    if sa_steps is not None and request.agents > 1:
        try_deals(request, sa_steps, CUTS if cut == BEST else (cut,), trials)
    run.score_time_s = trials.score_time_s
    run.extra["deal"] = trials.rows
    if trials.best is not None:
        run.fallback = longer_than_sa(request, trials.best[0].length, sa_steps)
    run.planner_calls.append(AgentPlan("agent0", "single", request.problem.goal.to_pddl(), sa_plan))
    if trials.best is not None and run.fallback is None:
        execution, plans = trials.best
        adopt_schedule(run, execution, [f"agent{k}" for k in range(len(plans))], plans)
    else:
        if run.fallback is None:
            run.fallback = not_dealt(request, sa_steps, trials.rows)
        adopt_sa_plan(run, sa_plan)
    run.state_editing_time_s = trials.deal_time_s
    run.planning_time_s = count_sa_time(run, sa_plan) + trials.deal_time_s
    run.wall_time_s = time.perf_counter() - start
    return run


def try_deals(
    request: MethodRequest, sa_steps: Sequence[str], cuts: Sequence[str], trials: Trials
) -> None:
    """Deal with every cut and order (the SA plan cleaned once for all), scoring each new
    set of plans; the chosen row is marked."""
    problem = request.problem
    scored: dict[tuple[tuple[str, ...], ...], int] = {}  # plans -> the row that scored them
    cleaned: list[GroundAction] | None = None
    for cut in cuts:
        for order in ORDERS:
            row: dict[str, Any] = {"cut": cut, "order": order}
            trials.rows.append(row)
            deal_start = time.perf_counter()
            try:
                if cleaned is None:
                    cleaned = clean_plan(problem, sa_steps)
                dealt = deal_plan(
                    problem, sa_steps, request.agents, request.agent_predicates, cut, order, cleaned
                )
            except (DealError, PlanError) as error:
                row["error"] = str(error)
                continue
            finally:
                trials.deal_time_s += time.perf_counter() - deal_start
            plans = [p for p in dealt.plans if p]
            row.update(pieces=len(dealt.pieces), walks=dealt.walks,
                       cleaned_sa_length=dealt.cleaned, agents_used=len(plans))  # fmt: skip
            key = tuple(map(tuple, plans))
            if key in scored:  # another cut or order dealt the same plans
                same = scored[key]
                row.update(same_as=same, exec_length=trials.rows[same].get("exec_length"))
                continue
            scored[key] = len(trials.rows) - 1
            score_deal(request, plans, row, trials)


def score_deal(
    request: MethodRequest, plans: list[list[str]], row: dict[str, Any], trials: Trials
) -> None:
    """Score one deal's plans into its row; keep them when they are the shortest yet."""
    score_start = time.perf_counter()
    try:
        execution = request.score(plans)
    except (ScheduleError, PlanError) as error:
        row["error"] = f"joint schedule invalid: {error}"
    else:
        row["exec_length"] = execution.length
        if trials.best is None or execution.length < trials.best[0].length:
            for other in trials.rows:
                other.pop("chosen", None)
            row["chosen"] = True
            trials.best = (execution, plans)
    trials.score_time_s += time.perf_counter() - score_start


def not_dealt(
    request: MethodRequest, sa_steps: Sequence[str] | None, rows: Sequence[dict[str, Any]]
) -> Fallback:
    """Why the run is the SA plan when no deal was kept."""
    if sa_steps is None:
        return Fallback(FallbackReason.NO_SA_PLAN)
    if request.agents < 2:
        return Fallback(FallbackReason.ONE_AGENT)
    return Fallback(
        FallbackReason.NO_DEAL, "; ".join(f"{r['cut']}: {r.get('error')}" for r in rows)
    )
