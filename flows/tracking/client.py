"""MLflow's own client on a store: experiments, the sweep's parent run, job runs
(:class:`Tracker`, :func:`log_job_run`), and the check of a store before any work.

* :func:`check_store` runs before any work: a store that cannot be reached or written
  is a one-line :class:`TrackingError`, not a traceback after an hour of planning;
  :func:`run_exists` tells cheaply whether a run the job store remembers is still there.
* One experiment per sweep; the sweep's parent run is found again by its
  ``twostep.sweep_key`` tag and each job's run by its ``twostep.job_key`` tag, so a
  sweep started again after ``kill -9`` reuses them instead of adding duplicates.

MLflow is imported lazily (seconds): a finished job that needs no logging never pays it.
"""

from __future__ import annotations

import hashlib
import json
import re
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Iterable, Mapping
from functools import partial
from pathlib import Path
from typing import Any, TypeVar
from urllib.parse import quote, urlparse

from flows.console import one_line
from flows.locations import sqlite_path, write_problem
from flows.tracking.contents import (
    CLASSIC_RUNS,
    EXPERIMENT_KIND,
    JOB_KEY,
    KIND,
    NOTE,
    PARENT,
    STATUS,
    SWEEP_KEY,
    TAG_LIMIT,
    clip,
    job_tags,
    metric_points,
)
from flows.tracking.template import quiet_mlflow_logging, seed_store
from twostep.util.outcome import SETTLED, JobStatus
from twostep.util.redaction import redact_text

T = TypeVar("T")


class TrackingError(Exception):
    """The MLflow store cannot be used; the message is one line for the terminal."""


def check_store(tracking_uri: str, timeout_s: float = 10.0) -> None:
    """Fail fast, with one line, when the tracking store cannot be reached or written.

    HTTP servers are asked for ``/health``; SQLite and file stores are checked on disk
    (the folder is writable, an existing SQLite file is a database) without importing
    MLflow, so the check costs milliseconds; other stores are opened with MLflow.
    """
    parsed = urlparse(tracking_uri)
    scheme = parsed.scheme
    hint = "set mlflow.tracking_uri=<uri> or mlflow.enabled=false"
    shown = redact_text(tracking_uri)  # the messages below never show URL credentials
    if scheme in ("http", "https"):
        url = tracking_uri.rstrip("/") + "/health"
        try:
            with urllib.request.urlopen(url, timeout=timeout_s) as response:
                status = response.status
        except urllib.error.HTTPError as error:
            status = error.code
        except (urllib.error.URLError, OSError) as error:
            reason = getattr(error, "reason", error)
            raise TrackingError(
                f"MLflow tracking server {shown} cannot be reached: {reason} ({hint})"
            ) from None
        if status != 200:
            raise TrackingError(f"MLflow tracking server {shown} answered {status} ({hint})")
        return
    if scheme == "sqlite":
        database = sqlite_path(tracking_uri)
        if database is None:
            return
        _check_writable(database.parent, f"MLflow store {shown}", hint)
        if database.exists():
            _check_sqlite(database, tracking_uri, hint)
        return
    if scheme in ("", "file"):
        _check_writable(Path(parsed.path or tracking_uri), f"MLflow store {shown}", hint)
        return
    try:
        mlflow_client(tracking_uri).search_experiments(max_results=1)
    except Exception as error:
        raise TrackingError(
            f"MLflow store {shown} cannot be used: {one_line(error, limit=300)}"
        ) from None


def run_exists(tracking_uri: str, run_id: str, timeout_s: float = 10.0) -> bool:
    """Whether the store still holds the active run ``run_id``, asked cheaply: a read of a
    SQLite store, a GET to a tracking server (MLflow is not imported). False also when it
    cannot be told cheaply: the caller then logs through the interface, which finds a run
    that exists by its job key (no duplicate)."""
    if sqlite_path(tracking_uri) is not None:
        return _run_column(tracking_uri, run_id, "lifecycle_stage") == "active"
    if urlparse(tracking_uri).scheme in ("http", "https"):
        url = f"{tracking_uri.rstrip('/')}/api/2.0/mlflow/runs/get?run_id={quote(run_id)}"
        try:
            with urllib.request.urlopen(url, timeout=timeout_s) as response:
                answer = json.load(response)
        except (OSError, ValueError):  # 404 for a lost run, or no answer
            return False
        info = answer.get("run", {}).get("info", {}) if isinstance(answer, dict) else {}
        return bool(info.get("lifecycle_stage") == "active")
    return False


