"""TwoStep (the paper's Fig. 2): helper subgoals first, then the main agent on the goal.

:func:`run_twostep` reads top to bottom as the paper's pipeline:

    propose (the decomposer: generate + translate)  ->  check each subgoal
    ->  plan each helper from the current environment  ->  progress the state
    ->  plan the main agent to the full goal  ->  score the parallel execution

Every call goes through the request's :class:`~twostep.methods.steps.Steps` (the Prefect
flow passes task-wrapped ones); the LLM decomposer's two calls are ``generate`` and
``translate``, handed to it in the :class:`~twostep.decomposers.base.DecompositionRequest`.
The subgoal rules are :mod:`twostep.plans.subgoals`. A decomposer that cannot propose (an LLM
call failed after its retries) fails the run with status ``llm_error``; only unusable
subgoals lead to the single-agent fallback.
"""

from __future__ import annotations

import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field

from twostep.decomposers.base import (
    Decomposer,
    DecomposerError,
    DecompositionRequest,
    SubgoalProposal,
    reads_sa_plan,
)
from twostep.makespan import ParallelExecution, ScheduleError
from twostep.methods.request import MethodRequest
from twostep.methods.result import (
    AgentPlan,
    Fallback,
    FallbackReason,
    MethodName,
    RunResult,
    RunStatus,
    adopt_sa_plan,
    adopt_schedule,
    count_sa_time,
    longer_than_sa,
    new_run,
    record_proposals,
    solved_steps,
)
from twostep.methods.single_agent import single_agent_plan
from twostep.methods.steps import PlanCall
from twostep.pddl import Fact, Goal, Problem
from twostep.planner import PlannerSettings, PlanResult, Status
from twostep.plans.progression import environment_part, handoff_problem
from twostep.plans.simulate import PlanError
from twostep.plans.subgoals import SubgoalError, SubgoalStatus, check_subgoal

# Why a helper's subgoal is discarded when its planner call finds no plan
HELPER_FAILURES: Mapping[Status, str] = {
    Status.TIMEOUT: "timed out",
    Status.UNSOLVABLE: "unsolvable from the helper's initial state",
    Status.INCOMPLETE: "no plan found (incomplete search: not a proof)",
}


@dataclass
class HandOff:
    """What the helpers planned so far: the environment they leave behind, their plans
    (in hand-off order), their accepted subgoals, and the time spent."""

    environment: frozenset[Fact]
    plans: list[list[str]] = field(default_factory=list)
    goals: dict[int, Goal] = field(default_factory=dict)  # helper -> accepted subgoal
    planner_time_s: float = 0.0
    editing_time_s: float = 0.0


