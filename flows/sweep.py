"""What the jobs of one sweep share, the progress line, and the Hydra callback.

:class:`SweepCallback` (``hydra.callbacks.twostep`` in ``conf/config.yaml``) runs in the
process that launches the sweep, whatever the launcher:

``on_multirun_start``
    checks the MLflow store (one line and exit 2 before any job when it cannot be used),
    starts a Dask ``LocalCluster`` for ``task_runner=dask`` without an address, and
    writes ``<sweep dir>/.twostep/sweep.json``, which every job reads;
``on_multirun_end``
    prints the summary, counts the sweep's Prefect flow runs through the server's API,
    stops the server by PID, closes the cluster, ends the MLflow parent run, and exits 1
    if a job failed.

The costly shared services start **on demand**, under a file lock, by the first job
that needs them: the Prefect server (:func:`sweep_server`) and the MLflow experiment
and parent run (:func:`sweep_tracking`). Re-running a finished sweep therefore starts no
server and imports neither Prefect nor MLflow.

Jobs report to ``.twostep/jobs/<num>.json`` (one file each: nothing to lock between
joblib or submitit workers); the progress line is computed from those files.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import json
import os
import socket
import sys
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig

from flows.environment import quiet_defaults
from flows.server import (
    ServerError,
    ServerInfo,
    ServerSettings,
    file_lock,
    is_healthy,
    read_info,
    shared_server,
    stop_server,
)
from flows.store import write_json_atomic

if TYPE_CHECKING:
    from flows.tracking import Tracker

STATE_DIR = ".twostep"

# Overrides that say where or how a sweep runs, not what it computes: they do not
# change the sweep's identity (its experiment name and parent run).
_NOT_IDENTITY = ("hydra.", "hydra/", "orchestration.", "mlflow.", "output.")


@dataclass
class SweepState:
    """What the launching process tells every job of the sweep."""

    sweep_dir: str
    started_at: float
    main_pid: int
    hostname: str = ""
    total_jobs: int | None = None
    sweep_key: str = ""
    overrides: list[str] = field(default_factory=list)
    tracking_uri: str | None = None  # None: MLflow off
    artifact_location: str | None = None
    experiment: str | None = None
    server: dict[str, Any] | None = None  # ServerSettings for an on-demand server
    prefect_api_url: str | None = None  # a server the user runs (not ours to start or stop)
    dask_address: str | None = None

    @property
    def folder(self) -> Path:
        return Path(self.sweep_dir) / STATE_DIR

    @staticmethod
    def path(sweep_dir: Path) -> Path:
        return Path(sweep_dir) / STATE_DIR / "sweep.json"

    def save(self) -> None:
        write_json_atomic(self.path(Path(self.sweep_dir)), asdict(self))

    @classmethod
    def load(cls, sweep_dir: Path) -> SweepState | None:
        try:
            return cls(**json.loads(cls.path(sweep_dir).read_text()))
        except (OSError, ValueError, TypeError):
            return None

    @property
    def run_tag(self) -> str:
        """Prefect tag of this multirun's flow runs (a resumed sweep gets a new one)."""
        folder = Path(self.sweep_dir)
        return f"multirun:{folder.parent.name}_{folder.name}"

    @property
    def sweep_tag(self) -> str:
        """Prefect tag shared by every attempt of the same sweep."""
        return f"sweep:{self.sweep_key[:12]}"


# ----------------------------------------------------------------- shared services


def sweep_server(state: SweepState) -> ServerInfo:
    """The sweep's Prefect server: the user's, or ours, started by the first job asking."""
    if state.prefect_api_url:
        return ServerInfo(state.prefect_api_url, None, time.time(), 30.0)
    if state.server is None:
        raise RuntimeError("this sweep runs without Prefect (orchestration.prefect=false)")
    if state.hostname and socket.gethostname() != state.hostname:
        # e.g. SLURM: the launching host's 127.0.0.1 is out of reach, and so is its PID.
        raise ServerError(
            f"this job runs on {socket.gethostname()}, the sweep was launched on "
            f"{state.hostname}: set orchestration.prefect_api_url to a server both reach "
            "(or orchestration.prefect=false)"
        )
    return shared_server(
        state.folder / "server.json", ServerSettings(**state.server), state.main_pid
    )


