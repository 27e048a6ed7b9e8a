"""The Prefect flow of one job and its tasks: each task calls one library function, the
library keeps the control flow.

:func:`run_flow` runs a built job (:class:`flows.build.Job`) as the flow ``twostep-job``
on a given API server. The flow's parameter is the job's resolved config (plain JSON,
shown in the Prefect UI); its body runs the job with :func:`prefect_steps`, so each
planner call, LLM call, state progression and scoring shows up as a task run. Task
results are persisted under ``orchestration.result_storage``; no ephemeral server is
started (a missing server is an error, not a silent 10-second start-up); the Dask task
runner is used when ``orchestration.task_runner=dask``.

=================  =================================================  ===================
task (run name)    library function                                   cache / retries
=================  =================================================  ===================
``plan``           :func:`twostep.planner.plan_pddl`                  cached on PDDL text
(``plan sa``, ``plan ma``, ``plan helper agent1``, ``plan main agent0``)
``generate``       :func:`~twostep.decomposers.llm.generate_subgoal`  no (see below)
(``generate helper agent1``; ``translate`` alike)
``translate``      :func:`~twostep.decomposers.llm.translate_subgoal` no (see below)
``progress_state`` :func:`twostep.methods.steps.progress`             no (microseconds)
(``progress after agent1``)
``score``          :func:`twostep.methods.steps.score`                no (milliseconds)
=================  =================================================  ===================

Cache keys are explicit (``cache_key_fn``): Prefect's INPUTS policy would hash Python
objects, and a :class:`~twostep.pddl.Problem` holds frozensets whose iteration order,
hence pickle, changes between processes. ``plan`` is keyed on the PDDL text the planner
reads, the planner settings, the Fast Downward wheel version and :data:`PLAN_VERSION`.
Results persist under ``orchestration.result_storage``, so a cache hit survives the
process, the sweep and a ``kill -9``. A planner crash is not cached (the task fails; the
method still gets the crash as a status).

The LLM tasks exist for observability only: the LLM client owns the one answer cache
(its disk cache, which replay reads) and the one retry loop, so these tasks neither
cache nor retry. A failed LLM call is the job's outcome (``llm_error``), not a task
crash: the task ends in a state named :data:`LLM_ERROR_STATE`, with no traceback.

The flow run's own state tells the truth: a job that ends without success (``llm_error``,
``error``, ``timeout``, an embodied execution that failed, ...) ends its flow run in a
Failed state named after it, with the reason (:func:`final_state`); a planner call that
ran out of its time limit ends its task run Failed, ``TimedOut``, with the reason
(:func:`mark_timed_out`), though its result stays cached. The flow run's log says what
the job is, what each step did and the job's result line (:func:`flow_log`); its
parameters are the config groups the job reads (:func:`flow_parameters`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import time
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from contextvars import ContextVar
from dataclasses import asdict
from functools import cache
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from prefect import State, flow, tags, task
from prefect.cache_policies import NO_CACHE
from prefect.client.orchestration import SyncPrefectClient
from prefect.context import SettingsContext, SyncClientContext, TagsContext, TaskRunContext
from prefect.flow_engine import run_flow_sync
from prefect.settings import (
    PREFECT_API_URL,
    PREFECT_CLIENT_CSRF_SUPPORT_ENABLED,
    PREFECT_FLOWS_HEARTBEAT_FREQUENCY,
    PREFECT_LOCAL_STORAGE_PATH,
    PREFECT_SERVER_ALLOW_EPHEMERAL_MODE,
    Settings,
    get_current_settings,
)
from prefect.states import Completed, Failed, Pending
from prefect.utilities.annotations import quote

from flows.build import keyed_plan_result
from flows.console import format_summary
from flows.identity import is_relevant, job_name
from flows.redaction import redact_config
from flows.status import JobStatus, job_status, reason_line
from flows.step_stats import StepStats
from flows.wording import worded, worded_error
from twostep import planner
from twostep.makespan import DEFAULT_SEARCH_BUDGET, ParallelExecution, SearchBudget
from twostep.methods import Steps
from twostep.methods.steps import SA_CALL, PlanCall, progress, score
from twostep.pddl import Fact, Problem
from twostep.planner import PlannerSettings, PlanResult, Status
from twostep.util.outcome import EmbodiedStatus, RunStatus

if TYPE_CHECKING:
    from flows.build import Job

# Bump when a change in the library makes cached task results stale.
PLAN_VERSION = "plan-2"  # PlanResult gained cost and the incomplete status
# The state name of an LLM task whose call failed (see _llm_call_outcome).
LLM_ERROR_STATE = "LLMError"
LLMStepResult = tuple[str | None, dict[str, Any]]


@cache
def _planner_version() -> str:
    try:
        return f"up-fast-downward {metadata.version('up-fast-downward')}"
    except metadata.PackageNotFoundError:
        return "up-fast-downward unknown"


def _digest(data: Any) -> str:
    blob = json.dumps(data, sort_keys=True, ensure_ascii=False, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


class PlannerCrashed(Exception):
    """Raised by the ``plan`` task for a planner error, so the error is not cached."""

    def __init__(self, result: PlanResult) -> None:
        super().__init__(result)
        self.result = result

    def __str__(self) -> str:
        return f"planner error: {keyed_plan_result(self.result).message}"


# ----------------------------------------------------------------- planner


def plan_cache_key(context: TaskRunContext, parameters: dict[str, Any]) -> str:
    settings: PlannerSettings = parameters["settings"]
    return _digest(
        {
            "task": "plan",
            "version": PLAN_VERSION,
            "planner": _planner_version(),
            "domain": parameters["domain_pddl"],
            "problem": parameters["problem_pddl"],
            "settings": asdict(settings),
        }
    )


@task(name="plan", persist_result=True, cache_key_fn=plan_cache_key, task_run_name="plan {call}")
def plan_task(
    domain_pddl: str, problem_pddl: str, settings: PlannerSettings, call: str = "sa"
) -> PlanResult:
    """One planner call (``call``: which, e.g. ``helper agent1``: the task run's name, not
    part of its cache key)."""
    result = planner.plan_pddl(domain_pddl, problem_pddl, settings)
    if result.status is Status.ERROR:
        raise PlannerCrashed(result)
    return result


@task(
    name="progress_state",
    cache_policy=NO_CACHE,
    persist_result=False,
    task_run_name="progress after {agent}",
)
def progress_task(
    problem: Problem, plan_steps: Sequence[str], agent_predicates: Collection[str], agent: str
) -> frozenset[Fact]:
    return progress(problem, plan_steps, agent_predicates)


@task(name="score", cache_policy=NO_CACHE, persist_result=False, task_run_name="score")
def score_task(
    problem: Problem,
    plans: Sequence[Sequence[str]],
    agent_predicates: Collection[str],
    mode: str,
    budget: SearchBudget,
) -> ParallelExecution:
    return score(problem, plans, agent_predicates, mode, budget)


# ----------------------------------------------------------------- LLM


def _llm_call_outcome(call: Callable[[], LLMStepResult]) -> Any:
    """Run one LLM step inside its task; a failed LLM call ends the task as a state.

    An :class:`~twostep.llm.client.LLMError` raised in a task would make Prefect log a
    traceback (and retry, with retries set): the error is the job's one-line outcome, so
    the task returns it in a ``Completed`` state named ``LLMError`` instead and
    :func:`_llm_step` raises it again in the caller, as the plain function would.
    """
    from twostep.llm.client import LLMError

    try:
        return call()
    except LLMError as error:
        return Completed(name=LLM_ERROR_STATE, message=worded(str(error)), data=error)


def _helper_run_name(step: str) -> Callable[..., str]:
    """``generate helper agent1``: an LLM task run named by its step and helper."""

    def name(parameters: dict[str, Any]) -> str:
        return f"{step} helper agent{parameters.get('helper', 1)}"

    return name


@task(
    name="generate",
    cache_policy=NO_CACHE,
    persist_result=False,
    retries=0,
    task_run_name=_helper_run_name("generate"),
)
def generate_task(
    client: Any,
    task: Any,
    agents: int,
    helper: int,
    earlier: Sequence[str],
    seed: int,
    *,
    fixed_example: bool = True,
) -> Any:
    from twostep.decomposers.llm import generate_subgoal

    return _llm_call_outcome(
        lambda: generate_subgoal(
            client, task, agents, helper, list(earlier), seed, fixed_example=fixed_example
        )
    )


@task(
    name="translate",
    cache_policy=NO_CACHE,
    persist_result=False,
    retries=0,
    task_run_name=_helper_run_name("translate"),
)
def translate_task(
    client: Any,
    task: Any,
    english: str,
    seed: int,
    *,
    helper: int = 1,
    earlier: dict[int, str] | None = None,
    agents: int | None = None,
) -> Any:
    from twostep.decomposers.llm import translate_subgoal

    return _llm_call_outcome(
        lambda: translate_subgoal(
            client, task, english, seed, helper=helper, earlier=earlier, agents=agents
        )
    )


def _llm_step(task_fn: Any, stats: StepStats) -> Callable[..., LLMStepResult]:
    """``task_fn`` as a library step: same arguments, same result, same exceptions."""

    def call(client: Any, task: Any, *args: Any, **kwargs: Any) -> LLMStepResult:
        start = time.perf_counter()
        state = task_fn(quote(client), quote(task), *args, return_state=True, **kwargs)
        outcome = state.result()  # raises what the task raised (a bug, not an LLM error)
        failed = isinstance(outcome, BaseException)
        # a hit of the LLM client's disk cache costs no call; a failed call does
        cached = not failed and bool(outcome[1].get("cached"))
        stats.add(
            llm_calls=0 if cached else 1,
            llm_cache_hits=1 if cached else 0,
            llm_wall_s=0.0 if cached else time.perf_counter() - start,
        )
        # generate(client, task, agents, helper, ...); translate(..., helper=k)
        helper = kwargs.get("helper", args[1] if task_fn.name == "generate" else 1)
        said = "failed" if failed else "answered" + (" (cached)" if cached else "")
        flow_log(f"{task_fn.name} helper agent{helper}: {said}", failed)
        if failed:  # the flow run's state says it with the config keys
            raise worded_error(outcome)
        text, exchange = outcome
        return text, exchange

    return call


# ----------------------------------------------------------------- steps


def _run(task_fn: Any, submit: bool, *args: Any, **kwargs: Any) -> State[Any]:
    """Run a task and return its final state: inline, or on the flow's task runner."""
    if submit:
        future = task_fn.submit(*args, **kwargs)
        future.wait()
        return future.state  # type: ignore[no-any-return]
    return task_fn(*args, return_state=True, **kwargs)  # type: ignore[no-any-return]


