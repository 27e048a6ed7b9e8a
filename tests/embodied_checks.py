"""Test helpers: run the kitchen tasks' methods and replay every trace with the independent
checker (:mod:`checkers.trace_check`), which reads the floor plan and the PDDL files itself."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import lru_cache
from pathlib import Path
from typing import Any

from checkers.trace_check import Floor, TraceReport, check_trace, read_kitchen_file
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.embodied import EmbodiedResult, ExecutorSettings, FloorPlan, execute_plans
from twostep.embodied.run import TRACE_KEY, embodied_fields
from twostep.methods import MethodRequest, run_multi_agent, run_twostep
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import load_task

DATA = Path(__file__).resolve().parent.parent / "data"
KITCHEN = DATA / "alfworld" / "kitchen.yaml"
FAST = PlannerSettings(alias="lama-first", search_time_limit_s=60)
AGENT_PREDICATES = ("at", "handempty", "holding")


def replay(
    result: EmbodiedResult,
    floor_plan: FloorPlan,
    plans: Mapping[str, Sequence[str]],
    domain_text: str,
    problem_text: str,
    floor: Floor | None,
) -> TraceReport:
    """The checker's verdict on ``result``, from the trace record a job would write."""
    record: dict[str, Any] = embodied_fields(result, floor_plan)[TRACE_KEY]
    return check_trace(record, plans, domain_text, problem_text, floor)


@lru_cache(maxsize=64)
def method_plans(task_id: int, method: str, agents: int) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """The per-agent plans of MA or TwoStep (goal-split) on kitchen task ``task_id``, in
    hand-off order (planned once per module run)."""
    task = load_task("alfworld", task_id, DATA)
    if method == "ma":
        run = run_multi_agent(MethodRequest(task, agents, FAST, AGENT_PREDICATES))
    else:
        decomposer = GoalSplitDecomposer(AGENT_PREDICATES)
        run = run_twostep(MethodRequest(task, agents, FAST, AGENT_PREDICATES, decomposer))
    return tuple((a, tuple(run.plans[a])) for a in run.agent_order if a in run.plans)


def run_and_check(
    task_id: int, method: str, agents: int, seed: int, floor_plan: FloorPlan
) -> tuple[EmbodiedResult, TraceReport]:
    """Execute one method's plans on the kitchen with ``seed`` and replay the trace."""
    task = load_task("alfworld", task_id, DATA)
    plans = dict(method_plans(task_id, method, agents))
    result = execute_plans(
        task.problem, plans, list(plans), floor_plan, ExecutorSettings(seed=seed)
    )
    report = replay(
        result,
        floor_plan,
        plans,
        task.domain_path.read_text(),
        task.problem_path.read_text(),
        read_kitchen_file(KITCHEN),
    )
    return result, report