def sweep_tracking(state: SweepState) -> tuple[Tracker, str, str]:
    """(Tracker, experiment id, parent run id), made by the first job that logs.

    Under the lock because the first MlflowClient on a new SQLite file creates its
    tables, which two processes must not do at once.
    """
    from flows.tracking import Tracker

    assert state.tracking_uri is not None and state.experiment is not None
    record = state.folder / "mlflow.json"
    with file_lock(state.folder / "mlflow.lock"):
        tracker = Tracker(state.tracking_uri, state.artifact_location)
        with contextlib.suppress(OSError, ValueError, KeyError):
            data = json.loads(record.read_text())
            return tracker, str(data["experiment_id"]), str(data["parent_run_id"])
        experiment_id = tracker.experiment_id(state.experiment)
        folder = Path(state.sweep_dir)
        parent = tracker.sweep_run(
            experiment_id,
            state.sweep_key,
            name=f"sweep {folder.parent.name}/{folder.name}",
            tags={
                "twostep.sweep_dir": state.sweep_dir,
                "twostep.overrides": " ".join(state.overrides),
            },
        )
        write_json_atomic(record, {"experiment_id": experiment_id, "parent_run_id": parent})
        return tracker, experiment_id, parent


# ----------------------------------------------------------------- sweep identity


def sweep_overrides(config: DictConfig) -> list[str]:
    """The sweep's command-line overrides that define what it computes, sorted.

    An experiment's grid is named by the command line that selects it
    (``experiment=paper``), not by the grid it expands to.
    """
    chosen: dict[str, str] = {}
    for item in config.hydra.overrides.task:
        key, _, value = str(item).partition("=")
        chosen[key] = value
    return sorted(
        f"{key}={value}"
        for key, value in chosen.items()
        if not key.lstrip("+~").startswith(_NOT_IDENTITY)
    )


def sweep_key(overrides: list[str]) -> str:
    return hashlib.sha256("\n".join(overrides).encode()).hexdigest()[:32]


def count_jobs(config: DictConfig) -> int | None:
    """How many jobs the basic sweeper will launch (None if it cannot be told)."""
    try:
        from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
        from hydra.core.override_parser.overrides_parser import OverridesParser

        params = config.hydra.sweeper.get("params") or {}
        arguments = [f"{k}={v}" for k, v in params.items()]
        arguments += [str(o) for o in config.hydra.overrides.task]
        parsed = OverridesParser.create().parse_overrides(arguments)
        batches = BasicSweeper.split_arguments(parsed, None)
        return sum(len(batch) for batch in batches)
    except Exception:  # another sweeper, or Hydra internals changed: progress shows "?"
        return None


# ----------------------------------------------------------------- progress


def _clock(seconds: float) -> str:
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def record_job(sweep_dir: Path, num: int, record: Mapping[str, Any]) -> None:
    write_json_atomic(Path(sweep_dir) / STATE_DIR / "jobs" / f"{num}.json", dict(record))


def job_records(sweep_dir: Path) -> list[dict[str, Any]]:
    records = []
    for path in sorted((Path(sweep_dir) / STATE_DIR / "jobs").glob("*.json")):
        with contextlib.suppress(OSError, ValueError):
            records.append(json.loads(path.read_text()))
    return records


def progress_line(state: SweepState) -> str:
    """``[3/4 done | 0 failed | 1 reused | 0:41 elapsed, ~0:14 left]``."""
    records = job_records(Path(state.sweep_dir))
    done = len(records)
    failed = sum(1 for r in records if r.get("status") == "failed")
    reused = sum(1 for r in records if r.get("reused"))
    elapsed = time.time() - state.started_at
    total = state.total_jobs
    parts = [f"{done}/{total if total is not None else '?'} done", f"{failed} failed"]
    if reused:
        parts.append(f"{reused} reused")
    timing = f"{_clock(elapsed)} elapsed"
    if total is not None and 0 < done < total:
        # Throughput so far, whatever the parallelism of the launcher.
        timing += f", ~{_clock(elapsed / done * (total - done))} left"
    parts.append(timing)
    return "[" + " | ".join(parts) + "]"


