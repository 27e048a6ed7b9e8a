"""One job, start to finish: reuse or compute, write its files, record it.

:func:`execute_job` is what the ``twostep`` command runs for every job, in a single run
and in each job of a sweep (any launcher):

1. check the job's input (values in range, data root, domain, task: :func:`flows.build.
   check_job`) and the MLflow store (single run; a sweep's callback checked it already):
   one line before any work, nothing heavy imported yet;
2. a job whose key is in the job store as a whole result is read back, not recomputed
   (``reused``); a process computing a job holds its lock, so a second one waits for it;
3. otherwise build it from its config, once (:func:`flows.build.build_job`), and run it
   (:func:`compute_job`): as the Prefect flow on the sweep's server (started on demand by
   the first job that needs it, then waited for); a single run as a flow on a running
   server (``twostep-services up``) or, with ``orchestration.prefect=true``, on a
   temporary server of its own; otherwise (a single run by default,
   ``orchestration.prefect=false``) the library directly;
4. write result.json and the other files to the job's Hydra directory;
5. under the job's lock, log params, metrics, artifacts and status to the job's MLflow
   run (:class:`~flows.tracking.runs.JobRunLog`), found again by ``twostep.job_key`` (a
   re-run adds no duplicate), child of the sweep's parent run; skipped when the run the
   job store remembers is still in the MLflow store, logged again from the job store's
   record when it is not (MLflow is a view the job store can rebuild).

A job that raises is recorded as ``failed`` (result.json, MLflow status and error), is
not stored (a re-run tries again), and the sweep goes on.
"""

from __future__ import annotations

import os
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flows.artifacts import write_job_files
from flows.build import Job, build_job, check_job, limit_message
from flows.checks import JobError
from flows.config import TwostepConfig, agents_run, typed
from flows.console import one_line
from flows.identity import job_name
from flows.services import running_prefect_api
from flows.spelling import respell
from flows.status import JobStatus, job_status
from flows.step_stats import StepStats, counting_steps
from flows.store import JobEntry, JobStore, job_config, job_inputs, job_key
from flows.sweep_state import SweepState
from flows.tracking.context import run_context_tags
from flows.tracking.runs import (
    DEFAULT_EXPERIMENT,
    JobRunLog,
    check_store,
    job_record,
    missing_artifacts,
    run_exists,
)
from flows.wording import worded
from twostep.embodied.run import draws_pictures
from twostep.llm.client import LLMScriptError
from twostep.pddl import PDDLError
from twostep.programs.processes import ResourceLimitError
from twostep.tasks.benchmark import BenchmarkError
from twostep.util.outcome import RunStatus

# Errors in what the user asked for: one line, no traceback.
INPUT_ERRORS: tuple[type[Exception], ...] = (BenchmarkError, PDDLError, JobError, LLMScriptError)


@dataclass
class JobOutcome:
    name: str
    key: str
    result: dict[str, Any]  # result.json as written
    status: JobStatus
    error: str | None
    reused: bool
    stats: StepStats = field(default_factory=StepStats)
    timings: dict[str, float] = field(default_factory=dict)
    input_error: bool = False  # the job's input was bad (unknown task, malformed PDDL)
    # Where the job's wall time went (the sweep's job record and bench/bench_sweep.py only:
    # neither result.json nor MLflow): setup (config, key, checks, job store lookup),
    # compute (task, method, flow), store (saving the result), files, mlflow.
    phases: dict[str, float] = field(default_factory=dict)
    mlflow_run_id: str | None = None
    tracking_error: str | None = None  # logging failed; the result itself is safe
    # why a stored entry of this job was not used (not this job's, changed, cut short)
    refused_entries: list[str] = field(default_factory=list)
    not_stored: str | None = None  # why the finished job could not be stored (disk full, ...)