def _run_column(tracking_uri: str, run_id: str, column: str) -> object | None:
    """One column of run ``run_id`` read from a SQLite store, read-only (MLflow is not
    imported); None without such a store or run (no tables, an emptied file)."""
    import sqlite3
    from contextlib import closing

    database = sqlite_path(tracking_uri)
    if database is None or not database.is_file():
        return None
    try:
        with closing(sqlite3.connect(f"file:{database}?mode=ro", uri=True, timeout=30.0)) as db:
            rows = db.execute(f"SELECT {column} FROM runs WHERE run_uuid = ?", (run_id,)).fetchall()
    except sqlite3.Error:
        return None
    return rows[0][0] if len(rows) == 1 else None


def missing_artifacts(tracking_uri: str, run_id: str) -> str | None:
    """The artifact folder of run ``run_id`` when the store names a local one that is
    gone or empty (``rm -rf outputs/mlruns``); None when it is there, or when that cannot
    be told cheaply (a tracking server, remote artifacts: nothing is claimed)."""
    from urllib.request import url2pathname

    found = _run_column(tracking_uri, run_id, "artifact_uri")
    if not found:
        return None
    uri = str(found)
    parsed = urlparse(uri)
    if parsed.scheme not in ("", "file"):
        return None
    folder = Path(url2pathname(parsed.path) if parsed.scheme else uri)
    if folder.is_dir() and any(folder.iterdir()):
        return None
    return str(folder)


def _check_sqlite(path: Path, uri: str, hint: str) -> None:
    import sqlite3

    try:
        connection = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=10.0)
        try:
            connection.execute("SELECT count(*) FROM sqlite_master").fetchone()
        finally:
            connection.close()
    except sqlite3.Error as error:
        raise TrackingError(
            f"MLflow store {uri} cannot be read: {one_line(error, limit=300)} ({hint})"
        ) from None


def _check_writable(folder: Path, what: str, hint: str) -> None:
    problem = write_problem(folder)
    if problem is not None:
        raise TrackingError(f"{what} is not writable: {problem} ({hint})")


def mlflow_client(tracking_uri: str) -> Any:
    """MLflow's client; a SQLite store that does not exist yet is seeded from the
    environment's template (:func:`flows.tracking.template.seed_store`), and is written
    without waiting for the disk (:func:`write_without_sync`)."""
    from mlflow.tracking import MlflowClient

    quiet_mlflow_logging()
    database = sqlite_path(tracking_uri)
    if database is not None:
        if not database.exists():  # copied, not migrated
            seed_store(database)
        write_without_sync(database)
    return MlflowClient(tracking_uri=tracking_uri)


_UNSYNCED: set[str] = set()  # SQLite stores this process writes with synchronous=OFF


def write_without_sync(database: Path) -> None:
    """This process's connections to the SQLite store ``database`` do not wait for the
    disk at each commit (``PRAGMA synchronous=OFF``): every commit of a job's run is
    written, in order, as before, and survives the process being killed; what it gives up
    is the guarantee after a power loss or an operating system crash, which the job store
    covers (MLflow is a view it rebuilds: ``rm mlflow.db`` and the same command). Half of
    a job's MLflow time on a busy disk went to those waits."""
    from sqlalchemy import event
    from sqlalchemy.engine import Engine

    if not _UNSYNCED:
        event.listen(Engine, "connect", _unsynced_connection)
    _UNSYNCED.add(str(database.resolve()))


