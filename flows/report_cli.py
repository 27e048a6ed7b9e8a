"""The ``twostep-report`` command: the paper's figures and tables from a sweep's runs.

Reads the job runs of one MLflow experiment (the contract is ``docs/tracking.md``), the
``result.json`` files of a Hydra multirun directory, or a report's own ``runs.csv``;
builds the report with :mod:`twostep.report` (pure analysis), writes PNG / PDF / SVG /
CSV / Markdown files, and logs them back to MLflow as the artifacts of a report run (tag
``twostep.kind=report``) in the same experiment.

    twostep-report --experiment NAME_OR_ID [--tracking-uri URI] [--out DIR] [--no-log]
    twostep-report --sweep-dir outputs/multiruns/2026-01-01/12-00-00 [--out DIR]
    twostep-report --runs-csv docs/report/runs.csv --out docs/report

Table II's task descriptions come from ``titles.yaml`` in the kitchen's data folder
(``--data-root``, else the runs' ``data.root``, else the package's data).

Exit codes: 0 report written; 1 nothing could be reported (unknown experiment, no runs,
no successful run); 2 bad command line, or an input file that is not text (named).

For a test or a notebook, the building blocks are::

    runs = load_runs_from_mlflow("sqlite:///outputs/mlflow.db", "my-sweep")
    report = twostep.report.build_report(runs)
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
import re
import shlex
import sys
import urllib.error
import urllib.request
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

import pandas as pd

from flows.locations import sqlite_path
from flows.report_sources import (
    RUN_PARAMS,
    load_runs_from_sweep_dir,
    params_to_columns,
    replay_bundle,
    replay_model,
    replay_settings,
)
from flows.sweep_state import job_records
from flows.tracking.contents import unsolved_name
from twostep.cli import console_main
from twostep.report import (
    METRICS,
    Report,
    ReportInputError,
    build_report,
    format_console,
    load_runs_from_csv,
    normalise_runs,
    write_report,
)
from twostep.report.runs import PARAM_PREFIX
from twostep.report.table2 import TABLE2_DOMAIN, read_task_titles
from twostep.tasks.benchmark import DEFAULT_DATA_ROOT
from twostep.util.files import NotTextError, read_text_file
from twostep.util.outcome import ReportStatus

DEFAULT_TRACKING_URI = "sqlite:///outputs/mlflow.db"
KIND_TAG = "twostep.kind"
STATUS_TAG = "twostep.status"
ERROR_TAG = "twostep.error"
JOB_KEY_TAG = "twostep.job_key"
CONFIG_TAG = "twostep.config"
GRID_TAG = "twostep.grid_agents"


def _quiet_mlflow() -> None:
    """Environment MLflow and litellm read at import: no telemetry, no network lookups."""
    os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    for name in ("mlflow", "alembic"):
        logging.getLogger(name).setLevel(logging.WARNING)


def _check_store(tracking_uri: str, timeout_s: float = 10.0) -> None:
    """Fail with one line before MLflow creates an empty store or retries for minutes."""
    hint = "run a sweep first, or pass --tracking-uri or --sweep-dir"
    parsed = urlparse(tracking_uri)
    if parsed.scheme == "sqlite":
        path = sqlite_path(tracking_uri) or Path(":memory:")
        if not path.is_file():
            raise ReportInputError(f"no MLflow store at {path} ({hint})")
    elif parsed.scheme in ("", "file"):
        path = Path(parsed.path or tracking_uri)
        if not path.is_dir():
            raise ReportInputError(f"no MLflow store at {path} ({hint})")
    elif parsed.scheme in ("http", "https"):
        url = tracking_uri.rstrip("/") + "/health"
        try:
            with urllib.request.urlopen(url, timeout=timeout_s):
                pass
        except (urllib.error.URLError, OSError) as error:
            reason = getattr(error, "reason", error)
            raise ReportInputError(
                f"MLflow tracking server {tracking_uri} cannot be reached: {reason}"
            ) from None


def _one_line(error: BaseException) -> str:
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0] if text else ''}".rstrip(": ")


@dataclass(frozen=True)
class MlflowRuns:
    """The job runs of one experiment as a canonical run table, and what was skipped."""

    runs: pd.DataFrame
    experiment_id: str
    ignored: int  # runs of the experiment that are not jobs (sweep/report parents, others)
    sweep_dirs: tuple[str, ...] = ()  # the sweeps' directories (their parents' tags)
    name: str = ""  # the experiment's name (it may have been asked for by id)

    def missing_jobs(self) -> tuple[int, int, list[str]]:
        """(job keys with a run, job keys the sweeps' records list, the record folders
        read): the store is a view of the job store, and can have lost runs."""
        recorded: set[str] = set()
        folders = [folder for folder in self.sweep_dirs if Path(folder).is_dir()]
        for folder in folders:
            recorded |= {str(r["job_key"]) for r in job_records(Path(folder)) if r.get("job_key")}
        logged = {str(key) for key in self.runs.get("job_key", []) if key}
        return len(logged & recorded), len(recorded), folders


def _run_params(tags: dict[str, str], params: dict[str, str]) -> dict[str, str]:
    """A job run's params with the rest of its identity config (tag ``twostep.config``,
    JSON; runs logged before it existed have every config key as a param)."""
    try:
        rest = json.loads(tags.get(CONFIG_TAG) or "{}")
    except ValueError:
        rest = {}
    return (
        {**{str(k): str(v) for k, v in rest.items()}, **params}
        if isinstance(rest, dict)
        else params
    )


def _run_row(run: Any) -> dict[str, Any] | None:
    tags: dict[str, str] = dict(run.data.tags)
    params = _run_params(tags, dict(run.data.params))
    kind = tags.get(KIND_TAG)
    if kind is not None and kind != "job":
        return None
    if kind is None and "domain.name" not in params:
        return None
    metrics: dict[str, float] = dict(run.data.metrics)
    row: dict[str, Any] = params_to_columns(params)
    if GRID_TAG in tags:  # the grid's N; the param is the N the job ran (1 for SA)
        row["agents_param"] = tags[GRID_TAG]
    row["run_id"] = run.info.run_id
    row["job_key"] = tags.get(JOB_KEY_TAG, "")
    row["start_time"] = run.info.start_time
    for metric in METRICS:  # an unsuccessful job's values: under unsolved.<name>
        for name in (metric, unsolved_name(metric)):
            if name in metrics:
                row[metric] = metrics[name]
    status = tags.get(STATUS_TAG)
    lifecycle = str(run.info.status).upper()
    if status is None and lifecycle in ("RUNNING", "SCHEDULED"):
        status = ReportStatus.RUNNING.value
    elif status is None and lifecycle in ("FAILED", "KILLED"):
        status = ReportStatus.FAILED.value
    row["status"] = status
    row["success"] = metrics.get("success")
    error = tags.get(ERROR_TAG, "")
    if not error and status is None and "success" not in metrics:
        error = f"no status tag and no success metric (MLflow run {lifecycle.lower()})"
    row["error"] = error
    return row


def read_mlflow_runs(tracking_uri: str, experiment: str) -> MlflowRuns:
    """Every job run of ``experiment`` (tag ``twostep.kind=job``) as a run table.

    Raises :class:`ReportInputError` with a one-line message for a missing store, an
    unknown experiment, a store that cannot be read, or an experiment without job runs.
    """
    _check_store(tracking_uri)
    _quiet_mlflow()
    from mlflow.entities import ViewType
    from mlflow.tracking import MlflowClient

    try:
        client = MlflowClient(tracking_uri=tracking_uri)
        found = find_experiment(client, experiment)
        if found is None:
            known = [f"{e.experiment_id} {e.name}" for e in client.search_experiments()]
            listed = "; ".join(sorted(known, key=lambda k: int(k.split()[0]))) or "none"
            raise ReportInputError(
                f"unknown experiment '{experiment}' in {tracking_uri} (known, id and name: "
                f"{listed})"
            )
        runs: list[Any] = []
        token: str | None = None
        while True:
            page = client.search_runs(
                [found.experiment_id],
                run_view_type=ViewType.ACTIVE_ONLY,
                max_results=1000,
                page_token=token,
            )
            runs.extend(page)
            token = page.token
            if not token:
                break
    except ReportInputError:
        raise
    except Exception as error:  # any store failure: one line, no traceback
        raise ReportInputError(
            f"cannot read MLflow at {tracking_uri}: {_one_line(error)}"
        ) from error
    rows = [row for row in (_run_row(run) for run in runs) if row is not None]
    sweep_dirs = tuple(
        sorted(
            {
                str(run.data.tags["twostep.sweep_dir"])
                for run in runs
                if run.data.tags.get(KIND_TAG) == "sweep" and run.data.tags.get("twostep.sweep_dir")
            }
        )
    )
    if not rows:
        raise ReportInputError(
            f"experiment '{experiment}' has no job runs (tag {KIND_TAG}=job) in {tracking_uri}"
        )
    frame = normalise_runs(pd.DataFrame.from_records(rows))
    return MlflowRuns(
        frame, str(found.experiment_id), len(runs) - len(rows), sweep_dirs, str(found.name)
    )


def find_experiment(client: Any, experiment: str) -> Any | None:
    """The experiment named ``experiment``, else the one with that id (None: neither)."""
    found = client.get_experiment_by_name(experiment)
    if found is None and experiment.strip().isdigit():
        with contextlib.suppress(Exception):  # MLflow raises for an unknown id
            found = client.get_experiment(experiment.strip())
    if found is not None and found.lifecycle_stage != "active":
        return None
    return found


def load_runs_from_mlflow(tracking_uri: str, experiment: str) -> pd.DataFrame:
    """The canonical run table of an experiment's job runs (see :func:`read_mlflow_runs`)."""
    return read_mlflow_runs(tracking_uri, experiment).runs