def run_twostep(request: MethodRequest) -> RunResult:
    """TwoStep with the request's decomposer.

    Each agent is planned with the time limit divided by N, helper i from the environment
    its predecessors left; discarded subgoals are recorded with the reason. If no subgoal
    survives, or the main agent cannot finish after the helpers, the result is the
    single-agent plan (success is guaranteed whenever SA succeeds).

    The SA plan is the request's, or planned here when the decomposer reads it. With
    ``fallback_if_longer`` and an SA plan at hand, a joint schedule longer than SA gives
    way to the SA plan (``fallback`` says so). Whenever the run uses the SA plan, its
    planner time counts in the planning time (``sa_time_included_s``).
    """
    start = time.perf_counter()
    decomposer = _decomposer(request)
    run = new_run(request, MethodName.TWOSTEP)
    run.decomposer = decomposer.name
    reads_sa = reads_sa_plan(decomposer)
    sa_plan = single_agent_plan(request) if reads_sa and request.agents > 1 else request.sa_plan
    sa_steps = solved_steps(sa_plan)
    if run.sa_length is None and sa_steps is not None:
        run.sa_length = len(sa_steps)

    # 1-2. generate + translate (the decomposer)
    try:
        proposals = propose(request, decomposer, sa_steps)
    except DecomposerError as error:  # no answer at all: the run fails, no SA fallback
        record_proposals(run, error.proposals)
        run.status, run.message = RunStatus(error.status), str(error)
        run.planning_time_s = run.llm_time_s
        run.wall_time_s = time.perf_counter() - start
        return run

    # 3-4. check each subgoal, plan its helper, progress the environment
    per_agent = request.planner.with_time_limit(
        request.planner.search_time_limit_s / max(request.agents, 1)
    )
    handoff = plan_helpers(request, proposals, per_agent, run)

    # 5. the main agent, from the final environment, to the full goal
    main_plan = plan_main(request, handoff, per_agent, run) if handoff.plans else None

    # 6. score; fall back to the single-agent plan when nothing usable remains
    execution = None if main_plan is None else score_joint(request, handoff, main_plan, run)
    compared = execution is not None and request.fallback_if_longer and sa_steps is not None
    if execution is not None:
        run.fallback = longer_than_sa(request, execution.length, sa_steps)
    planner_time = handoff.planner_time_s
    if execution is not None and main_plan is not None and run.fallback is None:
        accepted = [p for p in proposals if p.status == SubgoalStatus.ACCEPTED]
        names = [f"agent{p.helper}" for p in accepted] + ["agent0"]
        adopt_schedule(run, execution, names, [*handoff.plans, main_plan])
    else:
        planner_time += fall_back(request, run, proposals, sa_plan)
    # the SA plan's time counts whenever the run used it: read, compared or fallen back to
    used = (reads_sa and sa_steps is not None) or compared or run.fallback is not None
    if used and sa_plan is not None:
        planner_time += count_sa_time(run, sa_plan)
    record_proposals(run, proposals)
    run.state_editing_time_s = handoff.editing_time_s
    run.planning_time_s = run.llm_time_s + planner_time + handoff.editing_time_s
    run.wall_time_s = time.perf_counter() - start
    return run


def fall_back(
    request: MethodRequest,
    run: RunResult,
    proposals: Sequence[SubgoalProposal],
    sa_plan: PlanResult | None,
) -> float:
    """Make the SA plan the run's outcome (planned now when there is none yet: its
    planner time is returned); accepted subgoals become unused, with the reason."""
    if run.fallback is None:
        stopped = all(p.status == SubgoalStatus.STOPPED for p in proposals)
        run.fallback = Fallback(
            FallbackReason.NO_SUBGOAL_PROPOSED if stopped else FallbackReason.NO_SUBGOAL_ACCEPTED
        )
    for proposal in proposals:
        if proposal.status == SubgoalStatus.ACCEPTED:  # its plan is not used
            proposal.status, proposal.reason = SubgoalStatus.UNUSED, str(run.fallback)
    planned = 0.0
    if sa_plan is None:
        sa_plan = request.plan(request.problem)
        planned = sa_plan.planner_time_s
    goal = request.problem.goal.to_pddl()
    run.planner_calls.append(AgentPlan("agent0", "single", goal, sa_plan))
    adopt_sa_plan(run, sa_plan)
    return planned


def _decomposer(request: MethodRequest) -> Decomposer:
    if request.decomposer is None:
        raise ValueError("TwoStep needs a decomposer (MethodRequest.decomposer)")
    return request.decomposer


def propose(
    request: MethodRequest, decomposer: Decomposer, sa_steps: tuple[str, ...] | None
) -> list[SubgoalProposal]:
    """Steps 1-2: the decomposer's proposals, one per helper at most; its LLM calls go
    through the request's steps. Raises :class:`~twostep.decomposers.base.DecomposerError`."""
    asked = DecompositionRequest(
        request.task,
        request.agents,
        request.seed,
        sa_plan=sa_steps,
        generate=request.steps.generate,
        translate=request.steps.translate,
    )
    return decomposer.propose(asked)[: max(request.agents - 1, 0)]


