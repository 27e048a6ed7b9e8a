"""MLflow bookkeeping for sweeps and jobs, exactly as docs/tracking.md lays it out.

* :func:`check_store` runs before any work: a store that cannot be reached or written
  is a one-line :class:`TrackingError`, not a traceback after an hour of planning.
* One experiment per sweep; the sweep's parent run is found again by its
  ``twostep.sweep_key`` tag and each job's run by its ``twostep.job_key`` tag, so a
  sweep started again after ``kill -9`` reuses them instead of adding duplicates.
* :func:`job_params` / :func:`job_metrics` turn a resolved config and a result.json
  dict into MLflow params and metrics; nothing that looks like a secret is logged.

MLflow is imported lazily (seconds): a finished job that needs no logging never pays it.
"""

from __future__ import annotations

import hashlib
import re
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Iterable, Mapping
from functools import partial
from pathlib import Path
from typing import Any, TypeVar
from urllib.parse import urlparse

from twostep.params import flatten_config

KIND = "twostep.kind"
JOB_KEY = "twostep.job_key"
SWEEP_KEY = "twostep.sweep_key"
STATUS = "twostep.status"
ERROR = "twostep.error"
SCRIPTED = "twostep.scripted_llm"
REUSED = "twostep.reused"
PARENT = "mlflow.parentRunId"

DEFAULT_EXPERIMENT = "twostep"
_SECRET = re.compile(r"api_key|secret|token|password|authorization", re.IGNORECASE)
_PARAM_LIMIT = 6000
_TAG_LIMIT = 5000

T = TypeVar("T")


class TrackingError(Exception):
    """The MLflow store cannot be used; the message is one line for the terminal."""


def _one_line(error: BaseException) -> str:
    lines = str(error).strip().splitlines()
    text = lines[0] if lines else ""
    return f"{type(error).__name__}: {text}"[:300] if text else type(error).__name__


def check_store(tracking_uri: str, timeout_s: float = 10.0) -> None:
    """Fail fast, with one line, when the tracking store cannot be reached or written.

    HTTP servers are asked for ``/health``; SQLite and file stores are checked on disk
    (the folder is writable, an existing SQLite file is a database) without importing
    MLflow, so the check costs milliseconds; other stores are opened with MLflow.
    """
    parsed = urlparse(tracking_uri)
    scheme = parsed.scheme
    hint = "set mlflow.tracking_uri=<uri> or mlflow.enabled=false"
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
                f"MLflow tracking server {tracking_uri} cannot be reached: {reason} ({hint})"
            ) from None
        if status != 200:
            raise TrackingError(f"MLflow tracking server {tracking_uri} answered {status} ({hint})")
        return
    if scheme == "sqlite":
        path = tracking_uri[len("sqlite:///") :] if tracking_uri.startswith("sqlite:///") else ""
        if not path or path == ":memory:":
            return
        _check_writable(Path(path).parent, f"MLflow store {tracking_uri}", hint)
        if Path(path).exists():
            _check_sqlite(Path(path), tracking_uri, hint)
        return
    if scheme in ("", "file"):
        _check_writable(Path(parsed.path or tracking_uri), f"MLflow store {tracking_uri}", hint)
        return
    try:
        _client(tracking_uri).search_experiments(max_results=1)
    except Exception as error:
        raise TrackingError(
            f"MLflow store {tracking_uri} cannot be used: {_one_line(error)}"
        ) from None


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
            f"MLflow store {uri} cannot be read: {_one_line(error)} ({hint})"
        ) from None


def _check_writable(folder: Path, what: str, hint: str) -> None:
    from flows.checks import write_problem

    problem = write_problem(folder)
    if problem is not None:
        raise TrackingError(f"{what} is not writable: {problem} ({hint})")


