"""The Hydra callback of a sweep (``hydra.callbacks.twostep`` in ``conf/config.yaml``).

:class:`SweepCallback` runs in the process that launches the sweep, whatever the launcher:

``on_run_start`` (a single run)
    checks that the output locations are writable (:mod:`flows.checks`) before
    Hydra creates the run directory: one line and exit 2;
``on_multirun_start``
    checks the output locations the same way, refuses a sweep directory that a running
    sweep owns, checks the MLflow store (one line and exit 2 before any job when it cannot be used),
    picks the Prefect server (the user's, the long-lived services' from
    ``twostep-services up``, or one started on demand by the first job), starts a Dask
    ``LocalCluster`` for ``task_runner=dask`` without an address, and writes the sweep's
    state (:mod:`flows.sweep_state`), which every job reads;
``on_multirun_end``
    prints the summary (:mod:`flows.console`), counts the sweep's Prefect flow runs on
    the server, stops the server it started by PID, closes the cluster, ends the MLflow
    parent run, and exits 1 if a job failed.

The sweep's Prefect server: :mod:`flows.servers`; its MLflow parent run: :mod:`flows.tracking`.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import shlex
import socket
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from hydra.types import RunMode
from omegaconf import DictConfig

from flows.console import footer, header
from flows.environment import quiet_defaults
from flows.servers import (
    ServerSettings,
    count_flow_runs,
    is_healthy,
    pid_alive,
    read_info,
    stop_sweep_server,
)
from flows.spelling import sweep_notice
from flows.sweep_report import Drawing
from flows.sweep_results import RESULTS_CSV, format_results, result_rows, write_results_csv
from flows.sweep_state import (
    SweepState,
    count_jobs,
    job_records,
    launcher_parallelism,
    sweep_key,
    sweep_overrides,
)
from flows.sweep_timing import sweep_timing, timing_line
from twostep.util.files import write_json_atomic, write_text_atomic
from twostep.util.outcome import JobStatus
from twostep.util.redaction import redact_text


def _set_hydra_config(config: DictConfig) -> None:
    from hydra.core.hydra_config import HydraConfig

    if not HydraConfig.initialized():
        HydraConfig.instance().set_config(config)  # for ${hydra:...} in output.root


def _check_before_writing(config: DictConfig, run_dir: Path) -> None:
    """Before Hydra writes the run's (or sweep's) directory and config: no key where a
    variable's name belongs, every value in range and the task there (a single run's, or
    every value a sweep lists), every output location writable. One line, exit 2."""
    from flows.checks import (
        ValidationError,
        check_writable,
        input_problem,
        secret_problem,
        sweep_problem,
    )

    problem = secret_problem(config)
    if problem is None:
        multirun = config.hydra.mode == RunMode.MULTIRUN
        problem = sweep_problem(config) if multirun else input_problem(config)
    if problem is None:
        try:
            check_writable(config, run_dir)
        except ValidationError as error:
            problem = str(error)
    if problem is not None:
        print(f"error: {problem}", file=sys.stderr, flush=True)
        sys.exit(2)


# The launchers' own lines ("Launching 8 jobs locally", "#3 : domain=...") between the
# progress lines: shown only with hydra.verbose.
LAUNCHER_LOGGERS = (
    "flows.launcher",
    "hydra._internal.core_plugins.basic_launcher",
    "hydra_plugins.hydra_joblib_launcher._core",
    "hydra_plugins.hydra_joblib_launcher.joblib_launcher",
    "hydra_plugins.hydra_submitit_launcher.submitit_launcher",
)


def _launcher_lines(config: DictConfig) -> None:
    import logging

    level = logging.DEBUG if config.hydra.verbose else logging.WARNING
    for name in LAUNCHER_LOGGERS:
        logging.getLogger(name).setLevel(level)


def _refuse_running_sweep(sweep_dir: Path) -> None:
    """Two sweeps must never share a sweep directory (its server, parent run, job
    records): refuse one whose directory belongs to a sweep that is still running.
    A killed sweep's directory is resumed (its launching process is gone)."""
    other = SweepState.load(sweep_dir)
    if other is None or other.main_pid == os.getpid():
        return
    if other.hostname and other.hostname != socket.gethostname():
        return  # its PID means nothing here
    if pid_alive(other.main_pid):
        print(
            f"error: another sweep (pid {other.main_pid}) is running in {sweep_dir}: "
            "wait for it, or choose another hydra.sweep.dir",
            file=sys.stderr,
            flush=True,
        )
        sys.exit(2)


def mask_credentials(files: list[Path]) -> None:
    """Rewrite each file with the credentials inside its URLs masked (``https://***@host``);
    a file without any is left untouched."""
    for path in files:
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, ValueError):
            continue
        masked = redact_text(text)
        if masked != text:
            write_text_atomic(path, masked)