def failed_result(
    config: dict[str, Any], error: str, status: str = RunStatus.FAILED.value
) -> dict[str, Any]:
    """The result of a job that raised (``status``: ``failed``, or ``resource_limit`` for
    a limit that ended it, :class:`~twostep.programs.processes.ResourceLimitError`)."""
    return {
        "domain": config["domain"]["name"],
        "task": config.get("task"),
        "method": config["method"]["name"],
        "agents": config.get("agents"),
        "seed": config.get("seed"),
        "success": False,
        "status": status,
        "message": error,
        "error": error,
    }


# ----------------------------------------------------------------- computing


def prefect_target(cfg: TwostepConfig, sweep: SweepState | None) -> tuple[bool, str | None]:
    """Whether this job runs as a Prefect flow, and the API URL of a running server to
    use (None: the sweep's server, or one of the job's own).

    ``orchestration.prefect``: ``false`` never; ``true`` always (a single run starts a
    temporary server if none is running); ``null`` (auto, the default) in sweeps, and in
    single runs only when a server is already up (``twostep-services up``, or
    ``orchestration.prefect_api_url``): a single run never waits for a server start.
    """
    mode = cfg.orchestration.prefect
    if mode is False:
        return False, None
    if sweep is not None:
        return bool(sweep.server or sweep.prefect_api_url), None
    running = running_prefect_api(cfg.orchestration, str(cfg.output.root))
    if running:
        return True, running
    return mode is True, None


def _prefect_api(
    cfg: TwostepConfig, sweep: SweepState | None, external: str | None
) -> tuple[Any, bool]:
    """The server this job uses (started now if the sweep has none yet) and whether
    this job owns it (a single run's own server, stopped when the job ends)."""
    from flows.servers import (
        ServerError,
        ServerInfo,
        ServerSettings,
        is_healthy,
        spawn_server,
        sweep_server,
    )

    if sweep is not None:
        return sweep_server(sweep), False
    if external:
        if not is_healthy(external, timeout_s=10):
            raise ServerError(f"no Prefect server answers at {external}")
        return ServerInfo(external, None, time.time(), 10.0), False
    settings = ServerSettings.from_config(cfg.orchestration)
    return spawn_server(settings, owner_pid=os.getpid()), True


def compute_job(
    cfg: TwostepConfig,
    config: dict[str, Any],
    name: str,
    sweep: SweepState | None,
    stats: StepStats,
) -> tuple[dict[str, Any], dict[str, float]]:
    """Build the job once and run it; return its result dict and timings
    (``server_wait_s``; for a flow, ``flow_wall_s``: importing Prefect, waiting, the flow
    run). Bad input fails in the build, before any server starts for this run."""
    with build_job(cfg) as job:
        stats.add(task_load_s=job.task_load_s)
        use_prefect, external = prefect_target(cfg, sweep)
        if not use_prefect:
            return job.run(counting_steps(stats)).to_dict(), {"server_wait_s": 0.0}
        return _run_flow(job, cfg, config, name, sweep, external, stats)


def _run_flow(
    job: Job,
    cfg: TwostepConfig,
    config: dict[str, Any],
    name: str,
    sweep: SweepState | None,
    external: str | None,
    stats: StepStats,
) -> tuple[dict[str, Any], dict[str, float]]:
    """The job as a Prefect flow on its server (spawned before Prefect is imported, so
    that the two overlap)."""
    server, owned = _prefect_api(cfg, sweep, external)
    # Read by Prefect at import: the job's console shows warnings, not every API call.
    os.environ.setdefault("PREFECT_LOGGING_LEVEL", str(cfg.orchestration.prefect_log_level))
    flow_start = time.perf_counter()
    from flows.prefect_flow import flush_to_server, run_flow
    from flows.servers import stop_server, wait_until_healthy

    dask_address = (sweep.dask_address if sweep else None) or cfg.orchestration.dask_address
    try:
        start = time.perf_counter()
        wait_until_healthy(server)
        waited = time.perf_counter() - start
        tags = _flow_tags(config, sweep)
        result = run_flow(job, config, server.api_url, name, tags, dask_address, stats)
    finally:
        if owned:
            flush_to_server()
            stop_server(server)
    return result, {"server_wait_s": waited, "flow_wall_s": time.perf_counter() - flow_start}


