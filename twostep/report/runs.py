"""The run table every report starts from: one row per job, whatever its source.

A report reads jobs from MLflow (``flows/report_cli.py``, following ``docs/tracking.md``),
from a sweep's directory (``flows/report_sources.py``, no MLflow needed) or from a
report's own ``runs.csv`` (:func:`load_runs_from_csv`: redraw a report without its
source). All end up in the same *canonical run table*, checked and typed by
:func:`normalise_runs`:

=================  ===================================================================
column             meaning
=================  ===================================================================
``run_id``         MLflow run id, or the job directory relative to the sweep dir
``domain``         domain name
``task``           task number (Int64)
``method``         ``sa`` | ``ma`` | ``twostep``
``decomposer``     decomposer name for TwoStep, ``""`` for SA and MA
``agents``         N (Int64); always 1 for SA, which ignores N
``agents_param``   N as launched (SA jobs of a grid may have been launched with N > 1)
``seed``           seed (Int64)
``status``         ``success`` | ``failed`` | ``timeout`` | ``running``
``error``          one line for failed jobs, else ``""``
``job_key``        ``twostep.job_key`` tag (``""`` if unknown): a re-run job's older runs
                   are superseded by its latest
``start_time``     run start, ms since the epoch (NaN if unknown)
metric columns     :data:`METRICS` (float, NaN when not recorded)
``param.<name>``   every other setting of the run, as a string (opaque to the report)
=================  ===================================================================

Rows whose domain, task, method, agents or seed cannot be read are kept (with NA keys):
:func:`twostep.report.build.build_report` counts and lists them, never drops them. The
report knows no config: what the ``param.*`` columns stand for (which can split a series,
which a method reads, the executor, the planner's settings) comes beside the table, from
whoever read the config (:class:`RunParams`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from twostep.planner.limits import guard_stops, planner_limit_hits
from twostep.util.outcome import STATUS_SYNONYMS, ReportStatus, SubgoalStatus, limit_reached


class ReportInputError(Exception):
    """Input a report cannot be built from; the message is one line for the terminal."""


#: Metrics a job logs (docs/tracking.md) that the report reads.
METRICS: tuple[str, ...] = (
    "exec_length",
    "planning_time_s",
    "llm_time_s",
    "state_editing_time_s",
    "wall_time_s",
    "sa_length",
    "speedup_exec",
    "subgoals_proposed",
    "subgoals_accepted",
    "subgoals_discarded",
    "embodied_length",  # executor=embodied (Table II)
    "waits",
    "backoffs",
    "planner_timeouts",  # planner calls that hit their time limit (Table II's "timeout")
    "planner_guard_stops",  # planner calls the wall-clock guard stopped (reported apart)
)

#: Columns that identify a job: one (domain, task, method, decomposer, N, seed) cell.
KEY_COLUMNS: tuple[str, ...] = ("domain", "task", "method", "decomposer", "agents", "seed")

PARAM_PREFIX = "param."


def _every_param(name: str) -> bool:
    return True


def _read_by_every_run(name: str, method: str, decomposer: str) -> bool:
    return True


@dataclass(frozen=True)
class RunParams:
    """What a run table's ``param.*`` columns stand for (names without ``param.``), told by
    whoever made the table from a config (``flows.report_sources.RUN_PARAMS``): the report
    itself knows no config. The default knows nothing: every param may split series, for
    every method; no executor, no planner settings.

    * ``identity``: whether the param can change a run's result (one that cannot never
      splits series);
    * ``read_by``: whether runs of ``(method, decomposer)`` read the param (one they do
      not read never splits their series);
    * ``executor``: the param naming a run's executor (whether its seed matters:
      :mod:`twostep.report.seeds`);
    * ``planner``: the params that describe the planner, each with its unit (Table II's
      caption).
    """

    identity: Callable[[str], bool] = _every_param
    read_by: Callable[[str, str, str], bool] = _read_by_every_run
    executor: str | None = None
    planner: tuple[tuple[str, str], ...] = ()


NO_PARAMS = RunParams()
"""A run table's params told nothing about (the default of every report function)."""

METHODS: tuple[str, ...] = ("sa", "ma", "twostep")


def is_missing(value: object) -> bool:
    """True for None, NaN, pandas NA and the empty string."""
    if value is None:
        return True
    if isinstance(value, str):
        return value.strip() == ""
    if isinstance(value, float):
        return math.isnan(value)
    try:
        return bool(pd.isna(value))
    except (TypeError, ValueError):
        return False


def normalise_status(status: object, success: object = None) -> str:
    """A :class:`~twostep.util.outcome.ReportStatus` value from a status word (its
    :data:`~twostep.util.outcome.STATUS_SYNONYMS`) and/or a success flag.

    ``status`` wins when it is a known word; otherwise a truthy ``success`` means
    ``success`` and anything else ``failed`` (a job that recorded neither did not finish
    cleanly, so it is counted as failed rather than dropped).
    """
    if not is_missing(status):
        word = str(status).strip().lower()
        if word in STATUS_SYNONYMS:
            return STATUS_SYNONYMS[word].value
    if not is_missing(success):
        text = str(success).strip().lower()
        if text in ("1", "1.0", "true", "yes"):
            return ReportStatus.SUCCESS.value
    return ReportStatus.FAILED.value


def _to_int(value: object) -> int | None:
    if is_missing(value):
        return None
    try:
        number = float(str(value))
    except ValueError:
        return None
    if math.isnan(number) or number != int(number):
        return None
    return int(number)