def _metric_key(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.\-]+", "_", text).strip("_")


def report_metrics(report: Report) -> dict[str, float]:
    """Counts and changes of a report as MLflow metric names and values."""
    values: dict[str, float] = {f"report.runs.{k}": float(v) for k, v in report.counts.items()}
    for row in report.changes.to_dict("records"):
        key = (
            f"{_metric_key(str(row['series']))}.vs_{_metric_key(str(row['baseline']))}"
            f".{row['metric']}.n{row['agents']}"
        )
        for column in ("change_pct", "change_pct_raw"):
            if not pd.isna(row[column]):
                values[f"{column}.{key}"] = float(row[column])
    return values


def log_report_run(
    tracking_uri: str, experiment_id: str, out_dir: Path, report: Report, command: str
) -> str:
    """Log ``out_dir`` as the artifacts of a new report run; return its run id."""
    _quiet_mlflow()
    from mlflow.entities import Metric, Param
    from mlflow.tracking import MlflowClient

    client = MlflowClient(tracking_uri=tracking_uri)
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
    run = client.create_run(
        experiment_id,
        run_name=f"report {stamp}",
        tags={KIND_TAG: "report", "twostep.report.command": command[:5000]},
    )
    run_id: str = run.info.run_id
    try:
        now = int(datetime.now(UTC).timestamp() * 1000)
        metrics = [Metric(k, v, now, 0) for k, v in report_metrics(report).items()]
        params = [
            Param("report.series", ", ".join(report.series)[:6000]),
            Param("report.variant_params", ", ".join(report.variant_params) or "none"),
        ]
        client.log_batch(run_id, metrics=metrics, params=params)
        client.log_artifacts(run_id, str(out_dir))
    except Exception:
        client.set_terminated(run_id, status="FAILED")
        raise
    client.set_terminated(run_id)
    return run_id