def _ui_links(state: SweepState, output_root: str) -> list[str]:
    """The sweep's last lines: the Prefect UI's flow runs of this sweep (its tag) when
    ``twostep-services`` serves them (a sweep's own server is stopped by now), the MLflow
    UI's experiment page, and the exact command that reports the sweep."""
    from urllib.parse import quote

    from flows.services import experiment_page, read_record
    from flows.tracking.runs import sweep_run_ids

    services = read_record(output_root)
    lines = []
    prefect = services.get("prefect")
    if prefect is not None and state.prefect_api_url == prefect.url and prefect.healthy():
        lines.append(f"prefect UI: {prefect.ui_url}?tag={quote(state.run_tag, safe=':')}")
    ids = sweep_run_ids(state)
    if state.tracking_uri is None or (ids is None and state.experiment is None):
        return lines
    mlflow = services.get("mlflow")
    served = f"sqlite:///{Path(output_root).resolve() / 'mlflow.db'}"  # the services' store
    if ids is not None and state.tracking_uri == served:
        if mlflow is not None and mlflow.healthy():
            lines.append(f"mlflow UI: {experiment_page(mlflow.url, ids[0])}")
        else:
            lines.append(
                f"mlflow UI: twostep-services up --root {output_root}, then experiment {ids[0]}"
            )
    experiment = ids[0] if ids is not None else str(state.experiment)
    command = ["twostep-report", "--experiment", experiment, "--tracking-uri", state.tracking_uri]
    lines.append(f"report: {redact_text(shlex.join(command))}")
    return lines


def _written(path: Path, write: Callable[[], object]) -> bool:
    """Write a file of the sweep's end; a full disk or a read-only folder is one warning
    line (the summary is still printed)."""
    try:
        write()
    except OSError as error:
        print(f"warning: {path} not written ({error.strerror or error})", file=sys.stderr)
        return False
    return True


