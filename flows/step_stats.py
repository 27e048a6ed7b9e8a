"""What a job's step calls did (:class:`StepStats`): fresh planner and LLM calls against
cache hits, and their time; :func:`counting_steps` counts them on the path without
Prefect (``flows.prefect_flow`` counts its task runs itself)."""

from __future__ import annotations

import threading
from dataclasses import dataclass, field, fields, replace
from typing import Any

from twostep.methods import DIRECT, Steps
from twostep.methods.steps import SA_CALL, PlanCall
from twostep.pddl import Problem
from twostep.planner import PlannerSettings, PlanResult


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


def counting_steps(stats: StepStats, steps: Steps = DIRECT) -> Steps:
    """``steps`` with every planner call counted in ``stats`` (the path without Prefect)."""

    def counted_plan(
        problem: Problem, settings: PlannerSettings, call: PlanCall = SA_CALL
    ) -> PlanResult:
        result = steps.plan(problem, settings, call)
        stats.add(plan_calls=1, planner_wall_s=result.wall_time_s)
        return result

    return replace(steps, plan=counted_plan)