def _unsynced_connection(connection: Any, record: Any) -> None:
    """SQLAlchemy's connect hook: ``synchronous=OFF`` on a connection to a store of
    :data:`_UNSYNCED` (any other database is left as it is)."""
    import sqlite3

    if not isinstance(connection, sqlite3.Connection):
        return
    try:
        rows = connection.execute("PRAGMA database_list").fetchall()
        if any(row[1] == "main" and row[2] in _UNSYNCED for row in rows):
            connection.execute("PRAGMA synchronous=OFF")
    except sqlite3.Error:
        pass


def _sqlite_count(tracking_uri: str, query: str, parameters: tuple[Any, ...]) -> int | None:
    """``query``'s count, asked with one read-only read of a SQLite store (None: not a
    SQLite store, or it cannot be read)."""
    database = sqlite_path(tracking_uri)
    if database is None or not database.is_file():
        return None
    import sqlite3
    from contextlib import closing

    try:
        with closing(sqlite3.connect(f"file:{database}?mode=ro", uri=True, timeout=30.0)) as db:
            (count,) = db.execute(query, parameters).fetchone()
    except (sqlite3.Error, ValueError):
        return None
    return int(count)


def tagged_runs(tracking_uri: str, experiment_id: str, tag: str, value: str) -> int | None:
    """How many active runs of the experiment carry ``tag=value``, asked with one read
    of a SQLite store (None: not a SQLite store, or it cannot be read: ask MLflow)."""
    try:
        experiment = int(experiment_id)
    except ValueError:
        return None
    return _sqlite_count(
        tracking_uri,
        "SELECT count(*) FROM runs JOIN tags ON tags.run_uuid = runs.run_uuid"
        " WHERE runs.experiment_id = ? AND runs.lifecycle_stage = 'active'"
        " AND tags.key = ? AND tags.value = ?",
        (experiment, tag, value),
    )


def running_sweep_run(tracking_uri: str, experiment: str, sweep_key: str) -> bool:
    """Whether a SQLite store holds a parent run of this sweep key still ``RUNNING`` in
    experiment ``experiment`` (one read; False for another store, or when it cannot tell):
    a sweep that could not end it (a full disk) left it so."""
    count = _sqlite_count(
        tracking_uri,
        "SELECT count(*) FROM runs JOIN tags ON tags.run_uuid = runs.run_uuid"
        " JOIN experiments ON experiments.experiment_id = runs.experiment_id"
        " WHERE experiments.name = ? AND runs.lifecycle_stage = 'active'"
        " AND runs.status = 'RUNNING' AND tags.key = ? AND tags.value = ?",
        (experiment, SWEEP_KEY, sweep_key),
    )
    return bool(count)


def _retry(call: Callable[[], T], attempts: int = 5) -> T:
    """Retry a store write that lost a race for SQLite's lock with a parallel job."""
    for attempt in range(attempts):
        try:
            return call()
        except Exception as error:
            if "locked" not in str(error).lower() or attempt == attempts - 1:
                raise
            time.sleep(0.2 * 2**attempt)
    raise AssertionError("unreachable")


def experiment_location(artifact_root: str | None, name: str) -> str | None:
    """Where experiment ``name`` keeps its artifacts: one folder per experiment under a
    local artifact root, named so a person finds it (a URI root is MLflow's to extend)."""
    if not artifact_root or "://" in artifact_root:
        return artifact_root
    slug = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_")[:80]
    digest = hashlib.sha256(name.encode()).hexdigest()[:8]
    return (Path(artifact_root).resolve() / f"{slug}-{digest}").as_uri()


