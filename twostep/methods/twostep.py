"""The three methods of the paper, end to end: SA PDDL, MA PDDL and TwoStep.

TwoStep, readable top to bottom in :func:`run_twostep`:

    propose (decomposer: generate + translate)  ->  check each subgoal
    ->  plan each helper from the current environment  ->  progress the state
    ->  plan the main agent to the full goal  ->  score the parallel execution

Each step is one function here (the LLM decomposer's two calls are
:func:`~twostep.decomposers.llm.generate_subgoal` and
:func:`~twostep.decomposers.llm.translate_subgoal`), and :class:`Steps` is the one way to
replace them: the Prefect flow (``flows/``) passes task-wrapped versions.
The subgoal rules are :mod:`twostep.subgoals`.
Every method returns a :class:`RunResult`, which serialises to the common result.json;
plans and schedules are planned (and kept in the result object) in the compiled domain's
terms, and result.json names them in the task's own (:mod:`twostep.pddl.origins`).
A decomposer that cannot propose (an LLM call failed after its retries) fails the run
with status ``llm_error``; only unusable subgoals lead to the single-agent fallback.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

from twostep.benchmark import BenchmarkTask
from twostep.decomposers.base import (
    Decomposer,
    DecomposerError,
    DecompositionRequest,
    SubgoalProposal,
)
from twostep.decomposers.llm import (
    GenerateStep,
    LLMDecomposer,
    TranslateStep,
    generate_subgoal,
    translate_subgoal,
)
from twostep.execution import (
    DEFAULT_SEARCH_BUDGET,
    ParallelExecution,
    ScheduleError,
    SearchBudget,
    check_schedule,
    parallel_length,
)
from twostep.multiagent import compile_multi_agent_problem, split_plan
from twostep.pddl import Fact, Goal, Problem
from twostep.pddl.model import ActionOrigin
from twostep.pddl.origins import original_action, original_plan
from twostep.planner import PlannerSettings, PlanResult, Status, plan
from twostep.progression import environment_part, handoff_problem, progress_state
from twostep.strips import Grounder, PlanError
from twostep.subgoals import SubgoalError, SubgoalStatus, check_subgoal


@dataclass
class AgentPlan:
    """One planner call of a run: which agent, towards which goal, and what came back."""

    agent: str
    role: str  # "single", "multi", "helper" or "main"
    goal: str
    result: PlanResult

    def to_dict(self) -> dict[str, Any]:
        return {"agent": self.agent, "role": self.role, "goal": self.goal, **self.result.to_dict()}


@dataclass
class RunResult:
    """What every method returns; :meth:`to_dict` is the result.json shape."""

    domain: str
    task: int
    method: str
    agents: int
    seed: int = 0
    success: bool = False
    exec_length: int | None = None
    exact: bool = True  # False when the scorer hit its node budget (exec_length is an upper bound)
    lower_bound: int | None = None  # the scorer's proven lower bound on exec_length
    sa_length: int | None = None
    sa_cost: int | None = None  # the SA plan's cost (its length unless the domain has costs)
    planning_time_s: float = 0.0
    llm_time_s: float = 0.0
    plans: dict[str, list[str]] = field(default_factory=dict)
    agent_order: list[str] = field(default_factory=list)  # hand-off order: who planned after whom
    schedule: list[list[tuple[str, str]]] = field(default_factory=list)
    subgoals: list[dict[str, Any]] = field(default_factory=list)
    decomposer: str | None = None
    status: str = "solved"  # the planner's status, or "llm_error" (then ``message`` says why)
    message: str = ""
    fallback: str | None = None
    planner_calls: list[AgentPlan] = field(default_factory=list)
    state_editing_time_s: float = 0.0
    score_time_s: float = 0.0
    wall_time_s: float = 0.0
    scripted_llm: bool = False
    extra: dict[str, Any] = field(default_factory=dict)
    # The compiled domain's action origins (an ADL task): plans and schedule are in its
    # terms here, in the task's own in result.json; empty for a STRIPS task.
    origins: Mapping[str, ActionOrigin] = field(default_factory=dict, repr=False)

    def task_plans(self) -> dict[str, list[str]]:
        """The plans in the task's own action names (goal actions of a compilation left out)."""
        if not self.origins:
            return self.plans
        return {agent: original_plan(self.origins, steps) for agent, steps in self.plans.items()}

    def task_schedule(self) -> list[list[tuple[str, str]]]:
        """The joint schedule in the task's own action names (a step keeps its place even
        when it only held a compilation's goal action, so its length is ``exec_length``)."""
        if not self.origins:
            return self.schedule
        named = []
        for step in self.schedule:
            pairs = [(agent, original_action(self.origins, action)) for agent, action in step]
            named.append([(agent, action) for agent, action in pairs if action is not None])
        return named

    def to_dict(self) -> dict[str, Any]:
        compiled = (
            {"compiled_plans": self.plans} if self.task_plans() != self.plans else {}
        )  # kept so that a schedule can be re-validated against the compiled task
        return {
            "domain": self.domain,
            "task": self.task,
            "method": self.method,
            "agents": self.agents,
            "seed": self.seed,
            "success": self.success,
            "exec_length": self.exec_length,
            "exact": self.exact,
            "lower_bound": self.lower_bound,
            "sa_length": self.sa_length,
            "sa_cost": self.sa_cost,
            "planning_time_s": round(self.planning_time_s, 4),
            "llm_time_s": round(self.llm_time_s, 4),
            "plans": self.task_plans(),
            **compiled,
            "agent_order": self.agent_order,
            "schedule": [[list(pair) for pair in step] for step in self.task_schedule()],
            "subgoals": self.subgoals,
            "decomposer": self.decomposer,
            "status": self.status,
            "message": self.message,
            "fallback": self.fallback,
            "planner_calls": [c.to_dict() for c in self.planner_calls],
            "state_editing_time_s": round(self.state_editing_time_s, 6),
            "score_time_s": round(self.score_time_s, 6),
            "wall_time_s": round(self.wall_time_s, 4),
            "scripted_llm": self.scripted_llm,
            **self.extra,
        }