def check_proposal(
    proposal: SubgoalProposal,
    problem: Problem,
    environment: frozenset[Fact],
    agent_predicates: Collection[str],
    earlier: Mapping[int, Goal],
) -> Goal | None:
    """Step 3: the proposal's goal if :func:`twostep.plans.subgoals.check_subgoal` accepts it
    from the helper's start (``environment`` plus its own agent facts); else it is marked
    discarded."""
    if proposal.status != SubgoalStatus.PROPOSED:  # discarded or stopped by the decomposer
        return None
    start = handoff_problem(problem, environment, problem.goal, agent_predicates).init
    try:
        return check_subgoal(
            proposal.pddl,
            problem,
            start=start,
            earlier=earlier,
            source=f"helper {proposal.helper} subgoal",
        )
    except SubgoalError as error:
        proposal.status, proposal.reason = SubgoalStatus.DISCARDED, str(error)
        return None


def plan_helpers(
    request: MethodRequest,
    proposals: Sequence[SubgoalProposal],
    settings: PlannerSettings,
    run: RunResult,
) -> HandOff:
    """Steps 3-4: check each proposal, plan its helper from the environment its
    predecessors left, progress the environment by the plan. A subgoal whose helper finds
    no plan is discarded with the reason."""
    problem, predicates = request.problem, request.agent_predicates
    handoff = HandOff(environment_part(problem.init, predicates))
    for proposal in proposals:
        goal = check_proposal(proposal, problem, handoff.environment, predicates, handoff.goals)
        if goal is None:
            continue
        edit_start = time.perf_counter()
        helper_problem = handoff_problem(problem, handoff.environment, goal, predicates)
        handoff.editing_time_s += time.perf_counter() - edit_start
        call = PlanCall("helper", f"agent{proposal.helper}")
        result = request.plan(helper_problem, settings, call)
        handoff.planner_time_s += result.planner_time_s
        run.planner_calls.append(AgentPlan(call.agent, call.role, goal.to_pddl(), result))
        if not result.solved or result.plan is None:
            proposal.status = SubgoalStatus.DISCARDED
            proposal.reason = HELPER_FAILURES.get(result.status, f"planner error: {result.message}")
            continue
        edit_start = time.perf_counter()
        handoff.environment = request.steps.progress(
            helper_problem, result.plan, predicates, call.agent
        )
        handoff.editing_time_s += time.perf_counter() - edit_start
        proposal.status = SubgoalStatus.ACCEPTED
        handoff.goals[proposal.helper] = goal
        handoff.plans.append(list(result.plan))
    return handoff


def plan_main(
    request: MethodRequest, handoff: HandOff, settings: PlannerSettings, run: RunResult
) -> list[str] | None:
    """Step 5: the main agent's plan from the helpers' environment to the full goal (None,
    with the run's fallback saying why, when it finds none)."""
    problem = request.problem
    edit_start = time.perf_counter()
    main_problem = handoff_problem(
        problem, handoff.environment, problem.goal, request.agent_predicates
    )
    handoff.editing_time_s += time.perf_counter() - edit_start
    call = PlanCall("main", "agent0")
    result = request.plan(main_problem, settings, call)
    handoff.planner_time_s += result.planner_time_s
    run.planner_calls.append(AgentPlan(call.agent, call.role, problem.goal.to_pddl(), result))
    if result.solved and result.plan is not None:
        return list(result.plan)
    detail = f"{result.status.value} ({result.message})"
    run.fallback = Fallback(FallbackReason.MAIN_AGENT_FAILED, detail)
    return None


def score_joint(
    request: MethodRequest, handoff: HandOff, main_plan: list[str], run: RunResult
) -> ParallelExecution | None:
    """Step 6: the parallel execution of the helpers' plans and the main agent's (None,
    with the run's fallback saying why, when no valid joint schedule exists)."""
    score_start = time.perf_counter()
    try:
        return request.score([*handoff.plans, main_plan])
    except (ScheduleError, PlanError) as error:
        run.fallback = Fallback(FallbackReason.SCHEDULE_INVALID, str(error))
        return None
    finally:
        run.score_time_s = time.perf_counter() - score_start