# ------------------------------------------------------------------ command line


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="twostep-report",
        description="Fig. 3, Tables I and II and the percent changes of the TwoStep paper "
        "from a sweep's runs: PNG/PDF/SVG figures, CSV and Markdown files, logged back to "
        "MLflow as a report run.",
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument(
        "--experiment",
        metavar="NAME_OR_ID",
        help="MLflow experiment of the sweep: its name or its id (a sweep prints the command)",
    )
    source.add_argument(
        "--sweep-dir",
        metavar="DIR",
        type=Path,
        help="Hydra multirun directory: read every result.json below it (no MLflow needed)",
    )
    source.add_argument(
        "--runs-csv",
        metavar="FILE",
        type=Path,
        help="a report's runs.csv: redraw that report (no MLflow needed)",
    )
    parser.add_argument(
        "--tracking-uri",
        default=DEFAULT_TRACKING_URI,
        metavar="URI",
        help=f"MLflow tracking URI (default: {DEFAULT_TRACKING_URI})",
    )
    parser.add_argument(
        "--out",
        type=Path,
        metavar="DIR",
        help="output directory (default: outputs/reports/<experiment or sweep dir>)",
    )
    parser.add_argument(
        "--data-root",
        type=Path,
        metavar="DIR",
        help="data root for Table II's task descriptions (<DIR>/alfworld/titles.yaml; "
        "default: the runs' data.root, else the package's data)",
    )
    parser.add_argument(
        "--bundle",
        type=Path,
        metavar="DIR",
        help="the replay bundle of an experiment=paper_replay sweep: adds Table I and Fig. 3 "
        "with the official code's numbers (default: the bundle the runs name, llm.bundle)",
    )
    parser.add_argument("--no-log", action="store_true", help="do not log the report run to MLflow")
    return parser


