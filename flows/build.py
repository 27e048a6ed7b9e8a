"""A job's config turned into library objects, once: :func:`build_job` makes the
:class:`Job` (the task, the method and its request, the executor), and :meth:`Job.run`
runs it through a set of steps (the library's own, or Prefect tasks).

Each library setting has one name in the config (``flows/config.py``, whose defaults
are the library dataclasses' defaults) and is mapped here once; ``planner.time_limit_s``
is the planner's ``search_time_limit_s``; :func:`llm_settings` maps the ``llm`` group to
the LLM client's settings; :func:`search_budget` maps ``score_max_nodes`` and
``score_time_limit_s`` to the scorer's budget; a resource limit the library reports
(:class:`~twostep.programs.processes.LimitReached`, naming the library's parameter) is
worded with the config key that raises it (:func:`limit_message`), and so are the
library's other messages where they reach the user (:mod:`flows.wording`). The method is
the registry's (:func:`twostep.methods.method_for`), named by ``method`` with the keys of
its config file as its options; ``decomposer`` is TwoStep's subgoal source (the old spelling,
``method=twostep decomposer=plan-deal``, is respelled first: :mod:`flows.spelling`).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from flows.checks import JobError, check_values
from flows.config import TwostepConfig
from flows.identity import job_input_files
from flows.spelling import METHOD_KEYS, respell
from flows.wording import setting_key, worded, worded_run
from twostep.decomposers.base import Decomposer
from twostep.embodied import ExecutorSettings
from twostep.makespan import SearchBudget
from twostep.methods import (
    DIRECT,
    Method,
    MethodName,
    MethodRequest,
    RunResult,
    Steps,
    adopt_execution,
    method_for,
    run_single_agent,
)
from twostep.methods.registry import SUBGOAL_SOURCES, reads_subgoals
from twostep.methods.steps import SA_CALL, PlanCall
from twostep.pddl import Problem
from twostep.pddl.translator import GroundingLimits
from twostep.planner import PlannerSettings, PlanResult
from twostep.programs.processes import LimitReached
from twostep.tasks.benchmark import BenchmarkTask, load_task, task_path
from twostep.util.files import exists, file_problem, yaml_problem
from twostep.util.outcome import EmbodiedStatus

if TYPE_CHECKING:
    from twostep.llm import LLMSettings


def planner_settings(cfg: TwostepConfig) -> PlannerSettings:
    return PlannerSettings(
        alias=cfg.planner.alias,
        search_time_limit_s=float(cfg.planner.time_limit_s),
        memory_limit_mb=cfg.planner.memory_limit_mb,
    )


def grounding_limits(cfg: TwostepConfig) -> GroundingLimits:
    """What grounding the task may use: ``planner.memory_limit_mb`` and
    ``planner.grounding_time_limit_s`` (null: ``planner.time_limit_s``)."""
    seconds = cfg.planner.grounding_time_limit_s
    return GroundingLimits(
        memory_mb=cfg.planner.memory_limit_mb,
        time_s=float(cfg.planner.time_limit_s if seconds is None else seconds),
    )


def limit_message(reached: LimitReached) -> str:
    """What a job says of a limit it reached: the library's words, naming the config key
    of the library's parameter (:data:`flows.wording.SETTING_KEYS`)."""
    return reached.message(setting_key(reached.parameter))


def keyed_plan_result(result: PlanResult) -> PlanResult:
    """A planner call's result as a job records it: a limit's message names its key."""
    if result.limit is None:
        return result
    return replace(result, message=limit_message(result.limit))


def keyed_steps(steps: Steps) -> Steps:
    """``steps`` whose planner calls return :func:`keyed_plan_result`."""
    plan = steps.plan

    def keyed(problem: Problem, settings: PlannerSettings, call: PlanCall = SA_CALL) -> PlanResult:
        return keyed_plan_result(plan(problem, settings, call))

    return replace(steps, plan=keyed)