def _flow_tags(config: dict[str, Any], sweep: SweepState | None) -> list[str]:
    """Tags to find a job's flow runs in the Prefect UI and API."""
    method = config["method"]["name"]
    tags = [
        "twostep",
        f"domain:{config['domain']['name']}",
        f"task:{config.get('task')}",
        f"method:{method}",
        f"agents:{agents_run(str(method), config.get('agents'))}",  # the N it runs: SA 1
        f"seed:{config.get('seed')}",
    ]
    if method == "twostep":
        tags.append(f"decomposer:{config['decomposer']['name']}")
    if sweep is not None:
        tags += [sweep.sweep_tag, sweep.run_tag]
    return tags


# ----------------------------------------------------------------- one job


def _experiment(cfg: TwostepConfig, sweep: SweepState | None) -> str:
    if sweep is not None and sweep.experiment:
        return sweep.experiment
    return str(cfg.mlflow.experiment or DEFAULT_EXPERIMENT)


def execute_job(
    cfg: object, job_dir: Path, sweep: SweepState | None = None, tracking_worker: bool = False
) -> JobOutcome:
    """Run (or reuse) one job and record it; see the module docstring for the order.

    Raises :class:`~flows.tracking.runs.TrackingError` when the MLflow store of a single run
    cannot be used, before any planning; every other error is a ``failed`` outcome.

    ``tracking_worker`` (single runs of the command): MLflow's store is prepared while the
    job runs (:class:`~flows.tracking.runs.JobRunLog`); the job still returns after its run
    is logged.
    """
    start, started_at = time.perf_counter(), time.time()
    said = respell(cfg)  # the old spelling (method=twostep decomposer=plan-deal), once
    if said and sweep is None:  # a sweep says it once, at its start (flows.sweep_callback)
        print(said, file=sys.stderr, flush=True)
    config = job_config(cfg)
    inputs = job_inputs(config)
    key = job_key(config, inputs)
    entry = JobEntry.of(config, key, inputs)
    cfg = typed(cfg)
    refused = _input_problem(cfg)  # values, data, keys: one line, before any work
    tracking = bool(cfg.mlflow.enabled)
    if tracking and sweep is None:
        check_store(str(cfg.mlflow.tracking_uri), float(cfg.mlflow.connect_timeout_s))
    store = JobStore(str(cfg.orchestration.job_store))
    reuse = cfg.orchestration.reuse_results and refused is None
    stored = store.load_or_claim(key, expect=entry) if reuse else None  # only if it is this job's
    destination = MlflowDestination(str(cfg.mlflow.tracking_uri), _experiment(cfg, sweep))
    run_log = None
    held = destination.held_run(store, key) if tracking else None
    refill = held is not None and _artifacts_gone(destination, held, job_name(config))
    if refill:
        held = None  # logged again below: its run gets the job's files back
    if tracking and held is None:
        location = cfg.mlflow.artifact_location
        run_log = JobRunLog.open(
            destination.uri, location, destination.experiment, sweep, single_run=tracking_worker
        )
    setup_s = time.perf_counter() - start
    try:
        outcome, details = _run_or_reuse(cfg, config, entry, sweep, stored, refused, store, start)
        outcome.refused_entries = [why for k, why in store.refused.items() if k == key]
        outcome.not_stored = store.unwritten.get(key)
        outcome.phases["setup_s"] = setup_s
        outcome.mlflow_run_id = held
        files_start = time.perf_counter()
        pictures = draws_pictures(cfg.executor.render, int(cfg.seed), in_sweep=sweep is not None)
        files = write_job_files(job_dir, outcome.result, pictures)
        if details:
            (job_dir / "error.txt").write_text(details)
        tracking_start = time.perf_counter()
        outcome.phases["files_s"] = tracking_start - files_start
        if run_log is not None:
            # Under the job's lock: two processes that both hold this job (two sweeps at
            # once) never both create its run.
            with store.locked(key):
                window = (started_at, time.time())
                _log_run(run_log, outcome, config, files, store, destination, window, refill)
    finally:
        store.release(key)  # a process waiting for this job reads its result and run now
        if run_log is not None:
            run_log.close()
    # With MLflow logging: what the job cost end to end (the progress record, the bench).
    outcome.timings["tracking_s"] = outcome.phases["mlflow_s"] = (
        time.perf_counter() - tracking_start
    )
    outcome.timings["job_wall_time_s"] = job_wall = time.perf_counter() - start
    outcome.timings["orchestration_overhead_s"] = max(0.0, job_wall - _work(outcome))
    return outcome


