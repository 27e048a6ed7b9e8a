"""One job of a sweep, from its resolved config to a result: wiring only, no planning logic.

``run_job`` reads the task, builds the planner settings and the decomposer the config
names, and calls the library's method (:mod:`twostep.methods.twostep`) with a set of
:class:`~twostep.methods.twostep.Steps`: the library's own functions, or the Prefect-task
versions of :mod:`flows.tasks` when the job runs as a flow. The control flow of the
paper's pipeline stays in the library either way.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from flows.build import (
    check_job,
    executor_settings,
    load_job_task,
    open_decomposer,
    planner_settings,
    search_budget,
)
from flows.config import TwostepConfig
from twostep.benchmark import BenchmarkTask
from twostep.decomposers.base import Decomposer
from twostep.identity import display_name
from twostep.methods.twostep import (
    DIRECT,
    RunResult,
    Steps,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)
from twostep.pddl import Problem
from twostep.planner import PlannerSettings, PlanResult, plan


def run_job(
    cfg: TwostepConfig,
    task: BenchmarkTask | None = None,
    steps: Steps = DIRECT,
    prepare_decomposer: Callable[[Decomposer], object] | None = None,
    stats: StepStats | None = None,
) -> RunResult:
    """Run the method the config names on its task and return the result.

    ``prepare_decomposer`` sees the decomposer before it runs (the flow routes the LLM
    decomposer's calls through Prefect tasks there).
    """
    check_job(cfg)
    if task is None:
        start = time.perf_counter()
        task = load_job_task(cfg)
        if stats is not None:
            stats.add(task_load_s=time.perf_counter() - start)
    settings = planner_settings(cfg)
    steps = steps.with_search_budget(search_budget(cfg))
    method = cfg.method.name
    agents = int(cfg.agents)
    seed = int(cfg.seed)
    agent_predicates = list(cfg.domain.agent_predicates)
    if method == "sa":
        return execute_after_planning(
            cfg, task, run_single_agent(task, settings, seed, steps=steps)
        )
    sa: RunResult | None = None
    if cfg.compare_sa:
        sa = run_single_agent(task, settings, seed, steps=steps)
    sa_length = sa.sa_length if sa is not None else None
    if method == "ma":
        result = run_multi_agent(
            task, agents, agent_predicates, settings, cfg.score_mode, seed, sa_length, steps=steps
        )
    else:
        with open_decomposer(cfg) as decomposer:
            if prepare_decomposer is not None:
                prepare_decomposer(decomposer)
            result = run_twostep(
                task,
                agents,
                decomposer,
                agent_predicates,
                settings,
                cfg.score_mode,
                seed,
                sa_length,
                steps=steps,
                sa_plan=sa.planner_calls[0].result if sa is not None else None,
                fallback_if_longer=bool(cfg.method.fallback_if_longer),
            )
        result.extra["fallback_if_longer"] = bool(cfg.method.fallback_if_longer)
    if sa is not None:
        # The SA comparison is solved in the same job; its planner time is reported apart.
        result.extra["sa_planning_time_s"] = round(sa.planning_time_s, 4)
    return execute_after_planning(cfg, task, result)


def execute_after_planning(cfg: TwostepConfig, task: BenchmarkTask, run: RunResult) -> RunResult:
    """``executor=embodied``: the run's plans executed on the task's floor plan; the
    result gains the embodied fields (:func:`twostep.embodied.embodied_fields`). A
    failed execution is a recorded status, never an exception."""
    if cfg.executor.name != "embodied":
        return run
    from twostep.embodied import embodied_fields, execute_plans, task_floor_plan

    if not run.success or not run.plans:
        run.extra.update(executor="embodied", embodied_status="not_run", embodied_length=None)
        run.extra["embodied"] = {"status": "not_run", "reason": "no plan to execute"}
        return run
    floor = task_floor_plan(task.problem, task.problem_path.parent)
    execution = execute_plans(
        task.problem, run.plans, run.agent_order, floor, executor_settings(cfg)
    )
    run.extra.update(embodied_fields(execution, floor))
    run.extra["embodied_trace"]["render"] = bool(cfg.executor.render)
    return run


@dataclass
class StepStats:
    """What a job's step calls did: fresh planner calls vs cache hits, and their time.

    The job's orchestration overhead is its wall time minus ``planner_wall_s`` and
    ``llm_wall_s`` (time spent in fresh calls only: a cache hit costs no planning).
    """

    plan_calls: int = 0
    plan_cache_hits: int = 0
    planner_wall_s: float = 0.0
    llm_calls: int = 0
    llm_cache_hits: int = 0
    llm_wall_s: float = 0.0
    task_load_s: float = 0.0  # reading and parsing the task's PDDL (library work)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    def to_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self) if not f.name.startswith("_")}

    def add(self, **deltas: float) -> None:
        with self._lock:
            for name, delta in deltas.items():
                setattr(self, name, getattr(self, name) + delta)


def counting_steps(stats: StepStats) -> Steps:
    """The library's own steps, counting planner calls (the path without Prefect)."""

    def counted_plan(problem: Problem, settings: PlannerSettings) -> PlanResult:
        result = plan(problem, settings)
        stats.add(plan_calls=1, planner_wall_s=result.wall_time_s)
        return result

    return Steps(
        propose=DIRECT.propose, plan=counted_plan, progress=DIRECT.progress, score=DIRECT.score
    )


# ----------------------------------------------------------------- terminal output


def format_summary(result: RunResult | Mapping[str, Any]) -> str:
    """One line for the terminal (from a result or its result.json dict)."""
    r = result.to_dict() if isinstance(result, RunResult) else result
    if r.get("status") == "failed" and "error" in r:
        return f"{display_name(r)} | FAILED: {r['error']}"
    parts = [
        display_name(r),
        f"N={r.get('agents')}",
        "success" if r.get("success") else f"FAILED ({r.get('status')}: {r.get('message')})",
        f"exec_length={r.get('exec_length')}",
    ]
    if r.get("sa_length") is not None:
        parts.append(f"sa_length={r['sa_length']}")
    parts.append(f"planning_time={float(r.get('planning_time_s') or 0.0):.2f}s")
    subgoals = r.get("subgoals") or []
    chosen = [d for d in r.get("deal") or [] if d.get("chosen")]
    if chosen:  # plan-deal: pieces, not subgoals
        d = chosen[0]
        parts.append(f"dealt {d.get('pieces')} pieces ({d.get('walks')} walking steps)")
    elif r.get("decomposer"):
        accepted = sum(1 for s in subgoals if s.get("status") == "accepted")
        parts.append(f"subgoals={accepted}/{len(subgoals)} accepted")
    if r.get("fallback"):
        parts.append(f"fallback: {r['fallback']}")
    if r.get("executor") == "embodied":
        embodied = r.get("embodied") or {}
        if r.get("embodied_status") == "success":
            parts.append(
                f"embodied_length={r.get('embodied_length')} "
                f"(waits={r.get('waits')}, backoffs={r.get('backoffs')})"
            )
        else:
            where = f" {embodied.get('agent')} at step {embodied.get('step')}"
            where = where if embodied.get("agent") is not None else ""
            parts.append(
                f"embodied: {r.get('embodied_status')}{where}: {embodied.get('reason', '')}"
            )
    return " | ".join(parts)


def _agent_number(agent: str) -> int:
    digits = agent.removeprefix("agent")
    return int(digits) if digits.isdigit() else 0


def format_schedule(result: RunResult | Mapping[str, Any], width: int = 34) -> str:
    """The joint schedule as a table, one column per agent."""
    r = result.to_dict() if isinstance(result, RunResult) else result
    agents = sorted(r.get("plans") or {}, key=_agent_number)
    schedule = r.get("schedule") or []
    if not schedule or len(agents) < 2:
        return ""
    header = "step  " + "".join(a.ljust(width) for a in agents)
    lines = [header, "-" * len(header)]
    for t, step in enumerate(schedule, start=1):
        acting = {agent: action for agent, action in step}
        lines.append(f"{t:>4}  " + "".join(acting.get(a, ".").ljust(width) for a in agents))
    return "\n".join(lines)
