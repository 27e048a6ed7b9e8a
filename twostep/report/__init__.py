"""Reports: the paper's Fig. 3, Tables I and II and % changes from a table of runs.

Pure analysis (pandas, matplotlib); reading MLflow lives in ``flows/report_cli.py``.
Typical use, from any source of runs::

    from twostep.report import build_report, load_runs_from_sweep_dir, write_report

    report = build_report(load_runs_from_sweep_dir(Path("outputs/multiruns/...")))
    write_report(report, Path("outputs/reports/x"), title="...", source="...")
    report.compared     # the same cells over the tasks every series solved (the figures)
    report.summary      # per domain, series, N: mean/std over seeds, counts
"""

from twostep.report.build import REPORT_METRICS, Report, build_report, series_label
from twostep.report.render import format_console, render_markdown, write_report
from twostep.report.runs import (
    METRICS,
    ReportInputError,
    load_runs_from_csv,
    load_runs_from_sweep_dir,
    normalise_runs,
    result_to_row,
)

__all__ = [
    "METRICS",
    "REPORT_METRICS",
    "Report",
    "ReportInputError",
    "build_report",
    "format_console",
    "load_runs_from_csv",
    "load_runs_from_sweep_dir",
    "normalise_runs",
    "render_markdown",
    "result_to_row",
    "series_label",
    "write_report",
]