def _input_problem(cfg: TwostepConfig) -> str | None:
    """What is wrong with the job's input before any work (None: nothing found): values
    out of range, a data root, domain or task that is not there (:func:`check_job`)."""
    try:
        check_job(cfg)
    except INPUT_ERRORS as exc:
        return worded(one_line(exc, name_type=False))
    return None


def _run_or_reuse(
    cfg: TwostepConfig,
    config: dict[str, Any],
    entry: JobEntry,
    sweep: SweepState | None,
    stored: dict[str, Any] | None,
    refused: str | None,
    store: JobStore,
    start: float,
) -> tuple[JobOutcome, str | None]:
    """The job's outcome (the stored result, or computed and stored now) and, for a job
    that raised, its traceback (``entry``: its key, job and inputs; ``start``: when it
    started)."""
    key, name = entry.key, job_name(config)
    stats, error, details, status = StepStats(), refused, None, RunStatus.FAILED.value
    input_error = refused is not None
    compute_timings: dict[str, float] = {"server_wait_s": 0.0}
    phases: dict[str, float] = {}
    if stored is not None:
        result = stored
    elif error is None:
        compute_start = time.perf_counter()
        try:
            result, compute_timings = compute_job(cfg, config, name, sweep, stats)
        except INPUT_ERRORS as exc:
            error, input_error = worded(one_line(exc, name_type=False)), True
        except ResourceLimitError as exc:  # worded with the limit's key; never stored
            said = RuntimeError(limit_message(exc.reached))
            error, status = one_line(said, name_type=False), RunStatus.RESOURCE_LIMIT.value
        except Exception as exc:  # the library's words name the config keys (flows.wording)
            error, details = worded(one_line(exc)), traceback.format_exc()
        store_start = time.perf_counter()
        phases["compute_s"] = store_start - compute_start
        if error is None:
            # unless it did not finish (llm_error, error); sealed with its inputs
            store.save(key, config, result, entry.inputs)
        phases["store_s"] = time.perf_counter() - store_start
    if error is not None:
        result = failed_result(config, error, status)
    outcome = _outcome(name, key, result, stored is not None, stats, compute_timings, start)
    outcome.input_error = input_error
    outcome.phases.update(phases)
    return outcome, details


def _work(outcome: JobOutcome) -> float:
    """What the job spent on work, not orchestration: fresh planner and LLM calls, and
    waiting for its server."""
    stats = outcome.stats
    return outcome.timings["server_wait_s"] + stats.planner_wall_s + stats.llm_wall_s