def _to_float(value: object) -> float:
    if is_missing(value) or isinstance(value, bool):
        return float("nan")
    try:
        return float(str(value))
    except ValueError:
        return float("nan")


def _to_text(value: object) -> str:
    return "" if is_missing(value) else str(value).strip()


def normalise_runs(frame: pd.DataFrame) -> pd.DataFrame:
    """Check and type a run table (see the module docstring); returns a new frame.

    Accepts the canonical columns, or ``success`` instead of ``status``. Idempotent.
    Raises :class:`ReportInputError` when a required column is missing altogether.
    """
    required = ("domain", "task", "method", "agents", "seed")
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise ReportInputError(f"run table lacks column(s) {', '.join(missing)}")
    if "status" not in frame.columns and "success" not in frame.columns:
        raise ReportInputError("run table has neither a 'status' nor a 'success' column")

    records: list[dict[str, Any]] = []
    param_columns = sorted(c for c in frame.columns if str(c).startswith(PARAM_PREFIX))
    for position, row in enumerate(frame.to_dict("records")):
        method = _to_text(row.get("method")).lower()
        decomposer = _to_text(row.get("decomposer")) if method == "twostep" else ""
        agents_param = _to_int(row.get("agents_param", row.get("agents")))
        agents = 1 if method == "sa" else _to_int(row.get("agents"))
        run_id = _to_text(row.get("run_id")) or f"row{position}"
        record: dict[str, Any] = {
            "run_id": run_id,
            "domain": _to_text(row.get("domain")) or None,
            "task": _to_int(row.get("task")),
            "method": method or None,
            "decomposer": decomposer,
            "agents": agents,
            "agents_param": agents_param,
            "seed": _to_int(row.get("seed")),
            "status": normalise_status(row.get("status"), row.get("success")),
            "error": _to_text(row.get("error")).splitlines()[0]
            if _to_text(row.get("error"))
            else "",
            "job_key": _to_text(row.get("job_key")),
            "start_time": _to_float(row.get("start_time")),
        }
        for metric in METRICS:
            record[metric] = _to_float(row.get(metric))
        for column in param_columns:
            record[column] = _to_text(row.get(column))
        records.append(record)

    columns = [
        "run_id",
        "domain",
        "task",
        "method",
        "decomposer",
        "agents",
        "agents_param",
        "seed",
        "status",
        "error",
        "job_key",
        "start_time",
        *METRICS,
        *param_columns,
    ]
    out = pd.DataFrame.from_records(records, columns=columns)
    for column in ("task", "agents", "agents_param", "seed"):
        out[column] = out[column].astype("Int64")
    for column in (*METRICS, "start_time"):
        out[column] = out[column].astype("float64")
    for column in ("domain", "method"):
        out[column] = out[column].astype("object")
    return out


def _subgoal_counts(subgoals: object) -> dict[str, float]:
    if not isinstance(subgoals, list):
        return {}
    statuses = [s.get("status") for s in subgoals if isinstance(s, Mapping)]
    return {
        "subgoals_proposed": float(len(statuses)),
        "subgoals_accepted": float(sum(1 for s in statuses if s == SubgoalStatus.ACCEPTED)),
        "subgoals_discarded": float(sum(1 for s in statuses if s == SubgoalStatus.DISCARDED)),
    }


def result_to_row(result: Mapping[str, Any]) -> dict[str, Any]:
    """The run-table row of one result.json (the :class:`twostep.methods.twostep.RunResult` shape)."""
    row: dict[str, Any] = {
        key: result.get(key) for key in ("domain", "task", "method", "agents", "seed")
    }
    row["decomposer"] = result.get("decomposer")
    raw_status = _to_text(result.get("status")).lower()
    success = result.get("success")
    if success is True:
        row["status"] = ReportStatus.SUCCESS.value
    elif limit_reached(raw_status):
        row["status"] = ReportStatus.TIMEOUT.value
    else:
        row["status"] = ReportStatus.FAILED.value
    if row["status"] != ReportStatus.SUCCESS:
        row["error"] = _to_text(result.get("message")) or raw_status or "not successful"
    for metric in METRICS:
        if metric in result:
            row[metric] = result[metric]
    row.update(_subgoal_counts(result.get("subgoals")))
    row["planner_timeouts"] = float(planner_limit_hits(result))
    row["planner_guard_stops"] = float(guard_stops(result))
    exec_length = _to_float(result.get("exec_length"))
    sa_length = _to_float(result.get("sa_length"))
    if "speedup_exec" not in result and exec_length > 0 and not math.isnan(sa_length):
        row["speedup_exec"] = sa_length / exec_length
    return row


def load_runs_from_csv(path: Path) -> pd.DataFrame:
    """The canonical run table of a ``runs.csv`` a report wrote (or any CSV with the
    canonical columns). Every value is read as text, so params keep their spelling."""
    if not path.is_file():
        raise ReportInputError(f"runs file not found: {path}")
    try:
        frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    except (OSError, UnicodeDecodeError, pd.errors.ParserError) as error:
        raise ReportInputError(f"cannot read {path}: {error}") from None
    if frame.empty:
        raise ReportInputError(f"no runs in {path}")
    return normalise_runs(frame)


def __getattr__(name: str) -> Any:
    """``load_runs_from_sweep_dir`` moved to :mod:`flows.report_sources` (it reads the
    config each job's directory holds): the old name still imports, with a warning."""
    if name == "load_runs_from_sweep_dir":
        from twostep import moved_name

        return moved_name(__name__, name, "flows.report_sources")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
