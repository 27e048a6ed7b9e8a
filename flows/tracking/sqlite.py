"""A single run's MLflow logging written straight into its SQLite store, without MLflow.

Importing MLflow and opening its SQLAlchemy store (ORM set-up, alembic's schema check)
costs 3-4 CPU seconds per process: more than everything else a short single run does.
When the store is a SQLite file that MLflow created with the schema of the installed
MLflow (:data:`SCHEMA_VERSION`, its alembic head) and the run's experiment exists and is
active, :class:`SqliteJobLog` writes the rows MLflow's client writes for
:func:`flows.tracking.client.log_job_run` (``Tracker.job_run`` + ``Tracker.log_job``: the run,
its tags, params, metrics and latest metrics, the artifact files, the status tags and
the run's end) in one transaction, and copies the artifacts as MLflow's local artifact
repository does. The contents are MLflow's: tests/test_tracking_sqlite.py compares
every row with what MLflow itself writes for the same record.

A store that does not exist yet is seeded from the environment's template
(:mod:`flows.tracking.template`), and the run's experiment is then added as MLflow adds it
(one row).

Anything else answers ``None`` and the caller logs with MLflow as before: no template and
no store, another schema, an experiment deleted or without a local artifact root, a run
to be logged again (an earlier attempt failed), or a name or value MLflow would reject (so
its error message stays MLflow's).
"""

from __future__ import annotations

import math
import posixpath
import re
import shutil
import sqlite3
import uuid
from collections.abc import Mapping
from contextlib import closing
from pathlib import Path
from typing import Any
from urllib.parse import urlparse
from urllib.request import url2pathname

from flows.locations import sqlite_path
from flows.tracking.client import experiment_location
from flows.tracking.contents import JOB_KEY, KIND, STATUS, job_tags, metric_points
from flows.tracking.template import SCHEMA_VERSION, millis, seed_store

RUN_NAME = "mlflow.runName"
# MLflow's own limits and name rule (mlflow.utils.validation; POSIX systems).
_NAME = re.compile(r"^[/\w.\- :]*$")
_MAX_KEY = 250
_MAX_PARAM_VALUE = 6000
_MAX_TAG_VALUE = 8000
_MAX_DOUBLE = 1.7976931348623157e308  # what MLflow stores for +-inf


def _experiment_rows(db: sqlite3.Connection, name: str) -> list[tuple[Any, ...]]:
    return db.execute(
        "SELECT experiment_id, lifecycle_stage, artifact_location, workspace"
        " FROM experiments WHERE name = ?",
        (name,),
    ).fetchall()


def _create_experiment(db: sqlite3.Connection, name: str, location: str) -> list[tuple[Any, ...]]:
    """The experiment's row as MLflow's ``create_experiment`` writes it (no tags)."""
    if not _valid_name(name) or len(name) > 256:
        return []
    db.execute("BEGIN IMMEDIATE")
    try:
        if not _experiment_rows(db, name):  # else a parallel job created it first
            now = millis()
            db.execute(
                "INSERT INTO experiments (name, artifact_location, lifecycle_stage,"
                " creation_time, last_update_time, workspace)"
                " VALUES (?, ?, 'active', ?, ?, 'default')",
                (name, location, now, now),
            )
    except BaseException:
        db.execute("ROLLBACK")
        raise
    db.execute("COMMIT")
    return _experiment_rows(db, name)


def _valid_name(name: str) -> bool:
    normal = posixpath.normpath(name)
    unique = not (normal != name or normal == "." or normal.startswith(("..", "/")))
    return bool(_NAME.match(name)) and unique and len(name) <= _MAX_KEY


def _artifact_root(location: str) -> tuple[str, Path] | None:
    """``(uri, folder)`` of an experiment's local artifact location, else None."""
    parsed = urlparse(location)
    if parsed.scheme == "file" and not parsed.netloc and not parsed.query and parsed.path:
        return location.rstrip("/"), Path(url2pathname(parsed.path))
    if not parsed.scheme and location.startswith("/"):
        return location.rstrip("/"), Path(location)
    return None