def _outcome(
    name: str,
    key: str,
    result: dict[str, Any],
    reused: bool,
    stats: StepStats,
    compute_timings: dict[str, float],
    start: float,
) -> JobOutcome:
    """The job's outcome; its result gains ``job_key`` and ``orchestration`` (what ran
    where, and the timings so far)."""
    status, status_error = job_status(result)
    outcome = JobOutcome(name, key, result, status, status_error, reused, stats, compute_timings)
    job_wall = time.perf_counter() - start
    outcome.timings = {
        "job_wall_time_s": job_wall,
        **compute_timings,
        "orchestration_overhead_s": max(0.0, job_wall - _work(outcome)),
    }
    outcome.result = {
        **result,
        "job_key": key,
        "orchestration": {
            "reused": reused,
            "prefect": "flow_wall_s" in compute_timings,
            **stats.to_dict(),
            **{k: round(v, 4) for k, v in outcome.timings.items()},
        },
    }
    return outcome


@dataclass(frozen=True)
class MlflowDestination:
    """Where a job's run goes: a tracking store and an experiment in it."""

    uri: str
    experiment: str

    @property
    def name(self) -> str:
        """How the job store remembers it (:meth:`JobStore.logged_to`)."""
        return f"{self.uri} {self.experiment}"

    def held_run(self, store: JobStore, key: str) -> str | None:
        """The job's run, logged here before, if the store still holds it (a lost or
        emptied store, or a deleted run: None, and the job is logged again)."""
        run_id = store.logged_to(key).get(self.name)
        return run_id if run_id is not None and run_exists(self.uri, run_id) else None


def _log_run(
    run_log: JobRunLog,
    outcome: JobOutcome,
    config: dict[str, Any],
    files: list[tuple[Path, str | None]],
    store: JobStore,
    destination: MlflowDestination,
    window: tuple[float, float],
    refill: bool = False,
) -> None:
    """Log the job to its MLflow run (``window``: when the job started and ended, the run's
    start and end) and remember where and what; a failure is a warning
    (the result is stored: the next run logs it again).

    The job store is the source of truth and MLflow a view of it: a job logged here
    before whose run the store has lost is logged again with the record it had (same
    params, metrics, tags; the files of its first run directory when they are still
    there), tagged ``twostep.restored_from_job_store``.
    """
    try:
        held = None if refill else destination.held_run(store, outcome.key)
        if held is not None:  # a parallel process logged it meanwhile
            outcome.mlflow_run_id = held
            return
        record = _restored_record(store, outcome.key, destination)
        if record is None:
            record = job_record(
                key=outcome.key,
                name=outcome.name,
                status=outcome.status.value,
                error=outcome.error,
                reused=outcome.reused,
                config=config,
                result=outcome.result,
                timings=outcome.timings,
                files=files,
                tags=run_context_tags(),
                window=window,
            )
        elif not all(Path(path).is_file() for path, _ in record["files"]):
            record["files"] = [[str(path), folder] for path, folder in files]
        outcome.mlflow_run_id = run_log.log(record)
        record.pop("restored", None)
        store.mark_logged(
            outcome.key, destination.uri, destination.experiment, outcome.mlflow_run_id, record
        )
    except Exception as exc:
        outcome.tracking_error = one_line(exc)
        print(
            f"warning: {outcome.name}: not logged to MLflow: {outcome.tracking_error}",
            file=sys.stderr,
        )


def _artifacts_gone(destination: MlflowDestination, run_id: str, name: str) -> bool:
    """Whether the job's MLflow run lost its files (its artifact folder deleted): one
    line says so, and the job's files are logged to the run again."""
    gone = missing_artifacts(destination.uri, run_id)
    if gone is not None:
        print(
            f"warning: {name}: the files of its MLflow run {run_id} are gone ({gone}): "
            "logging them again from the job store",
            file=sys.stderr,
            flush=True,
        )
    return gone is not None


def _restored_record(
    store: JobStore, key: str, destination: MlflowDestination
) -> dict[str, Any] | None:
    """The record to log again when the store lost the job's run (None: not logged there
    before, or logged before the job store kept records)."""
    if destination.name not in store.logged_to(key):
        return None
    record = store.logged_record(key, destination.name)
    return None if record is None else {**record, "restored": True}