def search_budget(cfg: TwostepConfig) -> SearchBudget:
    """The exact scorer's budget: ``score_max_nodes`` and ``score_time_limit_s``."""
    max_nodes, time_limit_s = cfg.score_max_nodes, cfg.score_time_limit_s
    return SearchBudget(
        max_nodes=None if max_nodes is None else int(max_nodes),
        time_limit_s=None if time_limit_s is None else float(time_limit_s),
    )


def llm_settings(cfg: TwostepConfig) -> LLMSettings:
    """The LLM client's settings from the ``llm`` group (imported only for LLM jobs)."""
    from twostep.llm import LLMSettings

    llm = cfg.llm
    return LLMSettings(
        model=llm.model,
        temperature=float(llm.temperature),
        top_p=None if llm.top_p is None else float(llm.top_p),
        max_tokens=int(llm.max_tokens),
        api_base=llm.api_base,
        api_key_env=llm.api_key_env,
        mode=llm.mode,
        cache_dir=Path(llm.cache_dir),
        script=Path(llm.script) if llm.script else None,
        max_retries=int(llm.max_retries),
        backoff_s=float(llm.backoff_s),
        timeout_s=float(llm.timeout_s),
        use_cache=bool(llm.use_cache),
        local=bool(llm.local),
        bundle=Path(llm.bundle) if llm.bundle else None,
        translator=llm.translator,
    )


def executor_settings(cfg: TwostepConfig) -> ExecutorSettings:
    """The embodied executor's settings; its seed is the job's."""
    return ExecutorSettings(
        seed=int(cfg.seed),
        max_steps=cfg.executor.max_steps,
        random_start=bool(cfg.executor.random_start),
        stall_limit=int(cfg.executor.stall_limit),
        backoff_radius=int(cfg.executor.backoff_radius),
    )


def load_job_task(cfg: TwostepConfig) -> BenchmarkTask:
    """The job's task; says so on stderr when the data root's folder has no domain file
    and the tasks are read with twostep's own (:func:`twostep.tasks.benchmark.domain_file`)."""
    cache = Path(cfg.output.root) / "cache" / "tasks"  # parsed PDDL: see load_problem
    task = load_task(
        cfg.domain.name, int(cfg.task), Path(cfg.data.root), cache, grounding_limits(cfg)
    )
    folder = Path(cfg.data.root) / cfg.domain.name
    if task.domain_path.parent != folder:
        print(f"note: {folder} has no domain.pddl: its tasks are read with twostep's own "
              f"{task.domain_path}", file=sys.stderr)  # fmt: skip
    return task


def check_job(cfg: TwostepConfig) -> None:
    """Reject a config that cannot run, before any work (and before any server starts or
    anything heavy is imported): every value in range (one line naming the key and the
    allowed values), and the task's files where the config says they are."""
    respell(cfg)
    check_values(cfg)
    problem = task_path(cfg.domain.name, int(cfg.task), Path(cfg.data.root))  # BenchmarkError
    config = cast("Mapping[str, Any]", cfg)  # Hydra's DictConfig: a mapping
    for path in job_input_files(config, problem).values():  # no FIFO, device or loop read
        bad = file_problem(path)
        if bad is not None:
            raise JobError(bad)
    if (
        reads_subgoals(cfg.method.name)
        and cfg.decomposer.name == "llm"
        and cfg.llm.mode == "bundle"
    ):
        check_replay(cfg, problem)


def check_replay(cfg: TwostepConfig, problem_path: Path) -> None:
    """A job that replays a bundle's answers: the bundle holds them (its model, domain,
    task, N and a run for the seed) for this very task file; else one line saying what
    is missing, before any work (never a fallback that would look like a result)."""
    from twostep.replay import BundleError, BundleMiss, load_bundle

    if not cfg.llm.bundle:
        raise JobError("llm.mode=bundle needs llm.bundle=<folder of a replay bundle>")
    try:
        bundle = load_bundle(cfg.llm.bundle)
        bundle.entry(cfg.domain.name, int(cfg.task), int(cfg.agents), cfg.llm.model, int(cfg.seed))
        bundle.check_task_file(cfg.domain.name, int(cfg.task), problem_path)
    except (BundleError, BundleMiss) as error:
        raise JobError(worded(str(error))) from None