def task_titles(runs: pd.DataFrame, data_root: Path | None) -> dict[int, str]:
    """Table II's task descriptions from the first data root that has them: ``data_root``,
    the kitchen runs' ``data.root``, the package's data."""
    column = f"{PARAM_PREFIX}data.root"
    kitchen = runs[runs["domain"] == TABLE2_DOMAIN]
    if kitchen.empty:
        return {}
    roots = [data_root] if data_root is not None else []
    if column in kitchen:
        roots += [Path(str(v)) for v in dict.fromkeys(kitchen[column]) if str(v)]
    roots.append(DEFAULT_DATA_ROOT)
    for root in roots:
        titles = read_task_titles(root / TABLE2_DOMAIN)
        if titles:
            return titles
    return {}


def _warn_missing_jobs(loaded: MlflowRuns) -> None:
    """One line when the store holds fewer job runs than the sweep recorded jobs."""
    logged, recorded, folders = loaded.missing_jobs()
    if logged < recorded:
        print(
            f"twostep-report: warning: the MLflow store holds {logged} job run(s) of the "
            f"{recorded} job(s) recorded in {', '.join(folders)}: the report misses the "
            "others; run the sweep's command again to log them (finished jobs are reused, "
            "not recomputed)",
            file=sys.stderr,
        )


def _first_file_not_text(args: argparse.Namespace) -> str | None:
    """The first input file that is not UTF-8 text (a runs.csv, a sweep's result.json or
    job config), as the line to print; None when all are text (or there are none)."""
    if args.runs_csv is not None:
        files = [args.runs_csv]
    elif args.sweep_dir is not None and Path(args.sweep_dir).is_dir():
        folder = Path(args.sweep_dir)
        files = sorted([*folder.rglob("result.json"), *folder.rglob(".hydra/config.yaml")])
    else:
        files = []
    for path in files:
        try:
            read_text_file(path)
        except NotTextError as error:
            return f"{error}: move it out of the way or delete it"
        except OSError:
            continue  # a directory or no such file: the readers report those themselves
    return None


def _experiment_name(runs: pd.DataFrame) -> str:
    """The one MLflow experiment the runs were logged to, or ``""``."""
    column = f"{PARAM_PREFIX}mlflow.experiment"
    names = (
        {str(v) for v in runs[column] if str(v) not in ("", "None")} if column in runs else set()
    )
    return names.pop() if len(names) == 1 else ""


def _sweep_name(path: Path) -> str:
    resolved = path.resolve()
    return f"{resolved.parent.name}_{resolved.name}" if resolved.parent.name else resolved.name


def _safe_dir_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.\-]+", "_", name).strip("_") or "report"