class Tracker:
    """One MLflow store: experiments, the sweep's parent run, job runs."""

    def __init__(self, tracking_uri: str, artifact_location: str | None = None) -> None:
        self.tracking_uri = tracking_uri
        self.artifact_location = artifact_location
        self.client = mlflow_client(tracking_uri)

    # ------------------------------------------------------------- experiments

    def experiment_id(
        self, name: str, description: str | None = None, extra: Mapping[str, str] | None = None
    ) -> str:
        """The experiment ``name`` (created, or restored if deleted), marked to open on
        MLflow's runs table (:data:`EXPERIMENT_KIND`); ``description``: its note; ``extra``:
        more tags (a sweep's key and overrides)."""
        tags = {
            EXPERIMENT_KIND: CLASSIC_RUNS,
            **{k: clip(v, TAG_LIMIT) for k, v in (extra or {}).items()},
        }
        if description:
            tags[NOTE] = clip(description, TAG_LIMIT)
        found = self.client.get_experiment_by_name(name)
        if found is not None:
            if found.lifecycle_stage == "deleted":
                self.client.restore_experiment(found.experiment_id)
            for key, value in tags.items():  # an experiment made before the tags existed
                if found.tags.get(key) != value:
                    self.client.set_experiment_tag(found.experiment_id, key, value)
            return str(found.experiment_id)
        location = experiment_location(self.artifact_location, name)
        try:
            return str(self.client.create_experiment(name, location, tags=tags))
        except Exception:
            # A parallel job created it first.
            found = self.client.get_experiment_by_name(name)
            if found is None:
                raise
            return str(found.experiment_id)

    def find_run(self, experiment_id: str, tag: str, value: str) -> Any | None:
        if tagged_runs(self.tracking_uri, experiment_id, tag, value) == 0:
            return None  # the store says so without MLflow's search (a new job's run)
        runs = self.client.search_runs(
            [experiment_id], filter_string=f"tags.`{tag}` = '{value}'", max_results=5
        )
        # Oldest first: should duplicates ever exist, everyone keeps using the same one.
        return min(runs, key=lambda r: r.info.start_time) if runs else None

    # ------------------------------------------------------------- sweep run

    def sweep_run(
        self, experiment_id: str, sweep_key: str, name: str, tags: Mapping[str, str]
    ) -> str:
        """The sweep's parent run: the one with this sweep key, or a new one."""
        found = self.find_run(experiment_id, SWEEP_KEY, sweep_key)
        if found is not None:
            run_id = str(found.info.run_id)
            self.client.update_run(run_id, status="RUNNING")
            for key, value in tags.items():
                self.client.set_tag(run_id, key, clip(value, TAG_LIMIT))
            return run_id
        run = self.client.create_run(
            experiment_id,
            run_name=name,
            tags={
                KIND: "sweep",
                SWEEP_KEY: sweep_key,
                **{k: clip(v, TAG_LIMIT) for k, v in tags.items()},
            },
        )
        return str(run.info.run_id)

    def end_sweep(
        self,
        run_id: str,
        metrics: Mapping[str, float],
        failed: bool,
        files: Iterable[tuple[Path, str | None]] = (),
    ) -> None:
        """The sweep's summary metrics and its report files (``files``: (path, folder))."""
        from mlflow.entities import Metric, RunTag

        for path, folder in files:
            _retry(partial(self.client.log_artifact, run_id, str(path), folder))
        now = int(time.time() * 1000)
        _retry(
            lambda: self.client.log_batch(
                run_id,
                metrics=[Metric(k, float(v), now, 0) for k, v in metrics.items()],
                tags=[RunTag(STATUS, "failed" if failed else "success")],
            )
        )
        _retry(lambda: self.client.set_terminated(run_id, status="FINISHED"))

    # ------------------------------------------------------------- job runs

    def job_run(
        self,
        experiment_id: str,
        job_key: str,
        name: str,
        parent_run_id: str | None,
        tags: Mapping[str, str] | None = None,
        start_ms: int | None = None,
    ) -> tuple[str, Any | None]:
        """The job's run (found by job key, else created with ``tags``, starting when the
        job started) and the found run, if any."""
        found = self.find_run(experiment_id, JOB_KEY, job_key)
        if found is not None:
            return str(found.info.run_id), found
        run_tags = {k: clip(v, TAG_LIMIT) for k, v in (tags or {}).items()}
        run_tags.update({KIND: "job", JOB_KEY: job_key})
        if parent_run_id:
            run_tags[PARENT] = parent_run_id
        run = _retry(
            lambda: self.client.create_run(
                experiment_id, start_time=start_ms, tags=run_tags, run_name=name
            )
        )
        return str(run.info.run_id), None

    def log_job(
        self,
        run_id: str,
        params: Mapping[str, str],
        metrics: Mapping[str, float | list[float]],
        tags: Mapping[str, str],
        files: Iterable[tuple[Path, str | None]],
        existing_params: Mapping[str, str] | None = None,
        terminated: str = "FINISHED",
        end_ms: int | None = None,
    ) -> None:
        """Artifacts, then params, metrics and the status tags in one ``log_batch`` (one
        transaction of the store; split only past MLflow's batch limits, the status tags
        in the last part), then the run's end (``end_ms``: the job's).

        The ``twostep.status`` tag comes with or after everything else: a run that has it
        is complete. Params already on a reused run are not logged again (MLflow refuses a
        changed value, and a re-run may differ in where it ran).
        """
        from mlflow.entities import Metric, Param, RunTag

        for path, folder in files:
            _retry(partial(self.client.log_artifact, run_id, str(path), folder))
        existing = existing_params or {}
        new_params = [Param(k, v) for k, v in params.items() if k not in existing]
        now = end_ms if end_ms is not None else int(time.time() * 1000)
        metric_list = [Metric(*point) for point in metric_points(metrics, now)]
        run_tags = [RunTag(k, clip(v, TAG_LIMIT)) for k, v in tags.items()]
        for batch in batches(new_params, metric_list, run_tags):
            _retry(partial(self.client.log_batch, run_id, **batch))
        _retry(lambda: self.client.set_terminated(run_id, status=terminated, end_time=end_ms))