# ----------------------------------------------------------------- steps


def score(
    problem: Problem,
    plans: Sequence[Sequence[str]],
    agent_predicates: Collection[str],
    mode: str = "exact",
    budget: SearchBudget = DEFAULT_SEARCH_BUDGET,
) -> ParallelExecution:
    """Parallel execution length of per-agent plans given in hand-off order; ``budget``
    bounds the exact search (past it the result says ``exact=False``)."""
    grounder = Grounder(problem)
    grounded = [grounder.ground_plan(p) for p in plans]
    return parallel_length(
        grounded,
        problem.init,
        problem.goal,
        agent_predicates,
        mode,
        max_nodes=budget.max_nodes,
        time_limit_s=budget.time_limit_s,
    )


def check_run(problem: Problem, run: RunResult, agent_predicates: Collection[str]) -> None:
    """Re-validate a run's joint schedule against the original ``problem`` by simulation.

    Raises :class:`~twostep.execution.ScheduleError` (or :class:`PlanError` for a plan
    step the task does not know) when the schedule does not reach the goal.
    """
    grounder = Grounder(problem)
    index = {agent: i for i, agent in enumerate(run.agent_order)}
    plans = [grounder.ground_plan(run.plans[agent]) for agent in run.agent_order]
    steps = [tuple((index[agent], action) for agent, action in step) for step in run.schedule]
    check_schedule(steps, plans, problem.init, problem.goal, agent_predicates)


def _named_schedule(
    execution: ParallelExecution, names: Sequence[str]
) -> list[list[tuple[str, str]]]:
    return [[(names[agent], action) for agent, action in step] for step in execution.steps]


def check_proposal(
    proposal: SubgoalProposal,
    problem: Problem,
    environment: frozenset[Fact],
    agent_predicates: Collection[str],
    earlier: Mapping[int, Goal],
) -> Goal | None:
    """The proposal's goal if :func:`twostep.subgoals.check_subgoal` accepts it from the
    helper's start (``environment`` plus its own agent facts); else mark it discarded."""
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


def propose(
    decomposer: Decomposer,
    request: DecompositionRequest,
    generate: GenerateStep = generate_subgoal,
    translate: TranslateStep = translate_subgoal,
) -> list[SubgoalProposal]:
    """Ask the decomposer for helper subgoals; the LLM decomposer calls ``generate`` and
    ``translate``. Raises :class:`~twostep.decomposers.base.DecomposerError`."""
    if isinstance(decomposer, LLMDecomposer):
        return decomposer.propose(request, generate, translate)
    return decomposer.propose(request)