def _replay_report(report: Report, bundle: Path | None, out_dir: Path) -> list[Path]:
    """Table I and Fig. 3 of a replay (:mod:`twostep.report.replay`) when the runs replay
    a bundle (or ``--bundle`` names one); a bundle that cannot be read: a warning."""
    from twostep.replay import BundleError, load_bundle
    from twostep.report.replay import replay_tables
    from twostep.report.replay_plots import write_replay

    found = bundle or replay_bundle(report.runs)
    if found is None:
        return []
    try:
        loaded = load_bundle(Path(found))
        model = replay_model(report.runs) or (loaded.models[0] if loaded.models else "")
        tables = replay_tables(report.runs, loaded, model)
        return write_replay(tables, Path(found), out_dir, replay_settings(report.runs))
    except (BundleError, OSError) as error:
        print(f"twostep-report: warning: no replay tables: {_one_line(error)}", file=sys.stderr)
        return []


@console_main
def main(argv: Sequence[str] | None = None) -> int:
    """Run the command; returns the exit code (0 ok, 1 nothing to report)."""
    args = _parser().parse_args(argv)
    arguments = list(sys.argv[1:] if argv is None else argv)
    command = shlex.join(["twostep-report", *arguments])
    experiment_id: str | None = None
    not_text = _first_file_not_text(args)
    if not_text is not None:
        print(f"twostep-report: {not_text}", file=sys.stderr)
        return 2
    try:
        if args.sweep_dir is not None:
            runs = load_runs_from_sweep_dir(args.sweep_dir)
            name = _sweep_name(args.sweep_dir)
            source = f"Hydra multirun directory `{args.sweep_dir}`"
            read_line = f"read {len(runs)} job(s) from {args.sweep_dir}"
        elif args.runs_csv is not None:
            runs = load_runs_from_csv(args.runs_csv)
            name = _experiment_name(runs) or _safe_dir_name(args.runs_csv.resolve().parent.name)
            source = f"the run table `{args.runs_csv}`"
            read_line = f"read {len(runs)} run(s) from {args.runs_csv}"
        else:
            loaded = read_mlflow_runs(args.tracking_uri, args.experiment)
            runs, experiment_id, name = loaded.runs, loaded.experiment_id, loaded.name
            source = f"MLflow experiment `{name}` (id {experiment_id}) at `{args.tracking_uri}`"
            read_line = f"read {len(runs)} job run(s) from MLflow experiment '{name}'"
            if loaded.ignored:
                read_line += f" (skipped {loaded.ignored} sweep/report run(s))"
            _warn_missing_jobs(loaded)
        report = build_report(runs, task_titles(runs, args.data_root), RUN_PARAMS)
    except ReportInputError as error:
        print(f"twostep-report: {error}", file=sys.stderr)
        return 1

    out_dir: Path = args.out or Path("outputs") / "reports" / _safe_dir_name(name)
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    source_md = f"Source: {source}. Generated {stamp} by `{command}`."
    try:
        paths = write_report(report, out_dir, f"TwoStep report: {name}", source_md)
    except OSError as error:
        print(f"twostep-report: cannot write to {out_dir}: {_one_line(error)}", file=sys.stderr)
        return 1

    replay = _replay_report(report, args.bundle, out_dir)
    paths += replay
    print(read_line)
    print(format_console(report))
    if replay:
        print(f"replay: {out_dir / 'replay.md'} (Table I and Fig. 3 from the bundle's answers)")
    figures = sum(1 for p in paths if p.suffix == ".png")
    tables = sum(1 for p in paths if p.suffix == ".csv")
    print(
        f"report: {out_dir / 'report.md'} ({figures} figures as PNG, PDF and SVG, "
        f"{tables} CSV tables)"
    )

    if experiment_id is not None and not args.no_log:
        try:
            run_id = log_report_run(args.tracking_uri, experiment_id, out_dir, report, command)
        except Exception as error:  # the files are written; say why logging failed
            print(
                f"twostep-report: warning: report not logged to MLflow: {_one_line(error)}",
                file=sys.stderr,
            )
        else:
            print(f"logged to MLflow: run {run_id} ({KIND_TAG}=report) in experiment '{name}'")
    elif not args.no_log:
        print(f"not logged to MLflow (source is a {'sweep dir' if args.sweep_dir else 'CSV'})")

    if not report.has_results:
        print(
            "twostep-report: no successful run with metrics: nothing to average or plot; "
            "the failures are listed in report.md",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