def check_task(cfg: TwostepConfig, task: BenchmarkTask) -> None:
    """What needs the task read: agent predicates the domain has (every method), and a
    kitchen for ``executor=embodied``; before any planning."""
    predicates = task.problem.domain.predicates
    unknown = [p for p in cfg.domain.agent_predicates if str(p).lower() not in predicates]
    if unknown:
        booleans = [p for p in unknown if str(p) in ("True", "False")]
        hint = (
            f"; {', '.join(booleans)} came from YAML, which reads unquoted on/off/yes/no/"
            "true/false as booleans: quote the name, e.g. agent_predicates: ['on']"
            if booleans
            else ""
        )
        raise JobError(
            f"domain.agent_predicates: {', '.join(unknown)} not in domain '{cfg.domain.name}' "
            f"({task.domain_path}); its predicates: {', '.join(sorted(predicates))}{hint}"
        )
    if cfg.executor.name == "embodied":
        check_kitchen(task, cfg.executor.layout)


def check_kitchen(task: BenchmarkTask, layout: str | None = None) -> None:
    """``executor=embodied`` runs plans on the task's floor plan: the domain folder's
    kitchen.yaml, or the grid of its location objects, or the scene ``layout``
    (``executor.layout``). Neither there, a kitchen.yaml that cannot be read or a layout
    that does not exist, is one line naming the file, the domain or the key."""
    import yaml

    from twostep.embodied import FloorPlanError, task_floor_plan

    kitchen = task.domain_path.parent / "kitchen.yaml"
    try:
        task_floor_plan(task.problem, task.domain_path.parent, layout)
    except yaml.YAMLError as error:
        raise JobError(yaml_problem(kitchen, error)) from None
    except FloorPlanError as error:
        if layout is not None:
            raise JobError(f"executor.layout={layout}: {error}") from None
        if exists(kitchen):
            message = str(error)
            raise JobError(
                message if message.startswith(str(kitchen)) else f"{kitchen}: {message}"
            ) from None
        raise JobError(
            f"executor=embodied needs a kitchen: domain '{task.domain_name}' has no "
            f"kitchen.yaml in {kitchen.parent} and no location objects to lay out "
            "(the kitchen domain is alfworld)"
        ) from None


@contextmanager
def open_decomposer(cfg: TwostepConfig) -> Iterator[Decomposer | None]:
    """The subgoal source the config names (None for the methods that need none), for
    the duration of one job.

    A context manager because the LLM decomposer owns a client (``llm=local`` runs a
    model server for the job's lifetime, stopped when the job ends).
    """
    name = cfg.decomposer.name
    agent_predicates = list(cfg.domain.agent_predicates)
    if not reads_subgoals(cfg.method.name) or name not in SUBGOAL_SOURCES:
        yield None  # sa, ma, and the methods that deal or choose (plan-deal, ...)
    elif name == "goal-split":
        from twostep.decomposers.goal_split import GoalSplitDecomposer

        yield GoalSplitDecomposer(agent_predicates, cfg.decomposer.link_degree)
    elif name == "expert":
        from twostep.decomposers.expert import ExpertDecomposer

        yield ExpertDecomposer()
    elif name == "plan-split":
        from twostep.decomposers.plan_split import PlanSplitDecomposer

        yield PlanSplitDecomposer(agent_predicates)
    else:  # llm
        from twostep.decomposers.llm import LLMDecomposer
        from twostep.llm import open_client

        with open_client(llm_settings(cfg)) as client:
            yield LLMDecomposer(client)


