"""From the run table to the paper's numbers: every table a report shows, as DataFrames.

:func:`build_report` is the entry point. How the numbers are made:

* **Series.** A line in Fig. 3 is a *series*: SA, MA, or TwoStep with one decomposer
  ("TwoStep (goal-split)"). When runs of one job cell (domain, task, method, decomposer,
  N, seed) differ in a config value (two planner time limits, two LLM models), that
  param is a *variant param*: the series are split by it ("... [<param>=10]", the param
  named as the run table names it) and the report says so. A param only counts for the
  runs that read it (``params.read_by``: e.g. the LLM's settings only for TwoStep with the
  LLM decomposer).
* **Means.** Only successful runs with the metric recorded enter a mean. For each
  (domain, series, N, seed) the metric is averaged over tasks; the table shows the mean
  and the sample standard deviation (ddof = 1) of those per-seed averages over seeds, as
  the paper does for its 3 runs, with n (the seeds). A deterministic series (SA, MA,
  TwoStep with an offline decomposer) repeats one distinct run in every seed: its mean is
  that run's (n = 1, no std); see :mod:`twostep.report.seeds`.
* **Counts.** Failed, timed-out and still-running runs are counted in every cell, once
  per (task, seed): SA runs repeated by a grid's N count once.
* **Compared means.** The figures, the normalised panel and the changes average each cell
  over the tasks every series of its domain solved, so that a run lost to a timeout
  never improves a mean; what each series lost is counted and drawn
  (:mod:`twostep.report.compared`). Kitchen runs are measured by their embodied length.
* **Normalised panel.** Per domain and metric, the compared averages of every series
  and N are min-max scaled to [0, 1], then averaged across domains (the paper's
  rightmost column of Fig. 3). A cell that covers fewer of the domain's tasks than the
  others (e.g. expert subgoals, 4 tasks) is left out of the scaling, with a note.
* **Changes.** TwoStep against SA (N = 1) and MA (same N), in percent of the baseline's
  normalised cross-domain average, over the domains both have (as the paper computes
  its -50.1 % ...); also the mean over domains of the raw per-domain changes.
* **Table I.** Execution length on tasks 1, 6, 11, 16 of four domains at N = 2, per
  domain mean +- std over seeds of the 4-task average, and the macro average.

One job per module: :mod:`twostep.report.model` (the :class:`Report`),
:mod:`twostep.report.series`, :mod:`twostep.report.aggregation` (means and normalisation),
:mod:`twostep.report.compared` (the tasks compared), :mod:`twostep.report.seeds` (which
runs a mean is over), :mod:`twostep.report.tables` (changes and Table I),
:mod:`twostep.report.table2`, :mod:`twostep.report.notes`.
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from twostep.report.aggregation import (
    cell_summary,
    cross_domain_means,
    eligible_cells,
    normalise,
    per_seed_means,
    per_task_means,
)
from twostep.report.compared import common_tasks, compared_tables
from twostep.report.model import (
    CELL_COLUMNS,
    METRIC_LABELS,
    METRIC_NAMES,
    REPORT_METRICS,
    SERIES_COLUMNS,
    Report,
)
from twostep.report.notes import coverage_notes, report_notes
from twostep.report.runs import NO_PARAMS, ReportInputError, RunParams, normalise_runs
from twostep.report.seeds import grid_duplicates, measured_runs
from twostep.report.series import (
    assign_series,
    detect_variant_params,
    series_label,
    series_order,
)
from twostep.report.table2 import table_two
from twostep.report.tables import changes_against_baselines, table_one
from twostep.util.outcome import REPORT_STATUSES, ReportStatus

__all__ = [
    "CELL_COLUMNS",
    "METRIC_LABELS",
    "METRIC_NAMES",
    "REPORT_METRICS",
    "SERIES_COLUMNS",
    "Report",
    "RunParams",
    "build_report",
    "detect_variant_params",
    "series_label",
]


def _in_order(cells: pd.DataFrame, rank: Mapping[str, int]) -> pd.DataFrame:
    """Cells by domain, then series in display order, then N."""
    return (
        cells.assign(_rank=cells["series"].map(rank))
        .sort_values(["domain", "_rank", "agents"])
        .drop(columns="_rank")
        .reset_index(drop=True)
    )


def superseded_runs(table: pd.DataFrame) -> pd.Series:
    """True for older runs of a job that was run again (same ``job_key``).

    Re-running a sweep into the same experiment logs the same job again; the report
    counts each job once: its latest finished run (or its latest run if none finished).
    """
    flags = pd.Series(False, index=table.index)
    keyed = table[table["job_key"] != ""]
    if keyed.empty:
        return flags
    order = keyed.assign(
        _finished=(keyed["status"] != ReportStatus.RUNNING).astype(int),
        _start=keyed["start_time"].fillna(-1.0),
    ).sort_values(["job_key", "_finished", "_start"])
    latest = order.groupby("job_key").tail(1).index
    flags.loc[keyed.index.difference(latest)] = True
    return flags


def with_seeded(cells: pd.DataFrame, measured: pd.DataFrame) -> pd.DataFrame:
    """``cells`` with ``seeded``: whether its series' runs differ by seed (else each mean
    is one distinct run: :mod:`twostep.report.seeds`)."""
    seeded = measured.groupby("series")["seeded"].any().to_dict()
    return cells.assign(seeded=[bool(seeded.get(s, False)) for s in cells["series"]])


def build_report(
    runs: pd.DataFrame,
    task_titles: Mapping[int, str] | None = None,
    params: RunParams = NO_PARAMS,
) -> Report:
    """All of a report's tables from a run table (see :mod:`twostep.report.runs`).

    ``task_titles`` (task number -> a short description) heads Table II's columns when
    given; ``params`` says what the table's ``param.*`` columns stand for (the config's
    rules: ``flows.report_sources.RUN_PARAMS`` for a table ``flows/`` made). Raises
    :class:`ReportInputError` when there is no run at all.
    """
    if runs is None or len(runs) == 0:
        raise ReportInputError("no runs to report")
    table = normalise_runs(runs)
    table["placed"] = table[["domain", "task", "method", "agents", "seed"]].notna().all(
        axis=1
    ) & table["method"].isin(["sa", "ma", "twostep"])
    table["superseded"] = superseded_runs(table)
    table["counted"] = table["placed"] & ~table["superseded"]
    variant_params, between = detect_variant_params(table, params)
    table, values_of = assign_series(table, variant_params, params)
    table["duplicate"] = grid_duplicates(table)
    table["counted"] &= ~table["duplicate"]
    identified = table[table["counted"]]
    measured = measured_runs(identified, params)  # what means are made of (one distinct run ...)
    ok = measured[measured["status"] == ReportStatus.SUCCESS]

    per_seed = per_seed_means(ok)
    summary = with_seeded(cell_summary(identified, per_seed), measured)
    order = series_order(table)
    rank = {name: i for i, name in enumerate(order)}
    summary = _in_order(summary, rank)
    per_task = per_task_means(identified, ok)
    eligible = eligible_cells(identified, summary)
    full = {
        tuple(row)
        for row, keep in zip(
            summary[list(CELL_COLUMNS)].itertuples(index=False), eligible, strict=True
        )
        if keep
    }
    coverage = common_tasks(identified, full)
    compared, compared_per_seed = compared_tables(identified, coverage, measured)
    compared = _in_order(with_seeded(compared, measured), rank)
    compared_eligible = eligible_cells(identified, compared)
    length_of = dict(zip(coverage["domain"], coverage["length_metric"], strict=True))
    normalised, seed_norm = normalise(compared, compared_per_seed, compared_eligible, length_of)
    cross = cross_domain_means(normalised, seed_norm)
    series_frame = identified[list(SERIES_COLUMNS)].drop_duplicates()
    series_frame = series_frame.assign(_rank=series_frame["series"].map(rank)).sort_values("_rank")
    changes = changes_against_baselines(normalised, series_frame, values_of)
    table1 = table_one(measured, series_frame)
    table2 = table_two(
        measured,
        [(str(s), str(m)) for s, m in series_frame[["series", "method"]].values],
        titles=task_titles,
    )

    current = table[~table["superseded"] & ~table["duplicate"]]
    status = current["status"]
    counts = {
        "runs": len(current),
        **{word: int((status == word).sum()) for word in REPORT_STATUSES},
        "unidentified": int((~current["placed"]).sum()),
        "missing_metrics": int(summary["n_missing_metrics"].sum()),
        "superseded": int(table["superseded"].sum()),
        "grid_duplicates": int(table["duplicate"].sum()),
    }
    notes = report_notes(table, summary, per_seed, eligible, cross, variant_params, between)
    notes += coverage_notes(coverage)
    return Report(
        runs=table,
        per_seed=per_seed,
        per_task=per_task,
        summary=summary,
        compared=compared,
        coverage=coverage,
        normalised=normalised,
        cross_domain=cross,
        changes=changes,
        table1=table1,
        counts=counts,
        series=order,
        variant_params=tuple(variant_params),
        notes=tuple(notes),
        table2=table2,
        params=params,
    )