def _client(tracking_uri: str, seed: bool = True) -> Any:
    """MLflow's client; a SQLite store that does not exist yet is seeded from the
    environment's template (:func:`flows.tracking.sqlite.seed_store`) unless ``seed`` is
    False (MLflow then creates and migrates it: how the template itself is made)."""
    import logging

    from mlflow.tracking import MlflowClient

    # MLflow announces schema migrations at INFO on the job's console (it sets its
    # logger's level when imported, hence after the import): keep it quiet.
    for name in ("mlflow", "alembic"):
        logging.getLogger(name).setLevel(logging.WARNING)

    if seed and tracking_uri.startswith("sqlite:///"):  # a new store: copied, not migrated
        from flows.tracking.sqlite import seed_store

        path = Path(tracking_uri[len("sqlite:///") :])
        if not path.exists():
            seed_store(path)
    return MlflowClient(tracking_uri=tracking_uri)


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


def experiment_name_for(overrides: Iterable[str]) -> str:
    """A readable experiment name from a sweep's overrides (same command, same name)."""
    name = "sweep " + " ".join(overrides) if overrides else "sweep (defaults)"
    if len(name) > 200:
        digest = hashlib.sha256(name.encode()).hexdigest()[:10]
        name = f"{name[:180]} ... #{digest}"
    return name


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
        self.client = _client(tracking_uri)

    # ------------------------------------------------------------- experiments

    def experiment_id(self, name: str) -> str:
        found = self.client.get_experiment_by_name(name)
        if found is not None:
            if found.lifecycle_stage == "deleted":
                self.client.restore_experiment(found.experiment_id)
            return str(found.experiment_id)
        location = experiment_location(self.artifact_location, name)
        try:
            return str(self.client.create_experiment(name, artifact_location=location))
        except Exception:
            # A parallel job created it first.
            found = self.client.get_experiment_by_name(name)
            if found is None:
                raise
            return str(found.experiment_id)

    def find_run(self, experiment_id: str, tag: str, value: str) -> Any | None:
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
                self.client.set_tag(run_id, key, _clip(value, _TAG_LIMIT))
            return run_id
        run = self.client.create_run(
            experiment_id,
            run_name=name,
            tags={
                KIND: "sweep",
                SWEEP_KEY: sweep_key,
                **{k: _clip(v, _TAG_LIMIT) for k, v in tags.items()},
            },
        )
        return str(run.info.run_id)

    def end_sweep(self, run_id: str, metrics: Mapping[str, float], failed: bool) -> None:
        from mlflow.entities import Metric, RunTag

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
        self, experiment_id: str, job_key: str, name: str, parent_run_id: str | None
    ) -> tuple[str, Any | None]:
        """The job's run (found by job key, else created) and the found run, if any."""
        found = self.find_run(experiment_id, JOB_KEY, job_key)
        if found is not None:
            return str(found.info.run_id), found
        tags = {KIND: "job", JOB_KEY: job_key}
        if parent_run_id:
            tags[PARENT] = parent_run_id
        run = _retry(lambda: self.client.create_run(experiment_id, run_name=name, tags=tags))
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
    ) -> None:
        """Params, metrics, artifacts, then the status tags and the run's end, in that order.

        The ``twostep.status`` tag is written after everything else: a run that has it is
        complete. Params already on a reused run are not logged again (MLflow refuses a
        changed value, and a re-run may differ in where it ran, e.g. the task runner).
        """
        from mlflow.entities import Metric, Param, RunTag

        existing = existing_params or {}
        new_params = [Param(k, v) for k, v in params.items() if k not in existing]
        for start in range(0, len(new_params), 100):
            _retry(partial(self.client.log_batch, run_id, params=new_params[start : start + 100]))
        now = int(time.time() * 1000)
        metric_list = [Metric(*point) for point in metric_points(metrics, now)]
        for start in range(0, len(metric_list), 1000):
            _retry(
                partial(self.client.log_batch, run_id, metrics=metric_list[start : start + 1000])
            )
        for path, folder in files:
            _retry(partial(self.client.log_artifact, run_id, str(path), folder))
        run_tags = [RunTag(k, _clip(v, _TAG_LIMIT)) for k, v in tags.items()]
        _retry(lambda: self.client.log_batch(run_id, tags=run_tags))
        _retry(lambda: self.client.set_terminated(run_id, status=terminated))