def progress(
    problem: Problem, plan_steps: Sequence[str], agent_predicates: Collection[str]
) -> frozenset[Fact]:
    """The environment after an agent runs ``plan_steps`` from ``problem``'s initial state."""
    return progress_state(problem.init, Grounder(problem).ground_plan(plan_steps), agent_predicates)


class ScoreStep(Protocol):
    """:func:`score`'s signature; :meth:`Steps.with_search_budget` binds ``budget``."""

    def __call__(
        self,
        problem: Problem,
        plans: Sequence[Sequence[str]],
        agent_predicates: Collection[str],
        mode: str = ...,
        budget: SearchBudget = ...,
    ) -> ParallelExecution: ...


@dataclass(frozen=True)
class Steps:
    """The pipeline's steps as replaceable functions.

    The library runs them directly; ``flows/`` passes versions wrapped as Prefect tasks
    without repeating the control flow. ``generate`` and ``translate`` are the LLM
    decomposer's two calls (caching and retries stay in the LLM client).
    """

    propose: Callable[
        [Decomposer, DecompositionRequest, GenerateStep, TranslateStep], list[SubgoalProposal]
    ] = propose
    generate: GenerateStep = generate_subgoal
    translate: TranslateStep = translate_subgoal
    plan: Callable[[Problem, PlannerSettings], PlanResult] = plan
    progress: Callable[[Problem, Sequence[str], Collection[str]], frozenset[Fact]] = progress
    score: ScoreStep = score

    def with_search_budget(self, budget: SearchBudget) -> Steps:
        """These steps with every score call bounded by ``budget`` (a job's config)."""
        return replace(self, score=functools.partial(self.score, budget=budget))


DIRECT = Steps()


# ----------------------------------------------------------------- methods


def _use_single_agent_plan(run: RunResult, result: PlanResult) -> None:
    """Make ``result`` (one agent on the whole task) the run's outcome."""
    run.status = result.status.value
    if not result.solved or result.plan is None:
        run.message = result.message
        return
    run.success = True
    run.plans = {"agent0": list(result.plan)}
    run.agent_order = ["agent0"]
    run.exec_length = len(result.plan)
    run.schedule = [[("agent0", a)] for a in result.plan]
    if run.sa_length is None:
        run.sa_length = len(result.plan)
        run.sa_cost = result.cost


def run_single_agent(
    task: BenchmarkTask, settings: PlannerSettings, seed: int = 0, steps: Steps = DIRECT
) -> RunResult:
    """SA PDDL: the task solved as is by one agent."""
    start = time.perf_counter()
    problem = task.problem
    result = steps.plan(problem, settings)
    run = RunResult(task.domain_name, task.task_id, "sa", 1, seed, origins=problem.domain.origins)
    run.planner_calls.append(AgentPlan("agent0", "single", problem.goal.to_pddl(), result))
    run.planning_time_s = result.planner_time_s
    _use_single_agent_plan(run, result)
    run.wall_time_s = time.perf_counter() - start
    return run


def run_multi_agent(
    task: BenchmarkTask,
    agents: int,
    agent_predicates: Collection[str],
    settings: PlannerSettings,
    mode: str = "exact",
    seed: int = 0,
    sa_length: int | None = None,
    steps: Steps = DIRECT,
) -> RunResult:
    """MA PDDL: compile to N agents, solve sequentially, split per agent, score in parallel."""
    start = time.perf_counter()
    compiled, names = compile_multi_agent_problem(task.problem, agents, agent_predicates)
    result = steps.plan(compiled, settings)
    run = RunResult(task.domain_name, task.task_id, "ma", agents, seed, sa_length=sa_length)
    run.origins = task.problem.domain.origins
    run.planner_calls.append(AgentPlan("all", "multi", compiled.goal.to_pddl(), result))
    run.planning_time_s = result.planner_time_s
    run.status = result.status.value
    if not (result.solved and result.plan is not None):
        run.message = result.message
        run.wall_time_s = time.perf_counter() - start
        return run
    per_agent = split_plan(result.plan, names)
    run.agent_order = [f"agent{i}" for i in range(agents)]
    run.plans = dict(zip(run.agent_order, per_agent, strict=True))
    score_start = time.perf_counter()
    execution = steps.score(task.problem, per_agent, agent_predicates, mode)
    run.score_time_s = time.perf_counter() - score_start
    run.schedule = _named_schedule(execution, run.agent_order)
    run.exec_length = execution.length
    run.exact, run.lower_bound = execution.exact, execution.lower_bound
    run.success = True
    run.extra["sequential_length"] = len(result.plan)
    run.wall_time_s = time.perf_counter() - start
    return run


