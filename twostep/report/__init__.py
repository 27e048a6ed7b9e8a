"""Reports: the paper's Fig. 3, Tables I and II and % changes from a table of runs.

Pure analysis (pandas, matplotlib) of a run table with canonical columns
(:mod:`twostep.report.runs`); reading MLflow and a sweep's directory, and what a config's
params stand for, live in ``flows/`` (``report_cli.py``, ``report_sources.py``).
Typical use, from any source of runs::

    from flows.report_sources import RUN_PARAMS, load_runs_from_sweep_dir
    from twostep.report import build_report, write_report

    runs = load_runs_from_sweep_dir(Path("outputs/multiruns/..."))
    report = build_report(runs, params=RUN_PARAMS)
    write_report(report, Path("outputs/reports/x"), title="...", source="...")
    report.compared     # the same cells over the tasks every series solved (the figures)
    report.summary      # per domain, series, N: mean/std over seeds, counts
"""

from typing import Any

from twostep.report.build import REPORT_METRICS, Report, build_report, series_label
from twostep.report.render import format_console, render_markdown, write_report
from twostep.report.runs import (
    METRICS,
    ReportInputError,
    RunParams,
    load_runs_from_csv,
    normalise_runs,
    result_to_row,
)

__all__ = [
    "METRICS",
    "REPORT_METRICS",
    "Report",
    "ReportInputError",
    "RunParams",
    "build_report",
    "format_console",
    "load_runs_from_csv",
    "normalise_runs",
    "render_markdown",
    "result_to_row",
    "series_label",
    "write_report",
]


def __getattr__(name: str) -> Any:
    """``load_runs_from_sweep_dir`` moved to :mod:`flows.report_sources` (it reads the
    config each job's directory holds): the old name still imports, with a warning."""
    if name == "load_runs_from_sweep_dir":
        from twostep import moved_name

        return moved_name(__name__, name, "flows.report_sources")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
