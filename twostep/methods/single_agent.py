"""SA PDDL: the task solved as is, by one agent (the paper's single-agent baseline)."""

from __future__ import annotations

import time

from twostep.methods.request import MethodRequest
from twostep.methods.result import AgentPlan, MethodName, RunResult, adopt_sa_plan, new_run
from twostep.planner import PlanResult


def run_single_agent(request: MethodRequest) -> RunResult:
    """One planner call on the whole task; the plan is the schedule."""
    start = time.perf_counter()
    problem = request.problem
    result = request.plan(problem)
    run = new_run(request, MethodName.SA)
    run.planner_calls.append(AgentPlan("agent0", "single", problem.goal.to_pddl(), result))
    run.planning_time_s = result.planner_time_s
    adopt_sa_plan(run, result)
    run.wall_time_s = time.perf_counter() - start
    return run


def single_agent_plan(request: MethodRequest) -> PlanResult:
    """The SA planner result: the request's own (:attr:`MethodRequest.sa_plan`), or planned
    now, for the methods that start from the SA plan."""
    if request.sa_plan is not None:
        return request.sa_plan
    return request.plan(request.problem)