# ----------------------------------------------------------------- what a flow run says

# A timed-out planner call's task run: a Failed state of this name, never the green
# Completed or Cached its result gets (the result stays cached: a re-run does not wait
# for the limit again).
TIMED_OUT_STATE = "TimedOut"
FLOW_LOGGER = "twostep.flow"


def mark_timed_out(state: State[Any], result: PlanResult, cached: bool) -> None:
    """Set a planner call's task run, which ran out of its time limit, to Failed
    :data:`TIMED_OUT_STATE` with the reason (through the API: Prefect keeps a cached
    result Completed)."""
    task_run_id = state.state_details.task_run_id
    if task_run_id is None:
        return
    reason = f"timeout: {result.message or 'search time limit'}"
    reason += f" ({result.planner_time_s:.2f} s{', cached result' if cached else ''})"
    from prefect.client.orchestration import get_client

    with contextlib.suppress(Exception), get_client(sync_client=True) as client:
        client.set_task_run_state(
            task_run_id, Failed(name=TIMED_OUT_STATE, message=reason), force=True
        )


def plan_line(call: PlanCall, result: PlanResult, cached: bool) -> str:
    """``plan helper agent1: solved, 5 steps, 0.12 s (cached)``: a planner call's outcome."""
    what = result.status.value
    if result.plan is not None:
        what += f", {len(result.plan)} steps"
    elif result.message:
        what += f" ({result.message})"
    return f"plan {call.name}: {what}, {result.planner_time_s:.2f} s{' (cached)' if cached else ''}"