def batches(params: list[Any], metrics: list[Any], tags: list[Any]) -> list[dict[str, list[Any]]]:
    """``log_batch`` keyword sets within MLflow's limits (100 params, 1000 metrics, 1000
    entries per call): one call for a job's run; past the limits, params and metrics first
    and the tags in the last call."""
    if len(params) <= 100 and len(tags) <= 100 and len(params) + len(metrics) + len(tags) <= 1000:
        return [{"params": params, "metrics": metrics, "tags": tags}]
    calls: list[dict[str, list[Any]]] = []
    calls += [{"params": params[i : i + 100]} for i in range(0, len(params), 100)]
    calls += [{"metrics": metrics[i : i + 1000]} for i in range(0, len(metrics), 1000)]
    calls += [{"tags": tags[i : i + 100]} for i in range(0, len(tags), 100)]
    return calls


# MLflow's run status of a job, by how it ended (``twostep.status``): a timed-out job was
# stopped by its time limit, KILLED; any other job without success FAILED. Only a
# success is FINISHED (the green check of MLflow's runs table).
MLFLOW_RUN_STATES: dict[str, str] = {
    JobStatus.SUCCESS: "FINISHED",
    JobStatus.TIMEOUT: "KILLED",
    JobStatus.FAILED: "FAILED",
}


def log_job_run(
    tracker: Tracker, experiment_id: str, parent: str | None, record: Mapping[str, Any]
) -> str:
    """Log one job (``record``: plain data, see ``flows.job._job_record``) to its run,
    found again by job key; return the run id.

    A run recorded completely before (same job key: same result) is left as it is:
    logging again would only append a second point to every metric's history.
    """
    run_id, found = tracker.job_run(
        experiment_id,
        record["key"],
        record["name"],
        parent,
        tags=record.get("tags"),
        start_ms=record.get("start_ms"),
    )
    if found is not None and found.data.tags.get(STATUS) in SETTLED:
        if missing_artifacts(tracker.tracking_uri, run_id) is not None:  # mlruns/ deleted
            for path, folder in record["files"]:
                if Path(path).is_file():
                    _retry(partial(tracker.client.log_artifact, run_id, str(path), folder))
        return run_id
    tracker.log_job(
        run_id,
        record["params"],
        record["metrics"],
        job_tags(record),
        [(Path(path), folder) for path, folder in record["files"]],
        existing_params=dict(found.data.params) if found is not None else None,
        terminated=MLFLOW_RUN_STATES.get(str(record["status"]), "FAILED"),
        end_ms=record.get("end_ms"),
    )
    return run_id