class SweepCallback(Callback):
    """Sets up and tears down what the jobs of one multirun share (see module doc)."""

    composed = False  # Hydra made one: the command line composed into a config

    def __init__(self) -> None:
        self._cluster: Any = None
        self._state: SweepState | None = None
        self._drawing: Drawing | None = None
        SweepCallback.composed = True

    def __getstate__(self) -> dict[str, Any]:
        # joblib pickles the callbacks into its workers: the cluster stays here.
        return {}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self._cluster = None
        self._state = None
        self._drawing = None

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        # Before Hydra creates the run directory: a read-only output root is one line.
        _set_hydra_config(config)
        _check_before_writing(config, Path(str(config.hydra.run.dir)))

    def on_job_start(self, config: DictConfig, **kwargs: Any) -> None:
        # Hydra has just saved the job's config and overrides (and a sweep's multirun.yaml):
        # credentials inside URLs are masked in those copies (the job keeps its values).
        from flows.launcher import current_launch

        runtime = config.hydra.runtime.output_dir
        files = []
        # The twostep launcher writes them masked already (flows/run_job.py).
        if config.hydra.output_subdir is not None and current_launch() is None:
            folder = Path(str(runtime)) / str(config.hydra.output_subdir)
            files += [folder / "config.yaml", folder / "hydra.yaml", folder / "overrides.yaml"]
        if config.hydra.mode == RunMode.MULTIRUN:
            files.append(Path(str(config.hydra.sweep.dir)) / "multirun.yaml")
        mask_credentials(files)

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        quiet_defaults()
        _launcher_lines(config)
        _set_hydra_config(config)
        sweep_dir = Path(str(config.hydra.sweep.dir)).resolve()
        _check_before_writing(config, sweep_dir)
        _refuse_running_sweep(sweep_dir)
        said = sweep_notice(config)  # the old spelling of a method, once per sweep
        if said:
            print(said, file=sys.stderr, flush=True)
        overrides = sweep_overrides(config)
        state = SweepState(
            sweep_dir=str(sweep_dir),
            started_at=time.time(),
            main_pid=os.getpid(),
            hostname=socket.gethostname(),
            total_jobs=count_jobs(config),
            parallel=launcher_parallelism(config),
            sweep_key=sweep_key(overrides),
            overrides=overrides,
            command=redact_text(shlex.join(["twostep", *sys.argv[1:]])),
        )
        if config.mlflow.enabled:
            from flows.tracking.runs import TrackingError, check_store, experiment_name_for

            try:
                check_store(str(config.mlflow.tracking_uri), float(config.mlflow.connect_timeout_s))
            except TrackingError as error:
                print(f"error: {error}", file=sys.stderr, flush=True)
                sys.exit(2)
            state.tracking_uri = str(config.mlflow.tracking_uri)
            location = config.mlflow.artifact_location
            state.artifact_location = str(location) if location else None
            state.experiment = config.mlflow.experiment or experiment_name_for(
                overrides, state.sweep_key
            )
        orchestration = config.orchestration
        # Read by Prefect at import, here and in Dask workers started below.
        os.environ.setdefault("PREFECT_LOGGING_LEVEL", str(orchestration.prefect_log_level))
        if orchestration.prefect is not False:  # null (auto): sweeps always use Prefect
            from flows.services import running_prefect_api

            external = running_prefect_api(orchestration, str(config.output.root))
            if external:
                state.prefect_api_url = str(external)
            else:
                state.server = asdict(ServerSettings.from_config(orchestration))
                # Also when an exception skips on_multirun_end (Hydra raises after a batch).
                atexit.register(stop_sweep_server, state)
        if orchestration.task_runner == "dask":
            state.dask_address = self._dask_address(orchestration)
        state.save()
        self._state = state
        # Ready to draw the sweep's report at its end (imports matplotlib meanwhile).
        self._drawing = Drawing(sweep_dir)
        print(header(state), flush=True)

    def _dask_address(self, orchestration: Any) -> str:
        if orchestration.dask_address:
            return str(orchestration.dask_address)
        from distributed import LocalCluster

        self._cluster = LocalCluster(  # type: ignore[no-untyped-call]
            n_workers=int(orchestration.dask_workers),
            threads_per_worker=1,
            host="127.0.0.1",
            dashboard_address=None,
        )
        atexit.register(self._cluster.close)
        return str(self._cluster.scheduler_address)

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        state = self._state
        if state is None:
            return
        from flows.faults import UNRECORDED

        # A job that met a fault after its record was written: its fault record, kept
        # here when the disk could not take it, replaces that record.
        kept = {r.get("num"): r for r in UNRECORDED}
        records = [kept.pop(r.get("num"), r) for r in job_records(Path(state.sweep_dir))]
        records += kept.values()
        failed = [r for r in records if r.get("status") == JobStatus.FAILED]
        summary: dict[str, Any] = {
            "jobs_total": state.total_jobs,
            "jobs_done": len(records),
            "jobs_failed": len(failed),
            "jobs_timeout": sum(1 for r in records if r.get("status") == JobStatus.TIMEOUT),
            "jobs_reused": sum(1 for r in records if r.get("reused")),
            # stored entries not used (another job's, changed, cut short): computed again
            "jobs_store_refused": sum(1 for r in records if r.get("store_refused")),
            "jobs_not_stored": sum(1 for r in records if r.get("not_stored")),
            # could not start or finish writing: a full disk, a read-only folder
            "jobs_fault": sum(1 for r in records if r.get("fault")),
            "plan_cache_hits": sum(int(r.get("plan_cache_hits") or 0) for r in records),
            "planner_calls_run": sum(int(r.get("plan_calls") or 0) for r in records),
            "sweep_wall_time_s": round(time.time() - state.started_at, 3),
            **sweep_timing(records, time.time() - state.started_at),
        }
        # The report draws in its own process meanwhile (flows/sweep_report.py).
        drawing, self._drawing = self._drawing, None
        if drawing is not None and records:
            drawing.start()
        elif drawing is not None:
            drawing.cancel()
            drawing = None
        info = read_info(state.folder / "server.json")
        api_url = state.prefect_api_url or (info.api_url if info else None)
        if api_url and is_healthy(api_url):
            summary["prefect_api_url"] = api_url
            summary["prefect_flow_runs"] = count_flow_runs(api_url, state.run_tag)
        if "flows.prefect_flow" in sys.modules:  # jobs ran flows in this process (basic launcher)
            from flows.prefect_flow import flush_to_server

            flush_to_server()
        summary["prefect_server_started"] = stop_sweep_server(state)
        if self._cluster is not None:
            with contextlib.suppress(Exception):
                self._cluster.close()
        rows = result_rows(records)
        results = Path(state.sweep_dir) / RESULTS_CSV
        written = _written(results, lambda: write_results_csv(rows, results))
        summary_file = state.folder / "summary.json"
        _written(summary_file, lambda: write_json_atomic(summary_file, summary))
        print(footer(state, summary, failed), flush=True)
        print(timing_line(summary), flush=True)
        table = format_results(rows)
        if table:
            print(f"{table}\nresults: {results if written else 'not written'}", flush=True)
        if state.tracking_uri is not None:  # MLflow's client, while the report draws
            with contextlib.suppress(Exception):
                import mlflow.tracking  # noqa: F401
        report = drawing.files() if drawing is not None and written else []
        if drawing is not None and not written:  # no results file (a full disk): no report
            drawing.cancel()
        files = [(results, None), *report] if written else []
        self._end_parent_run(state, summary, bool(failed), files)
        for line in _ui_links(state, str(config.output.root)):
            print(line, flush=True)
        if failed:
            sys.exit(1)

    @staticmethod
    def _end_parent_run(
        state: SweepState,
        summary: Mapping[str, Any],
        failed: bool,
        files: list[tuple[Path, str | None]],
    ) -> None:
        if state.tracking_uri is None:
            return
        from flows.tracking.runs import end_sweep_run

        metrics = {
            key: float(value)
            for key, value in summary.items()
            if isinstance(value, int | float) and not isinstance(value, bool)
        }
        try:
            end_sweep_run(state, metrics, failed, files)
        except Exception as error:  # the jobs are recorded; the summary metrics are extra
            from flows.console import one_line

            print(
                f"warning: could not end the MLflow parent run: {one_line(error)}",
                file=sys.stderr,
            )