@cache
def _flow_logger() -> logging.Logger:
    """The flow runs' own log lines: sent to the Prefect API only (the job's console and
    log file have the summary already), whatever level Prefect's loggers are kept at."""
    from prefect.logging.handlers import APILogHandler

    logger = logging.getLogger(FLOW_LOGGER)
    logger.setLevel(logging.INFO)
    logger.propagate = False
    logger.addHandler(APILogHandler())
    return logger


def flow_log(message: str, warning: bool = False) -> None:
    """One line in the log of the flow run this thread runs (a step's outcome)."""
    with contextlib.suppress(Exception):  # a log line is never worth failing a job
        _flow_logger().log(logging.WARNING if warning else logging.INFO, message)


def prefect_steps(stats: StepStats, submit: bool = False) -> Steps:
    """The pipeline's steps as task runs; ``submit`` sends planner calls to the task runner.

    Only ``plan`` is submitted: it is the step worth moving to a Dask worker, while
    progress_state and score take micro- to milliseconds and run inline.
    """

    def plan(problem: Problem, settings: PlannerSettings, call: PlanCall = SA_CALL) -> PlanResult:
        if problem.goal.holds(problem.init):
            # The library answers this without calling the planner: no task run needed.
            result = planner.plan(problem, settings)
            flow_log(f"plan {call.name}: the goal holds already (no planner call)")
            return result
        domain_pddl, problem_pddl = planner.planner_input(problem)
        state = _run(plan_task, submit, domain_pddl, problem_pddl, settings, call.name)
        outcome = state.result(raise_on_failure=False)
        if isinstance(outcome, PlannerCrashed):
            result = keyed_plan_result(outcome.result)
        elif isinstance(outcome, BaseException):
            raise outcome
        else:
            result = outcome
        cached = state.name == "Cached"
        stats.add(
            plan_calls=0 if cached else 1,
            plan_cache_hits=1 if cached else 0,
            planner_wall_s=0.0 if cached else result.wall_time_s,
        )
        if result.status is Status.TIMEOUT:
            mark_timed_out(state, result, cached)
        flow_log(plan_line(call, result, cached), result.status is not Status.SOLVED)
        return result

    def progress_step(
        problem: Problem,
        plan_steps: Sequence[str],
        agent_predicates: Collection[str],
        agent: str = "",
    ) -> frozenset[Fact]:
        # quote(): Prefect must not walk the problem's fact sets looking for futures; it
        # hands the task the problem itself.
        environment: frozenset[Fact] = progress_task(
            quote(problem),  # type: ignore[call-overload]
            list(plan_steps),
            list(agent_predicates),
            agent or "?",
        )
        flow_log(f"progress after {agent or '?'}: {len(environment)} environment facts")
        return environment

    def score_step(
        problem: Problem,
        plans: Sequence[Sequence[str]],
        agent_predicates: Collection[str],
        mode: str = "exact",
        budget: SearchBudget = DEFAULT_SEARCH_BUDGET,
    ) -> ParallelExecution:
        execution: ParallelExecution = score_task(
            quote(problem),  # type: ignore[call-overload]
            [list(p) for p in plans],
            list(agent_predicates),
            mode,
            budget,
        )
        found = "the shortest" if execution.exact else f"lower bound {execution.lower_bound}"
        flow_log(f"score: execution length {execution.length} ({mode} mode, {found})")
        return execution

    return Steps(
        generate=_llm_step(generate_task, stats),
        translate=_llm_step(translate_task, stats),
        plan=plan,
        progress=progress_step,
        score=score_step,
    )


