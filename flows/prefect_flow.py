"""The Prefect flow of one job: (domain, task, method, N, seed) -> result.json dict.

The flow holds no planning logic: it loads the job's config and calls
:func:`flows.step_stats.run_job` with the task-wrapped steps of :mod:`flows.tasks`, so each
planner call, LLM call, state progression and scoring shows up as a task run. Its
parameter is the job's resolved config (plain JSON, shown in the Prefect UI).

:func:`run_flow` runs it against a given API server with this job's settings: task
results persisted under ``orchestration.result_storage``, no ephemeral server (a
missing server is an error, not a silent 10-second start-up), and the Dask task runner
when ``orchestration.task_runner=dask``.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from prefect import flow, tags
from prefect.context import SettingsContext
from prefect.settings import (
    PREFECT_API_URL,
    PREFECT_FLOWS_HEARTBEAT_FREQUENCY,
    PREFECT_LOCAL_STORAGE_PATH,
    PREFECT_SERVER_ALLOW_EPHEMERAL_MODE,
    Settings,
    get_current_settings,
)

from flows.config import typed
from flows.step_stats import StepStats, run_job
from flows.tasks import prefect_steps


@flow(name="twostep-job", persist_result=False, validate_parameters=False, log_prints=False)
def job_flow(job: dict[str, Any]) -> dict[str, Any]:
    from omegaconf import OmegaConf

    cfg = typed(OmegaConf.create(job))
    stats = StepStats()
    orchestration = cfg.orchestration
    # The steps, the LLM calls among them, as task runs; the library keeps the control flow.
    steps = prefect_steps(stats, submit=orchestration.task_runner == "dask")
    result = run_job(cfg, steps=steps, stats=stats)
    return {"result": result.to_dict(), "stats": stats.to_dict()}


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


_SETTINGS: dict[tuple[str, str], Settings] = {}


def job_settings(api_url: str, storage: Path) -> SettingsContext:
    """Prefect settings of a job, built once per process (validating them takes 0.1 s)."""
    key = (api_url, str(storage))
    if key not in _SETTINGS:
        _SETTINGS[key] = get_current_settings().copy_with_update(
            updates={
                PREFECT_API_URL: api_url,
                PREFECT_LOCAL_STORAGE_PATH: str(storage),
                # A missing server is an error, never a silent ephemeral start-up.
                PREFECT_SERVER_ALLOW_EPHEMERAL_MODE: False,
                # Heartbeats detect crashed flow runs in deployments; here they only
                # cost a thread whose join adds up to a second to every job.
                PREFECT_FLOWS_HEARTBEAT_FREQUENCY: None,
            }
        )
    current = SettingsContext.get()
    assert current is not None  # Prefect enters a root settings context at import
    return SettingsContext(profile=current.profile, settings=_SETTINGS[key])


def run_flow(
    config: Mapping[str, Any],
    api_url: str,
    name: str,
    flow_tags: Sequence[str] = (),
    dask_address: str | None = None,
) -> tuple[dict[str, Any], StepStats]:
    """Run the job's flow on the server at ``api_url``; raise the job's error if it failed."""
    quiet_logs(str(config["orchestration"]["prefect_log_level"]))
    storage = Path(config["orchestration"]["result_storage"])
    storage.mkdir(parents=True, exist_ok=True)
    options: dict[str, Any] = {"flow_run_name": name}
    runner = _task_runner(config, dask_address)
    if runner is not None:
        options["task_runner"] = runner
    with job_settings(api_url, storage), tags(*flow_tags):
        state = job_flow.with_options(**options)(dict(config), return_state=True)
    output = state.result()  # raises the exception the job raised
    stats = StepStats(**output["stats"])
    return output["result"], stats
