"""The one interface the rest of ``flows/`` calls for MLflow: :func:`check_store` before
any work, :func:`run_exists` for a run the job store remembers, :class:`JobRunLog` for a
job's run, :func:`end_sweep_run` for a sweep's parent run (and the names they need:
:class:`TrackingError`, :func:`job_record`, :func:`experiment_name_for`).

Every write goes through MLflow's own client (``MlflowClient``: ``create_run``, one
``log_batch`` per run, ``log_artifact``, ``set_terminated``; never its tables), in one of
two places, chosen when the job starts so that the slow part (importing MLflow, opening
its store: 2-4 s) overlaps the job:

* a single run of the command: a helper process that imports MLflow and opens the store
  while the job runs (:class:`~flows.tracking.worker.TrackingWorker`);
* a job of a sweep (and a single run without the helper): MLflow's client in this
  process (:class:`~flows.tracking.client.Tracker`), under the sweep's parent run, which
  the first job that logs creates (:func:`sweep_parent`).
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flows.locations import sqlite_path
from flows.servers import file_lock
from flows.tracking.client import (
    Tracker,
    TrackingError,
    check_store,
    log_job_run,
    missing_artifacts,
    run_exists,
    running_sweep_run,
)
from flows.tracking.contents import (
    DEFAULT_EXPERIMENT,
    OVERRIDES,
    SWEEP_KEY,
    experiment_name_for,
    job_record,
)
from flows.tracking.worker import TrackingWorker
from twostep.util.files import write_json_atomic

if TYPE_CHECKING:
    from flows.sweep_state import SweepState

__all__ = [
    "DEFAULT_EXPERIMENT",
    "JobRunLog",
    "TrackingError",
    "check_store",
    "end_sweep_run",
    "experiment_name_for",
    "job_record",
    "missing_artifacts",
    "run_exists",
    "sweep_run_ids",
]


class JobRunLog:
    """Where one job's MLflow run is written: opened before the job runs, written once
    after it (:meth:`log`), then closed."""

    def __init__(
        self,
        tracking_uri: str,
        artifact_location: str | None,
        experiment: str,
        sweep: SweepState | None = None,
        worker: TrackingWorker | None = None,
    ) -> None:
        self.tracking_uri = tracking_uri
        self.artifact_location = artifact_location
        self.experiment = experiment
        self.sweep = sweep
        self.worker = worker

    @classmethod
    def open(
        cls,
        tracking_uri: str,
        artifact_location: str | None,
        experiment: str,
        sweep: SweepState | None = None,
        single_run: bool = False,
    ) -> JobRunLog:
        """The job's log; a ``single_run`` of the command (no sweep) prepares the store now,
        while the job runs (module docstring)."""
        worker = None
        if single_run and sweep is None:
            worker = TrackingWorker.start(tracking_uri, artifact_location, experiment)
        return cls(tracking_uri, artifact_location, experiment, sweep, worker)

    def log(self, record: Mapping[str, Any]) -> str:
        """Log the job (:func:`flows.tracking.contents.job_record`); return its run id."""
        if self.worker is not None:
            return self.worker.log(dict(record))
        sweep = self.sweep
        if sweep is not None and sweep.tracking_uri == self.tracking_uri:
            tracker, experiment_id, parent = sweep_parent(sweep)
            return log_job_run(tracker, experiment_id, parent, record)
        tracker = Tracker(self.tracking_uri, self.artifact_location)
        return log_job_run(tracker, tracker.experiment_id(self.experiment), None, record)

    def close(self) -> None:
        """Let the helper process go (after :meth:`log`, or with nothing logged)."""
        if self.worker is not None:
            self.worker.close()


# A process's client of each store (creating MLflow's client and store costs a tenth of a
# second; a worker process of a sweep logs many jobs).
_TRACKERS: dict[tuple[str, str | None], Tracker] = {}


def sweep_parent(state: SweepState) -> tuple[Tracker, str, str]:
    """(Tracker, experiment id, parent run id) of the sweep, made by the first job that logs.

    Under a lock because the first MlflowClient on a new SQLite file creates its
    tables, which two processes must not do at once: a lock beside the SQLite file, so
    that two sweeps sharing one store take turns too (else the sweep's own).
    """
    assert state.tracking_uri is not None and state.experiment is not None
    key = (state.tracking_uri, state.artifact_location)
    ids = sweep_run_ids(state)
    if key in _TRACKERS and ids is not None:  # every job of this process after the first
        return _TRACKERS[key], ids[0], ids[1]
    record = state.folder / "mlflow.json"
    database = sqlite_path(state.tracking_uri)
    lock = state.folder / "mlflow.lock" if database is None else Path(f"{database}.lock")
    with file_lock(lock):
        if key not in _TRACKERS:
            _TRACKERS[key] = Tracker(state.tracking_uri, state.artifact_location)
        tracker = _TRACKERS[key]
        ids = sweep_run_ids(state)
        if ids is not None:
            return tracker, ids[0], ids[1]
        overrides = " ".join(state.overrides)
        experiment_id = tracker.experiment_id(
            state.experiment,
            state.command or None,
            {SWEEP_KEY: state.sweep_key, OVERRIDES: overrides},
        )
        folder = Path(state.sweep_dir)
        parent = tracker.sweep_run(
            experiment_id,
            state.sweep_key,
            name=f"sweep {folder.parent.name}/{folder.name}",
            tags={
                "twostep.sweep_dir": state.sweep_dir,
                OVERRIDES: overrides,
            },
        )
        write_json_atomic(record, {"experiment_id": experiment_id, "parent_run_id": parent})
        return tracker, experiment_id, parent


def sweep_run_ids(state: SweepState) -> tuple[str, str] | None:
    """(experiment id, parent run id) of the sweep, once a job has logged (else None)."""
    with contextlib.suppress(OSError, ValueError, KeyError):
        data = json.loads((state.folder / "mlflow.json").read_text())
        return str(data["experiment_id"]), str(data["parent_run_id"])
    return None


def end_sweep_run(
    state: SweepState,
    metrics: Mapping[str, float],
    failed: bool,
    files: Iterable[tuple[Path, str | None]] = (),
) -> bool:
    """End the sweep's parent run with its summary metrics and the sweep's report files
    (``files``: (path, artifact folder)); False: no job logged one, and no earlier run of
    the same sweep left it ``RUNNING`` (a full disk: this run ends it)."""
    if state.tracking_uri is None:
        return False
    ids = sweep_run_ids(state)
    if ids is None:  # no job logged anything (all reused and recorded before)
        if state.experiment is None or not running_sweep_run(
            state.tracking_uri, state.experiment, state.sweep_key
        ):
            return False
        tracker, _, parent = sweep_parent(state)
        tracker.end_sweep(parent, metrics, failed, files)
        return True
    Tracker(state.tracking_uri).end_sweep(ids[1], metrics, failed, files)
    return True