# ----------------------------------------------------------------- the flow


def _task_runner(config: Mapping[str, Any], dask_address: str | None) -> Any:
    if config["orchestration"]["task_runner"] != "dask":
        return None
    from prefect_dask.task_runners import DaskTaskRunner

    if dask_address:
        return DaskTaskRunner(address=dask_address)
    workers = int(config["orchestration"]["dask_workers"])
    # No cluster given and none started for a sweep: a temporary one for this job.
    return DaskTaskRunner(
        cluster_kwargs={"n_workers": workers, "threads_per_worker": 1, "dashboard_address": None}
    )


def flush_to_server(timeout_s: float = 5.0) -> None:
    """Send the logs and events this process still queues, before their server stops.

    Task runs and logs reach the server from background workers; a server stopped
    right after the last flow would lose them (and each worker would print an error).
    """
    from prefect.events.worker import EventsWorker
    from prefect.logging.handlers import APILogWorker

    for worker in (APILogWorker, EventsWorker):
        with contextlib.suppress(Exception):
            worker.drain_all(timeout=timeout_s)


def quiet_logs(level: str) -> None:
    """Hydra's job logging sends every logger to the console at INFO; Prefect's client
    logs each API request there (through httpx). Keep them at ``level``."""
    for name in ("prefect", "prefect.flow_runs", "prefect.task_runs", "httpx", "httpcore"):
        logging.getLogger(name).setLevel(level)


