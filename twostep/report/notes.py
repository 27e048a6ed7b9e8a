"""The report's notes: what a reader must know to read the numbers right."""

from __future__ import annotations

import pandas as pd

from twostep.report.aggregation import span
from twostep.report.model import CELL_COLUMNS, REPORT_METRICS
from twostep.report.runs import PARAM_PREFIX
from twostep.util.outcome import ReportStatus


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
    running = int((identified["status"] == ReportStatus.RUNNING).sum())
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
    duplicates = int(runs["duplicate"].sum()) if "duplicate" in runs else 0
    sa_moved = identified[(identified["method"] == "sa") & (identified["agents_param"] > 1)]
    if len(sa_moved) or duplicates:
        notes.append(
            "SA plans one agent whatever N says: its runs count as N = 1"
            + (
                f", and the {duplicates} SA run(s) a grid's N repeated (same task and seed) "
                "are counted once (runs.csv, column 'duplicate')."
                if duplicates
                else "."
            )
        )
    fixed = summary[~summary["seeded"]] if "seeded" in summary else summary.iloc[0:0]
    seeds = identified.groupby(list(CELL_COLUMNS), dropna=False)["seed"].nunique()
    repeated = [
        str(series)
        for series in dict.fromkeys(fixed["series"])
        if any(
            seeds.get(tuple(row[c] for c in CELL_COLUMNS), 0) > 1
            for row in fixed[fixed["series"] == series].to_dict("records")
        )
    ]
    if repeated:
        notes.append(
            f"{', '.join(repeated)}: deterministic, so every seed repeats one distinct run "
            "(the same plans; a later seed's planner times are the first seed's, from the "
            "planner cache). Their means are that run's, n = 1, with no ±; their runs are "
            "still counted per seed."
        )
    ok = identified[identified["status"] == ReportStatus.SUCCESS]
    repeats = ok.groupby([*CELL_COLUMNS, "task", "seed"], dropna=False).size()
    repeats = repeats[repeats > 1]
    if len(repeats):
        notes.append(
            f"{len(repeats)} (cell, task, seed) combination(s) have more than one successful "
            "run; their values are averaged before averaging over tasks."
        )
    has_mean = summary[f"{REPORT_METRICS[0]}_mean"].notna()
    seeded = summary["seeded"] if "seeded" in summary else pd.Series(True, index=summary.index)
    single = summary[has_mean & seeded & (summary[f"{REPORT_METRICS[0]}_n_seeds"] == 1)]
    if len(single):
        notes.append(
            f"{len(single)} of {int((has_mean & seeded).sum())} cells whose runs differ by "
            "seed have results from 1 seed only: no std (n = 1)."
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
