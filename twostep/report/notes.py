"""The report's notes: what a reader must know to read the numbers right."""

from __future__ import annotations

import pandas as pd

from twostep.report.aggregation import span
from twostep.report.model import CELL_COLUMNS, REPORT_METRICS
from twostep.report.runs import PARAM_PREFIX


def report_notes(
    runs: pd.DataFrame,
    summary: pd.DataFrame,
    per_seed: pd.DataFrame,
    eligible: pd.Series,
    cross: pd.DataFrame,
    variant_params: list[str],
    between: list[str],
) -> list[str]:
    notes: list[str] = []
    identified = runs[runs["counted"]]
    if variant_params:
        described = []
        for param in variant_params:
            values = sorted(set(identified[PARAM_PREFIX + param]))
            described.append(f"{param} ({', '.join(values)})")
        notes.append(
            "Runs differ in config beyond domain/task/method/N/seed/decomposer; series are "
            "split by: " + "; ".join(described) + "."
        )
    if between:
        notes.append(
            "These params differ between methods or decomposers (not used for grouping): "
            + ", ".join(between)
            + "."
        )
    superseded = int(runs["superseded"].sum())
    if superseded:
        notes.append(
            f"{superseded} older run(s) of jobs that were run again (same twostep.job_key) "
            "are superseded by the latest run and left out (runs.csv, column 'superseded')."
        )
    unidentified = int((~runs["placed"] & ~runs["superseded"]).sum())
    if unidentified:
        notes.append(
            f"{unidentified} run(s) lack domain, task, method, N or seed and could not be "
            "placed in any table; they are listed under the failed runs."
        )
    running = int((identified["status"] == "running").sum())
    if running:
        notes.append(
            f"{running} run(s) had not finished when the report was made (still running, "
            "or interrupted before logging a status): counted, not averaged."
        )
    missing = int(summary["n_missing_metrics"].sum())
    if missing:
        notes.append(
            f"{missing} successful run(s) lack exec_length or planning_time_s; "
            "they are counted but left out of the means of the missing metric."
        )
    sa_moved = identified[(identified["method"] == "sa") & (identified["agents_param"] > 1)]
    if len(sa_moved):
        notes.append(
            f"{len(sa_moved)} SA run(s) were launched with N > 1; SA ignores N, so they "
            "count as N = 1 (repeated runs of one task and seed are averaged)."
        )
    ok = identified[identified["status"] == "success"]
    repeats = ok.groupby([*CELL_COLUMNS, "task", "seed"], dropna=False).size()
    repeats = repeats[repeats > 1]
    if len(repeats):
        notes.append(
            f"{len(repeats)} (cell, task, seed) combination(s) have more than one successful "
            "run; their values are averaged before averaging over tasks."
        )
    has_mean = summary[f"{REPORT_METRICS[0]}_mean"].notna()
    single = summary[has_mean & (summary[f"{REPORT_METRICS[0]}_n_seeds"] == 1)]
    if len(single):
        notes.append(
            f"{len(single)} of {int(has_mean.sum())} cells have results from 1 seed only: "
            "no std, shown as 'mean (1 seed)'."
        )
    uneven = summary[summary["tasks_per_seed"].str.contains("-", regex=False)]
    if len(uneven):
        notes.append(
            f"{len(uneven)} cell(s) average a different number of tasks per seed "
            "(failed runs leave their task out): see the 'tasks/seed' column."
        )
    excluded = summary[~eligible & has_mean]
    if len(excluded):
        parts = [
            f"{row.domain} {row.series} N={row.agents} ({row.n_tasks} tasks)"
            for row in excluded.itertuples(index=False)
        ]
        notes.append(
            "Left out of the min-max normalised averages and the changes because they cover "
            "fewer tasks than the rest of their domain: " + "; ".join(parts) + "."
        )
    if len(cross) and cross["n_domains"].nunique() > 1:
        notes.append(
            "Normalised cross-domain points average different numbers of domains "
            f"({span(cross['n_domains'])}); changes use only the domains both sides have."
        )
    return notes


def coverage_notes(coverage: pd.DataFrame) -> list[str]:
    """What the compared means leave out, per domain (:mod:`twostep.report.compared`)."""
    notes: list[str] = []
    for row in coverage.itertuples(index=False):
        if row.left_out_tasks or row.lost_cells:
            plural = "s" if "," in str(row.left_out_tasks) else ""
            left_out = (
                f" (left out: task{plural} {row.left_out_tasks})" if row.left_out_tasks else ""
            )
            notes.append(
                f"{row.domain}: figures, normalised averages and changes compare the "
                f"{row.n_compared} of {row.n_tasks} tasks every series solved{left_out}; "
                f"{row.lost_cells}."
            )
    measured = coverage[coverage["length_metric"] != "exec_length"]
    if len(measured):
        notes.append(
            "Execution length in " + ", ".join(measured["domain"]) + " is the embodied length "
            "(environment steps in the kitchen) in the figures, normalised averages and changes."
        )
    return notes