def run_twostep(
    task: BenchmarkTask,
    agents: int,
    decomposer: Decomposer,
    agent_predicates: Collection[str],
    settings: PlannerSettings,
    mode: str = "exact",
    seed: int = 0,
    sa_length: int | None = None,
    steps: Steps = DIRECT,
    sa_plan: PlanResult | None = None,
    fallback_if_longer: bool = True,
) -> RunResult:
    """TwoStep (the paper's Fig. 2): helpers on subgoals, then the main agent on the goal.

    Helper i is planned with the time limit divided by N, from the environment its
    predecessors left; discarded subgoals are recorded with the reason. If no subgoal
    survives, or the main agent cannot finish after the helpers, the result is the
    single-agent plan (success is guaranteed whenever SA succeeds).

    ``sa_plan`` is the SA planner result when the caller already has it (it is planned
    here when the decomposer sets ``needs_sa_plan``). With ``fallback_if_longer`` and an SA
    plan at hand, a joint schedule longer than SA gives way to the SA plan (``fallback``
    says so). Whenever the run uses the SA plan, its planner time counts in planning time
    (``extra["sa_time_included_s"]``). A :class:`~twostep.methods.portfolio.Portfolio` decomposer
    runs :func:`~twostep.methods.portfolio.run_portfolio` instead, and a
    :class:`~twostep.dealing.deal.PlanDeal` :func:`~twostep.dealing.deal.run_plan_deal` (it deals
    the SA plan's pieces to the agents instead of proposing subgoals).
    """
    from twostep.dealing.deal import PlanDeal, run_plan_deal
    from twostep.methods.portfolio import Portfolio, run_portfolio  # it calls this function

    # decomposers that need the whole pipeline, not just subgoals, run their own
    rest = (agent_predicates, settings, mode, seed, sa_length, steps, sa_plan, fallback_if_longer)
    if isinstance(decomposer, PlanDeal | Portfolio):
        chosen = (
            run_plan_deal(task, agents, decomposer, *rest)
            if isinstance(decomposer, PlanDeal)
            else run_portfolio(task, agents, decomposer, *rest)
        )
        chosen.origins = task.problem.domain.origins
        return chosen
    start = time.perf_counter()
    problem = task.problem
    run = RunResult(task.domain_name, task.task_id, "twostep", agents, seed, sa_length=sa_length)
    run.origins = problem.domain.origins
    run.decomposer = decomposer.name
    per_agent_settings = settings.with_time_limit(settings.search_time_limit_s / max(agents, 1))
    planner_time = 0.0
    if sa_plan is None and getattr(decomposer, "needs_sa_plan", False) and agents > 1:
        sa_plan = steps.plan(problem, settings)
    sa_steps: tuple[str, ...] | None = None
    if sa_plan is not None and sa_plan.solved and sa_plan.plan is not None:
        sa_steps = tuple(sa_plan.plan)
    sa_used = getattr(decomposer, "needs_sa_plan", False) and sa_steps is not None
    if run.sa_length is None and sa_steps is not None:
        run.sa_length = len(sa_steps)

    # 1-2. generate + translate (the decomposer)
    request = DecompositionRequest(task, agents, seed, sa_plan=sa_steps)
    try:
        proposals = steps.propose(decomposer, request, steps.generate, steps.translate)
    except DecomposerError as error:  # no answer at all: the run fails, no SA fallback
        _record_proposals(run, error.proposals)
        run.status, run.message = error.status, str(error)
        run.planning_time_s = run.llm_time_s
        run.wall_time_s = time.perf_counter() - start
        return run
    proposals = proposals[: max(agents - 1, 0)]

    # 3-4. check each subgoal, plan its helper, progress the environment
    environment = environment_part(problem.init, agent_predicates)
    helper_plans: list[list[str]] = []
    accepted_goals: dict[int, Goal] = {}
    editing_time = 0.0
    for proposal in proposals:
        goal = check_proposal(proposal, problem, environment, agent_predicates, accepted_goals)
        if goal is None:
            continue
        edit_start = time.perf_counter()
        helper_problem = handoff_problem(problem, environment, goal, agent_predicates)
        editing_time += time.perf_counter() - edit_start
        result = steps.plan(helper_problem, per_agent_settings)
        planner_time += result.planner_time_s
        run.planner_calls.append(
            AgentPlan(f"agent{proposal.helper}", "helper", goal.to_pddl(), result)
        )
        if not result.solved or result.plan is None:
            proposal.status = SubgoalStatus.DISCARDED
            proposal.reason = {
                Status.TIMEOUT: "timed out",
                Status.UNSOLVABLE: "unsolvable from the helper's initial state",
                Status.INCOMPLETE: "no plan found (incomplete search: not a proof)",
            }.get(result.status, f"planner error: {result.message}")
            continue
        edit_start = time.perf_counter()
        environment = steps.progress(helper_problem, result.plan, agent_predicates)
        editing_time += time.perf_counter() - edit_start
        proposal.status = SubgoalStatus.ACCEPTED
        accepted_goals[proposal.helper] = goal
        helper_plans.append(list(result.plan))

    # 5. the main agent, from the final environment, to the full goal
    main_plan: list[str] | None = None
    if helper_plans:
        edit_start = time.perf_counter()
        main_problem = handoff_problem(problem, environment, problem.goal, agent_predicates)
        editing_time += time.perf_counter() - edit_start
        result = steps.plan(main_problem, per_agent_settings)
        planner_time += result.planner_time_s
        run.planner_calls.append(AgentPlan("agent0", "main", problem.goal.to_pddl(), result))
        if result.solved and result.plan is not None:
            main_plan = list(result.plan)
        else:
            run.fallback = f"main agent after helpers: {result.status.value} ({result.message})"

    # 6. score; fall back to the single-agent plan when nothing usable remains
    accepted = [p for p in proposals if p.status == SubgoalStatus.ACCEPTED]
    execution: ParallelExecution | None = None
    if main_plan is not None:
        score_start = time.perf_counter()
        try:
            execution = steps.score(problem, [*helper_plans, main_plan], agent_predicates, mode)
        except (ScheduleError, PlanError) as error:
            run.fallback = f"joint schedule invalid: {error}"
        run.score_time_s = time.perf_counter() - score_start
    if execution is not None and fallback_if_longer and sa_steps is not None:
        sa_used = True  # the SA plan decided
        if execution.length > len(sa_steps):
            run.fallback = f"joint schedule longer than SA ({execution.length} > {len(sa_steps)})"
            execution = None
    if execution is not None:
        names = [f"agent{p.helper}" for p in accepted] + ["agent0"]
        run.agent_order = names
        run.plans = dict(zip(names, [*helper_plans, main_plan or []], strict=True))
        run.schedule = _named_schedule(execution, names)
        run.exec_length = execution.length
        run.exact, run.lower_bound = execution.exact, execution.lower_bound
        run.success = True
    else:
        if run.fallback is None:
            run.fallback = (
                "no helper subgoal accepted"
                if any(p.status != SubgoalStatus.STOPPED for p in proposals)
                else "no helper subgoal proposed"
            )
        for proposal in accepted:  # their plans are not used
            proposal.status, proposal.reason = SubgoalStatus.UNUSED, run.fallback
        if sa_plan is not None:
            result, sa_used = sa_plan, True
        else:
            result = steps.plan(problem, settings)
            planner_time += result.planner_time_s
        run.planner_calls.append(AgentPlan("agent0", "single", problem.goal.to_pddl(), result))
        _use_single_agent_plan(run, result)
    if sa_used and sa_plan is not None:
        planner_time += sa_plan.planner_time_s
        run.extra["sa_time_included_s"] = round(sa_plan.planner_time_s, 4)
    _record_proposals(run, proposals)
    run.state_editing_time_s = editing_time
    run.planning_time_s = run.llm_time_s + planner_time + editing_time
    run.wall_time_s = time.perf_counter() - start
    return run


def _record_proposals(run: RunResult, proposals: Sequence[SubgoalProposal]) -> None:
    """The proposals as result.json records them, with their LLM time."""
    run.llm_time_s = sum(p.llm_time_s for p in proposals)
    run.scripted_llm = any(x.get("scripted") for p in proposals for x in p.exchanges)
    run.subgoals = [p.to_dict() for p in proposals]