@dataclass(frozen=True)
class Job:
    """One job's library objects: the method, the request it answers (with the library's
    own steps), whether SA is solved beside it, and the embodied executor (None:
    symbolic)."""

    method_name: str  # the registry's (twostep.methods.registry.METHODS)
    method: Method
    request: MethodRequest
    compare_sa: bool
    executor: ExecutorSettings | None = None
    layout: str | None = None  # embodied: the scene (FloorPlanN, open); None: found
    task_load_s: float = 0.0  # reading and parsing the task's PDDL

    def run(self, steps: Steps = DIRECT) -> RunResult:
        """The method's result through ``steps``; with ``compare_sa`` the SA plan is
        solved first (its length is reported beside the result, and TwoStep reuses the
        plan), then the embodied executor runs the plans when configured; its messages
        name the config keys (:func:`flows.wording.worded_run`)."""
        return worded_run(self._run(steps))

    def _run(self, steps: Steps) -> RunResult:
        request = replace(self.request, steps=keyed_steps(steps))
        if self.method_name == MethodName.SA:
            return self.execute(self.method(request))
        sa = run_single_agent(request) if self.compare_sa else None
        if sa is not None:
            request = replace(request, sa_length=sa.sa_length, sa_plan=sa.planner_calls[0].result)
        result = self.method(request)
        if result.method == MethodName.TWOSTEP:  # plan-deal and the portfolios as well
            result.extra["fallback_if_longer"] = request.fallback_if_longer
        if sa is not None:
            # The SA comparison is solved in the same job; its planner time is reported apart.
            result.extra["sa_planning_time_s"] = round(sa.planning_time_s, 4)
        return self.execute(result)

    def execute(self, run: RunResult) -> RunResult:
        """``executor=embodied``: the run's plans executed on the task's floor plan (the
        scene ``layout`` when set); the result gains the embodied fields and fails when the
        execution does (:func:`twostep.methods.adopt_execution`). A failed execution is a
        recorded status, never an exception."""
        if self.executor is None:
            return run
        from twostep.embodied import embodied_fields, execute_plans, task_floor_plan

        if not run.success or not run.plans:
            run.extra.update(
                executor="embodied",
                embodied_status=EmbodiedStatus.NOT_RUN.value,
                embodied_length=None,
            )
            run.extra["embodied"] = {
                "status": EmbodiedStatus.NOT_RUN.value,
                "reason": "no plan to execute",
            }
            return run
        task = self.request.task
        floor = task_floor_plan(task.problem, task.problem_path.parent, self.layout)
        execution = execute_plans(task.problem, run.plans, run.agent_order, floor, self.executor)
        adopt_execution(run, embodied_fields(execution, floor))
        return run


@contextmanager
def build_job(cfg: TwostepConfig) -> Iterator[Job]:
    """The job of a config, checked (:class:`JobError`) and built once, for the duration
    of the job (the LLM decomposer's client lives as long)."""
    check_job(cfg)  # respelled first
    method_name = str(cfg.method.name)
    options = {str(k): v for k, v in cfg.method.items() if k not in METHOD_KEYS}
    try:
        method = method_for(method_name, cfg.decomposer.name, **options)
    except ValueError as error:  # UnknownMethod, or an option out of range
        raise JobError(str(error)) from None
    start = time.perf_counter()
    task = load_job_task(cfg)
    task_load_s = time.perf_counter() - start
    check_task(cfg, task)
    with open_decomposer(cfg) as decomposer:
        request = MethodRequest(
            task,
            agents=int(cfg.agents),
            planner=planner_settings(cfg),
            agent_predicates=list(cfg.domain.agent_predicates),
            decomposer=decomposer,
            seed=int(cfg.seed),
            score_mode=cfg.score_mode,
            search_budget=search_budget(cfg),
            fallback_if_longer=bool(cfg.method.fallback_if_longer),
        )
        embodied = cfg.executor.name == "embodied"
        yield Job(
            method_name,
            method,
            request,
            compare_sa=bool(cfg.compare_sa),
            executor=executor_settings(cfg) if embodied else None,
            layout=cfg.executor.layout,
            task_load_s=task_load_s,
        )


def run_config(cfg: TwostepConfig, steps: Steps = DIRECT) -> RunResult:
    """Build the job of ``cfg`` and run it through ``steps``: the library path of one job,
    without the job store, files or records (:func:`flows.job.execute_job` adds them)."""
    with build_job(cfg) as job:
        return job.run(steps)