# ----------------------------------------------------------------- the callback


def _stop_sweep_server(state: SweepState) -> bool:
    info = read_info(state.folder / "server.json")
    if info is None:
        return False
    stop_server(info)
    return True


class SweepCallback(Callback):
    """Sets up and tears down what the jobs of one multirun share (see module doc)."""

    def __init__(self) -> None:
        self._cluster: Any = None
        self._state: SweepState | None = None

    def __getstate__(self) -> dict[str, Any]:
        # joblib pickles the callbacks into its workers: the cluster stays here.
        return {}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self._cluster = None
        self._state = None

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        from hydra.core.hydra_config import HydraConfig

        quiet_defaults()
        if not HydraConfig.initialized():
            HydraConfig.instance().set_config(config)  # for ${hydra:...} in output.root
        sweep_dir = Path(str(config.hydra.sweep.dir)).resolve()
        overrides = sweep_overrides(config)
        state = SweepState(
            sweep_dir=str(sweep_dir),
            started_at=time.time(),
            main_pid=os.getpid(),
            hostname=socket.gethostname(),
            total_jobs=count_jobs(config),
            sweep_key=sweep_key(overrides),
            overrides=overrides,
        )
        if config.mlflow.enabled:
            from flows.tracking import TrackingError, check_store, experiment_name_for

            try:
                check_store(str(config.mlflow.tracking_uri), float(config.mlflow.connect_timeout_s))
            except TrackingError as error:
                print(f"error: {error}", file=sys.stderr, flush=True)
                sys.exit(2)
            state.tracking_uri = str(config.mlflow.tracking_uri)
            location = config.mlflow.artifact_location
            state.artifact_location = str(location) if location else None
            state.experiment = config.mlflow.experiment or experiment_name_for(overrides)
        orchestration = config.orchestration
        # Read by Prefect at import, here and in Dask workers started below.
        os.environ.setdefault("PREFECT_LOGGING_LEVEL", str(orchestration.prefect_log_level))
        if orchestration.prefect:
            external = orchestration.prefect_api_url or os.environ.get("PREFECT_API_URL")
            if external:
                state.prefect_api_url = str(external)
            else:
                settings = ServerSettings(
                    home=str(orchestration.prefect_home),
                    host=str(orchestration.server_host),
                    startup_timeout_s=float(orchestration.server_startup_timeout_s),
                )
                state.server = asdict(settings)
                # Also when an exception skips on_multirun_end (Hydra raises after a batch).
                atexit.register(_stop_sweep_server, state)
        if orchestration.task_runner == "dask":
            state.dask_address = self._dask_address(orchestration)
        state.save()
        self._state = state
        print(_header(state), flush=True)

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
        records = job_records(Path(state.sweep_dir))
        failed = [r for r in records if r.get("status") == "failed"]
        summary: dict[str, Any] = {
            "jobs_total": state.total_jobs,
            "jobs_done": len(records),
            "jobs_failed": len(failed),
            "jobs_timeout": sum(1 for r in records if r.get("status") == "timeout"),
            "jobs_reused": sum(1 for r in records if r.get("reused")),
            "plan_cache_hits": sum(int(r.get("plan_cache_hits") or 0) for r in records),
            "planner_calls_run": sum(int(r.get("plan_calls") or 0) for r in records),
            "sweep_wall_time_s": round(time.time() - state.started_at, 3),
        }
        info = read_info(state.folder / "server.json")
        api_url = state.prefect_api_url or (info.api_url if info else None)
        if api_url and is_healthy(api_url):
            summary["prefect_api_url"] = api_url
            summary["prefect_flow_runs"] = _count_flow_runs(api_url, state.run_tag)
        if "flows.flow" in sys.modules:  # jobs ran flows in this process (basic launcher)
            from flows.flow import flush_to_server

            flush_to_server()
        summary["prefect_server_started"] = _stop_sweep_server(state)
        if self._cluster is not None:
            with contextlib.suppress(Exception):
                self._cluster.close()
        self._end_parent_run(state, summary, bool(failed))
        write_json_atomic(state.folder / "summary.json", summary)
        print(_footer(state, summary, failed), flush=True)
        if failed:
            sys.exit(1)

    @staticmethod
    def _end_parent_run(state: SweepState, summary: Mapping[str, Any], failed: bool) -> None:
        record = state.folder / "mlflow.json"
        if state.tracking_uri is None or not record.is_file():
            return  # no job logged anything (all reused and recorded before)
        from flows.tracking import Tracker

        metrics = {
            key: float(value)
            for key, value in summary.items()
            if isinstance(value, int | float) and not isinstance(value, bool)
        }
        try:
            parent = json.loads(record.read_text())["parent_run_id"]
            Tracker(state.tracking_uri).end_sweep(parent, metrics, failed)
        except Exception as error:  # the jobs are recorded; the summary metrics are extra
            print(f"warning: could not end the MLflow parent run: {error}", file=sys.stderr)