class SqliteJobLog:
    """One experiment of one SQLite store, ready to take a single run's record."""

    def __init__(self, path: Path, experiment_id: int, artifact_location: str) -> None:
        self.path = path
        self.experiment_id = experiment_id
        self.artifact_location = artifact_location

    @classmethod
    def open(
        cls, tracking_uri: str, experiment: str, artifact_root: str | None = None
    ) -> SqliteJobLog | None:
        """The store and experiment, if this module can log into them (see above).

        A missing store is seeded from the template; a missing experiment is added when
        ``artifact_root`` (``mlflow.artifact_location``) is a local folder."""
        path = sqlite_path(tracking_uri)
        if path is None or (not path.is_file() and not seed_store(path)):
            return None
        try:
            with closing(cls._connect(path)) as db:
                version = db.execute("SELECT version_num FROM alembic_version").fetchall()
                if version != [(SCHEMA_VERSION,)]:
                    return None
                rows = _experiment_rows(db, experiment)
                location = experiment_location(artifact_root, experiment)
                if not rows and location is not None and _artifact_root(location) is not None:
                    rows = _create_experiment(db, experiment, location)
        except sqlite3.Error:
            return None
        if len(rows) != 1:
            return None
        experiment_id, stage, location, workspace = rows[0]
        if stage != "active" or workspace != "default" or not isinstance(location, str):
            return None
        if _artifact_root(location) is None:
            return None
        return cls(path, int(experiment_id), location)

    @staticmethod
    def _connect(path: Path) -> sqlite3.Connection:
        # isolation_level=None: transactions are begun explicitly (BEGIN IMMEDIATE).
        return sqlite3.connect(str(path), timeout=30.0, isolation_level=None)

    def log(self, record: Mapping[str, Any]) -> str | None:
        """Log the job (``flows.job._job_record``) and return its run id, or None when
        MLflow has to do it (see the module docstring). Nothing is half written."""
        params = {str(k): str(v) for k, v in record["params"].items()}
        tags = job_tags(record)
        files = [(Path(path), folder) for path, folder in record["files"]]
        keys = [*params, *record["metrics"], *tags, KIND, JOB_KEY, RUN_NAME]
        if not all(_valid_name(k) for k in keys):
            return None
        if any(len(v) > _MAX_PARAM_VALUE for v in params.values()):
            return None
        if any(len(v) > _MAX_TAG_VALUE for v in (*tags.values(), record["name"])):
            return None
        if not all(path.is_file() for path, _ in files):
            return None
        with closing(self._connect(self.path)) as db:
            db.execute("BEGIN IMMEDIATE")
            try:
                run_id = self._write(db, record, params, tags, files)
            except BaseException:
                db.execute("ROLLBACK")
                raise
            db.execute("COMMIT" if run_id else "ROLLBACK")
        return run_id

    def _find_run(self, db: sqlite3.Connection, key: str) -> str | None:
        """As ``Tracker.find_run``: MLflow's search (active runs, newest first, five at
        most), then the oldest of those."""
        rows = db.execute(
            "SELECT runs.run_uuid, runs.start_time FROM runs JOIN tags"
            " ON tags.run_uuid = runs.run_uuid"
            " WHERE runs.experiment_id = ? AND runs.lifecycle_stage = 'active'"
            " AND tags.key = ? AND tags.value = ?"
            " ORDER BY runs.start_time DESC, runs.run_uuid ASC LIMIT 5",
            (self.experiment_id, JOB_KEY, key),
        ).fetchall()
        return str(min(rows, key=lambda row: row[1])[0]) if rows else None

    def _write(
        self,
        db: sqlite3.Connection,
        record: Mapping[str, Any],
        params: Mapping[str, str],
        tags: Mapping[str, str],
        files: list[tuple[Path, str | None]],
    ) -> str | None:
        found = self._find_run(db, str(record["key"]))
        if found is not None:
            found_status = db.execute(
                "SELECT value FROM tags WHERE run_uuid = ? AND key = ?", (found, STATUS)
            ).fetchall()
            # Complete: left as it is (log_job_run). Else MLflow logs into it again.
            return found if found_status in ([("success",)], [("timeout",)]) else None
        run_id = uuid.uuid4().hex
        root = _artifact_root(self.artifact_location)
        assert root is not None  # checked in open()
        artifact_uri = f"{root[0]}/{run_id}/artifacts"
        name = str(record["name"])
        db.execute(
            "INSERT INTO runs (run_uuid, name, source_type, source_name, entry_point_name,"
            " user_id, status, start_time, end_time, source_version, lifecycle_stage,"
            " artifact_uri, experiment_id, deleted_time)"
            " VALUES (?, ?, 'UNKNOWN', '', '', 'unknown', 'RUNNING', ?, NULL, '', 'active',"
            " ?, ?, NULL)",
            (run_id, name, millis(), artifact_uri, self.experiment_id),
        )
        first_tags = {KIND: "job", JOB_KEY: str(record["key"]), RUN_NAME: name}
        db.executemany(
            "INSERT INTO tags (key, value, run_uuid) VALUES (?, ?, ?)",
            [(k, v, run_id) for k, v in first_tags.items()],
        )
        db.executemany(
            "INSERT INTO params (key, value, run_uuid) VALUES (?, ?, ?)",
            [(k, v, run_id) for k, v in params.items()],
        )
        self._write_metrics(db, run_id, record["metrics"])
        folder = root[1] / run_id / "artifacts"
        for path, subfolder in files:
            target = folder / subfolder if subfolder else folder
            target.mkdir(parents=True, exist_ok=True)
            shutil.copy2(path, target / path.name)  # content and times, as MLflow copies
        db.executemany(
            "INSERT OR REPLACE INTO tags (key, value, run_uuid) VALUES (?, ?, ?)",
            [(k, v, run_id) for k, v in tags.items()],
        )
        status = "FAILED" if record["status"] == "failed" else "FINISHED"
        db.execute(
            "UPDATE runs SET status = ?, end_time = ? WHERE run_uuid = ?",
            (status, millis(), run_id),
        )
        return run_id

    @staticmethod
    def _write_metrics(
        db: sqlite3.Connection, run_id: str, metrics: Mapping[str, float | list[float]]
    ) -> None:
        """Metric points and each key's latest point (by step, timestamp, value), with
        MLflow's storage of NaN (0, is_nan) and infinities (the largest double)."""
        rows: list[tuple[str, float, int, int, int]] = []
        for key, value, timestamp, step in metric_points(metrics, millis()):
            is_nan = math.isnan(value)
            if is_nan:
                value = 0.0
            elif math.isinf(value):
                value = _MAX_DOUBLE if value > 0 else -_MAX_DOUBLE
            rows.append((key, value, timestamp, step, int(is_nan)))
        db.executemany(
            "INSERT OR IGNORE INTO metrics (key, value, timestamp, run_uuid, step, is_nan)"
            " VALUES (?, ?, ?, ?, ?, ?)",
            [(k, v, t, run_id, s, n) for k, v, t, s, n in rows],
        )
        latest: dict[str, tuple[str, float, int, int, int]] = {}
        for row in rows:
            key, value, timestamp, step, _ = row
            best = latest.get(key)
            if best is None or (step, timestamp, value) > (best[3], best[2], best[1]):
                latest[key] = row
        db.executemany(
            "INSERT INTO latest_metrics (key, value, timestamp, step, is_nan, run_uuid)"
            " VALUES (?, ?, ?, ?, ?, ?)",
            [(k, v, t, s, n, run_id) for k, v, t, s, n in latest.values()],
        )