@cache
def _flow_with(storage: Path) -> Any:
    """The job's flow with its results' folder, made once per folder (a copy of a flow
    builds its parameter schema again)."""
    return job_flow.with_options(result_storage=storage)


_CLIENTS: dict[tuple[int, str], SyncClientContext] = {}


@contextlib.contextmanager
def open_client(api_url: str) -> Iterator[SyncPrefectClient]:
    """This process's Prefect client of the server at ``api_url``, kept open from one job to
    the next (a client per flow run costs its construction and a new connection each);
    every API call of the flow run and its task runs goes through it. Enter inside
    :func:`job_settings` (the client reads the API address from the settings)."""
    key = (os.getpid(), api_url)  # a forked worker never shares its parent's connections
    context = _CLIENTS.get(key)
    if context is None:
        context = SyncClientContext()
        context.client.__enter__()  # closed with the process
        context.client.raise_for_api_version_mismatch_once()
        _CLIENTS[key] = context
    token = SyncClientContext.__var__.set(context)
    try:
        yield context.client
    finally:
        SyncClientContext.__var__.reset(token)


_SETTINGS: dict[tuple[str, str], Settings] = {}


def job_settings(api_url: str, storage: Path) -> SettingsContext:
    """Prefect settings of a job, built once per process (validating them takes 0.1 s)."""
    key = (api_url, str(storage))
    if key not in _SETTINGS:
        from flows.servers import csrf_enforced

        _SETTINGS[key] = get_current_settings().copy_with_update(
            updates={
                PREFECT_API_URL: api_url,
                PREFECT_LOCAL_STORAGE_PATH: str(storage),
                # A missing server is an error, never a silent ephemeral start-up.
                PREFECT_SERVER_ALLOW_EPHEMERAL_MODE: False,
                # Heartbeats detect crashed flow runs in deployments; here they only
                # cost a thread whose join adds up to a second to every job.
                PREFECT_FLOWS_HEARTBEAT_FREQUENCY: None,
                # A server without CSRF protection (ours): no token request per flow run.
                PREFECT_CLIENT_CSRF_SUPPORT_ENABLED: csrf_enforced(api_url),
            }
        )
    current = SettingsContext.get()
    assert current is not None  # Prefect enters a root settings context at import
    return SettingsContext(profile=current.profile, settings=_SETTINGS[key])


# The job the current flow run computes, with its step counts and whether planner calls go
# to the task runner: built once by flows.job and handed over here, since the flow's
# parameter is the config (what the UI shows). Prefect pickles the flow's function by value
# into Dask's workers: it must not hold the job (nor this variable) itself.
_RUNNING: ContextVar[tuple[Job, StepStats, bool]] = ContextVar("twostep_running_job")


def running_job() -> tuple[Job, StepStats, bool]:
    """The job :func:`run_flow` is running in this context."""
    return _RUNNING.get()


# The flow run's state name for a job that ends without success, by what the result says
# (others: the status in CamelCase). Every one is a FAILED state: red in the Prefect UI.
FAILED_STATE_NAMES: dict[str, str] = {
    RunStatus.LLM_ERROR: LLM_ERROR_STATE,
    RunStatus.TIMEOUT: "TimedOut",  # Prefect's own name for a run stopped by its time limit
    RunStatus.EMBODIED_FAILED: "EmbodiedFailed",
}


def final_state(result: Mapping[str, Any]) -> dict[str, Any] | State[Any]:
    """What the flow returns for a job's result: the result itself (the run is Completed)
    for a success, else a Failed state named after how the job ended, with the reason as
    its message and the result as its data (the job is still recorded; a sweep goes on)."""
    status, reason = job_status(result)
    if status is JobStatus.SUCCESS:
        return dict(result)
    kind = str(result.get("status") or RunStatus.FAILED)
    embodied = result.get("executor") == "embodied" and result.get("embodied_status")
    if embodied and embodied != EmbodiedStatus.SUCCESS and kind == RunStatus.SOLVED:
        kind = (
            RunStatus.EMBODIED_FAILED.value
        )  # planned, but the plans did not execute in the kitchen
    name = FAILED_STATE_NAMES.get(kind) or kind.replace("_", " ").title().replace(" ", "")
    return Failed(name=name, message=reason_line(kind, str(reason)), data=dict(result))