def _clip(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def metric_points(
    metrics: Mapping[str, float | list[float]], timestamp_ms: int
) -> list[tuple[str, float, int, int]]:
    """``(key, value, timestamp, step)`` of every metric point: a list is one point per step."""
    points: list[tuple[str, float, int, int]] = []
    for key, value in metrics.items():
        if isinstance(value, list):
            points += [(key, float(v), timestamp_ms, step) for step, v in enumerate(value)]
        else:
            points.append((key, float(value), timestamp_ms, 0))
    return points


def job_tags(record: Mapping[str, Any]) -> dict[str, str]:
    """The status tags written at the end of a job run's logging, in one batch."""
    tags = {
        STATUS: str(record["status"]),
        SCRIPTED: "true" if record["scripted"] else "false",
        REUSED: "true" if record["reused"] else "false",
    }
    if record["error"]:
        tags[ERROR] = str(record["error"])
    return tags


# ----------------------------------------------------------------- params / metrics


def log_job_run(
    tracker: Tracker, experiment_id: str, parent: str | None, record: Mapping[str, Any]
) -> str:
    """Log one job (``record``: plain data, see ``flows.job._job_record``) to its run,
    found again by job key; return the run id.

    A run recorded completely before (same job key: same result) is left as it is:
    logging again would only append a second point to every metric's history.
    """
    run_id, found = tracker.job_run(experiment_id, record["key"], record["name"], parent)
    if found is not None and found.data.tags.get(STATUS) in ("success", "timeout"):
        return run_id
    tracker.log_job(
        run_id,
        record["params"],
        record["metrics"],
        job_tags(record),
        [(Path(path), folder) for path, folder in record["files"]],
        existing_params=dict(found.data.params) if found is not None else None,
        terminated="FAILED" if record["status"] == "failed" else "FINISHED",
    )
    return run_id


def job_params(config: Mapping[str, Any]) -> dict[str, str]:
    """The flattened resolved config as params; secret-looking keys are left out.

    ``*_env`` keys name an environment variable (``llm.api_key_env: OPENAI_API_KEY``),
    never hold its value, so they are kept.
    """
    params: dict[str, str] = {}
    for key, text in flatten_config(config).items():
        if key.startswith("hydra.") or (_SECRET.search(key) and not key.endswith("_env")):
            continue
        params[key] = _clip(text, _PARAM_LIMIT)
    return params


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, int | float):
        return float(value)
    return None


def job_metrics(result: Mapping[str, Any], timings: Mapping[str, float]) -> dict[str, Any]:
    """Metrics of one job (docs/tracking.md); a value that is absent is not logged."""
    metrics: dict[str, Any] = {"success": 1.0 if result.get("success") else 0.0}
    for key in (
        "exec_length",
        "sa_length",
        "planning_time_s",
        "llm_time_s",
        "state_editing_time_s",
        "wall_time_s",
        "sa_planning_time_s",
        "embodied_length",  # executor=embodied
        "waits",
        "backoffs",
    ):
        number = _number(result.get(key))
        if number is not None:
            metrics[key] = number
    exec_length, sa_length = _number(result.get("exec_length")), _number(result.get("sa_length"))
    if exec_length and sa_length is not None:
        metrics["speedup_exec"] = sa_length / exec_length
    subgoals = result.get("subgoals")
    if result.get("method") == "twostep" and isinstance(subgoals, list):
        statuses = [s.get("status") for s in subgoals if isinstance(s, Mapping)]
        metrics["subgoals_proposed"] = float(len(statuses))
        metrics["subgoals_accepted"] = float(statuses.count("accepted"))
        metrics["subgoals_discarded"] = float(statuses.count("discarded"))
    calls = [c for c in result.get("planner_calls") or [] if isinstance(c, Mapping)]
    for call in calls:
        number = _number(call.get("planner_time_s"))
        if number is not None:
            metrics[f"planner_time_s.{call.get('role')}.{call.get('agent')}"] = number
    per_call = [_number(c.get("planner_time_s")) for c in calls]
    if per_call and all(v is not None for v in per_call):
        metrics["planner_time_s"] = [v for v in per_call if v is not None]
    if calls:  # Table II's "timeout": planner calls stopped by their time limit
        from twostep.report.table2 import planner_limit_hits

        metrics["planner_timeouts"] = float(planner_limit_hits(result))
    for key, value in timings.items():
        metrics[key] = float(value)
    return metrics