def _count_flow_runs(api_url: str, tag: str) -> dict[str, int] | None:
    """Flow runs of this multirun on the server, by state type (the server's own record)."""
    import urllib.request

    counts: dict[str, int] = {}
    offset = 0
    try:
        while True:
            payload = {"flow_runs": {"tags": {"all_": [tag]}}, "limit": 200, "offset": offset}
            request = urllib.request.Request(
                f"{api_url}/flow_runs/filter",
                data=json.dumps(payload).encode(),
                headers={"Content-Type": "application/json"},
            )
            with urllib.request.urlopen(request, timeout=10) as response:
                runs = json.loads(response.read())
            for run in runs:
                state_type = (run.get("state") or {}).get("type", "UNKNOWN")
                counts[state_type] = counts.get(state_type, 0) + 1
            if len(runs) < 200:
                return counts
            offset += len(runs)
    except (OSError, ValueError):
        return None


def _header(state: SweepState) -> str:
    total = state.total_jobs if state.total_jobs is not None else "?"
    parts = [f"sweep: {total} jobs -> {state.sweep_dir}"]
    if state.prefect_api_url:
        parts.append(f"prefect {state.prefect_api_url}")
    elif state.server:
        parts.append("prefect server on demand")
    if state.experiment:
        parts.append(f"mlflow experiment '{state.experiment}'")
    if state.dask_address:
        parts.append(f"dask {state.dask_address}")
    return " | ".join(parts)


def _footer(state: SweepState, summary: Mapping[str, Any], failed: list[dict[str, Any]]) -> str:
    lines = [
        f"sweep finished: {summary['jobs_done']}/{summary['jobs_total']} jobs, "
        f"{summary['jobs_failed']} failed, {summary['jobs_timeout']} timed out, "
        f"{summary['jobs_reused']} reused | planner calls: {summary['planner_calls_run']} run, "
        f"{summary['plan_cache_hits']} from cache | {_clock(summary['sweep_wall_time_s'])}"
    ]
    for record in failed[:10]:
        lines.append(f"  failed: {record.get('name')}: {record.get('error')}")
    runs = summary.get("prefect_flow_runs")
    if runs is not None:
        shown = ", ".join(f"{n} {s.lower()}" for s, n in sorted(runs.items())) or "none"
        stopped = " (server stopped)" if summary.get("prefect_server_started") else ""
        lines.append(f"prefect: {summary['prefect_api_url']}: flow runs: {shown}{stopped}")
    if state.experiment:
        lines.append(f"mlflow: experiment '{state.experiment}' in {state.tracking_uri}")
    return "\n".join(lines)