def start_line(config: Mapping[str, Any]) -> str:
    """The flow run's first log line: what the job plans, with which planner settings."""
    method = str(config["method"]["name"])
    what = {"sa": "SA", "ma": "MA"}.get(method, "TwoStep")
    if method == "twostep":
        what += f" with {config['decomposer']['name']} subgoals"
    planner_settings = config.get("planner") or {}
    return (
        f"start {job_name(config)}: {what} on {config['domain']['name']} task "
        f"{config.get('task')}, N = {1 if method == 'sa' else config.get('agents')}, seed "
        f"{config.get('seed')}; planner {planner_settings.get('alias')}, "
        f"{planner_settings.get('time_limit_s')} s"
    )


@flow(name="twostep-job", persist_result=False, validate_parameters=False, log_prints=False)
def job_flow(job: dict[str, Any]) -> dict[str, Any] | State[Any]:
    """One job (``job``: the config groups it reads); the steps, the LLM calls among them,
    run as tasks and the library keeps the control flow; the flow run's log says what
    each step did. A job that did not succeed ends its flow run Failed
    (:func:`final_state`)."""
    built, stats, submit = running_job()
    flow_log(start_line(job))
    # The job's tags are its flow run's (to find it); its task runs carry none: a tagged
    # task run asks the server for tag concurrency limits (an API call and a client each).
    with TagsContext(current_tags=set()):
        result = built.run(prefect_steps(stats, submit=submit)).to_dict()
    flow_log(f"result: {format_summary(result, job_name(job))}", not result.get("success"))
    return final_state(result)


def flow_parameters(config: Mapping[str, Any]) -> dict[str, Any]:
    """The flow run's parameters: the job's config without the groups its method never
    reads (``decomposer`` but for TwoStep, ``llm`` but for its LLM decomposer) or that
    are empty; credentials inside URLs masked."""
    method = str(config["method"]["name"])
    decomposer = str((config.get("decomposer") or {}).get("name"))
    used = {
        key: value
        for key, value in config.items()
        if value is not None and is_relevant(f"{key}.", method, decomposer)
    }
    return dict(redact_config(used))


def run_flow(
    built: Job,
    config: Mapping[str, Any],
    api_url: str,
    name: str,
    flow_tags: Sequence[str] = (),
    dask_address: str | None = None,
    stats: StepStats | None = None,
) -> dict[str, Any]:
    """Run the ``built`` job as its flow on the server at ``api_url`` (``config``: its
    resolved config, the flow's parameter); return its result.json dict, counting its task
    runs in ``stats``. Raise the job's error if it failed."""
    quiet_logs(str(config["orchestration"]["prefect_log_level"]))
    storage = Path(config["orchestration"]["result_storage"])
    storage.mkdir(parents=True, exist_ok=True)
    submit = config["orchestration"]["task_runner"] == "dask"
    # The results' folder named here: Prefect does not ask the server for a default one.
    options: dict[str, Any] = {"result_storage": storage}
    runner = _task_runner(config, dask_address)
    if runner is not None:
        options["task_runner"] = runner
    running = _RUNNING.set((built, stats if stats is not None else StepStats(), submit))
    try:
        with job_settings(api_url, storage), tags(*flow_tags), open_client(api_url) as client:
            # The parameter is what Prefect stores and shows: no URL credentials in it.
            job: dict[str, Any] = {"job": flow_parameters(config)}
            job_flow_run = (
                _flow_with(storage) if runner is None else job_flow.with_options(**options)
            )
            # Created with its name: the engine would create it unnamed, then rename it.
            created = client.create_flow_run(
                job_flow_run,
                name=name,
                parameters=job_flow_run.serialize_parameters(job),
                state=Pending(),
                tags=TagsContext.get().current_tags,
            )
            state = run_flow_sync(
                job_flow_run, flow_run=created, parameters=job, return_type="state"
            )
    finally:
        _RUNNING.reset(running)
    assert isinstance(state, State)
    result = state.result(raise_on_failure=False)
    if isinstance(result, BaseException):
        raise result  # the job raised: the caller records it as failed
    assert isinstance(result, dict)  # the job's result, whatever the flow run's state
    return result
