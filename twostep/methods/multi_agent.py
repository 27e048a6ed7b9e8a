"""MA PDDL: the task compiled for N agents, solved sequentially by one planner call, split
per agent and scored as a parallel execution (the paper's multi-agent baseline)."""

from __future__ import annotations

import time

from twostep.methods.request import MethodRequest
from twostep.methods.result import (
    AgentPlan,
    MethodName,
    RunResult,
    RunStatus,
    adopt_schedule,
    new_run,
)
from twostep.methods.steps import PlanCall
from twostep.tasks.multiagent import compile_multi_agent_problem, split_plan


def run_multi_agent(request: MethodRequest) -> RunResult:
    """Compile to N agents, plan once, split the plan per agent, score in parallel."""
    start = time.perf_counter()
    agents = request.agents
    compiled, names = compile_multi_agent_problem(request.problem, agents, request.agent_predicates)
    result = request.plan(compiled, call=PlanCall("multi", "all"))
    run = new_run(request, MethodName.MA)
    run.planner_calls.append(AgentPlan("all", "multi", compiled.goal.to_pddl(), result))
    run.planning_time_s = result.planner_time_s
    run.status = RunStatus(result.status.value)
    if not (result.solved and result.plan is not None):
        run.message = result.message
        run.wall_time_s = time.perf_counter() - start
        return run
    per_agent = split_plan(result.plan, names)
    score_start = time.perf_counter()
    execution = request.score(per_agent)
    run.score_time_s = time.perf_counter() - score_start
    adopt_schedule(run, execution, [f"agent{i}" for i in range(agents)], per_agent)
    run.extra["sequential_length"] = len(result.plan)
    run.wall_time_s = time.perf_counter() - start
    return run
