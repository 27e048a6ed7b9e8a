"""Which tasks a domain's series are compared on, and the cell means over those tasks.

A mean over the tasks a series happened to solve is not comparable with a mean over all of
them: one MA timeout on a domain's longest task lowers MA's average length (38 -> 13
steps on termes at N = 4 in a real sweep) although MA did no better. The figures, the
normalised panel and the changes therefore compare every series of a domain **on the
tasks every series solved** ("common tasks"), and show what each series lost:

* A run *solved* its task when it succeeded with the domain's length and its planning time
  recorded. The length is the execution length; for kitchen runs it is the embodied length
  (environment steps, as the paper measures execution in its embodied domain).
* A domain's common tasks are the tasks that every run of every *full* cell (a series at
  one N that was run on all the domain's tasks) solved, in every seed. Cells that solved
  no task at all do not take part (they would leave nothing to compare): they are drawn as
  lost and named in the notes. Cells run on a subset of the tasks (expert subgoals on the
  annotated tasks) are averaged over their own tasks among the common ones.
* ``compared`` has one row per cell, like the summary: mean and sample std over seeds of
  each seed's average over the common tasks, the run counts, and ``n_lost`` (runs that did
  not solve their task: failed, timed out, unfinished, or without the domain's length).

The summary table keeps the means over every successful run, with its counts.
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from twostep.report.aggregation import cell_summary, per_seed_means
from twostep.report.model import CELL_COLUMNS, REPORT_METRICS
from twostep.util.outcome import ReportStatus

COVERAGE_COLUMNS: tuple[str, ...] = (
    "domain",
    "length_metric",
    "n_tasks",
    "n_compared",
    "compared_tasks",
    "left_out_tasks",
    "lost_cells",
)


def length_metric(runs: pd.DataFrame) -> str:
    """``embodied_length`` when a domain's runs were executed in the kitchen, else
    ``exec_length``."""
    if "embodied_length" in runs and bool(runs["embodied_length"].notna().any()):
        return "embodied_length"
    return REPORT_METRICS[0]


def solved_runs(runs: pd.DataFrame, metric: str) -> pd.Series:
    """Per run: succeeded with ``metric`` and the planning time recorded."""
    return (
        (runs["status"] == ReportStatus.SUCCESS)
        & runs[metric].notna()
        & runs["planning_time_s"].notna()
    )


def _task_list(tasks: set[int] | frozenset[int]) -> str:
    return ",".join(str(t) for t in sorted(tasks))


def _tasks_named(tasks: set[int] | frozenset[int]) -> str:
    return f"task{'s' if len(tasks) > 1 else ''} {_task_list(tasks)}"


def _cell_label(key: tuple[Any, ...]) -> str:
    row = dict(zip(CELL_COLUMNS, key, strict=True))
    return f"{row['series']} N={row['agents']}"


def common_tasks(identified: pd.DataFrame, full_cells: set[tuple[Any, ...]]) -> pd.DataFrame:
    """Per domain: its length metric and the tasks every full cell solved (see the module
    docstring); ``full_cells`` are the (domain, series, ..., N) keys run on all tasks."""
    rows: list[dict[str, Any]] = []
    for domain, runs in identified.groupby("domain"):
        metric = length_metric(runs)
        solved = runs.assign(_solved=solved_runs(runs, metric))
        per_task = solved.groupby([*CELL_COLUMNS, "task"], dropna=False)["_solved"].all()
        tasks = frozenset(int(t) for t in runs["task"].dropna())
        solved_by: dict[tuple[Any, ...], frozenset[int]] = {}
        for key, ok in per_task.items():
            cell, task = tuple(key[:-1]), int(key[-1])
            solved_by.setdefault(cell, frozenset())
            if ok:
                solved_by[cell] = solved_by[cell] | {task}
        taking_part = [c for c in solved_by if c in full_cells and solved_by[c]]
        common = set(tasks)
        for cell in taking_part:
            common &= solved_by[cell]
        lost = [
            f"{_cell_label(cell)} solved none"
            for cell in solved_by
            if cell in full_cells and not solved_by[cell]
        ]
        lost += [
            f"{_cell_label(cell)} did not solve {_tasks_named(tasks - solved_by[cell])}"
            for cell in taking_part
            if tasks - solved_by[cell]
        ]
        rows.append(
            {
                "domain": str(domain),
                "length_metric": metric,
                "n_tasks": len(tasks),
                "n_compared": len(common),
                "compared_tasks": _task_list(common),
                "left_out_tasks": _task_list(tasks - common),
                "lost_cells": "; ".join(lost),
            }
        )
    return pd.DataFrame.from_records(rows, columns=list(COVERAGE_COLUMNS))


def compared_tables(
    identified: pd.DataFrame, coverage: pd.DataFrame, measured: pd.DataFrame | None = None
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(per-cell summary over each domain's common tasks, its per-seed averages); counts
    from ``identified``, means from ``measured`` (:func:`twostep.report.seeds.measured_runs`;
    default: every identified run)."""
    measured = identified if measured is None else measured
    compared_tasks = {
        str(row.domain): {int(t) for t in str(row.compared_tasks).split(",") if t}
        for row in coverage.itertuples(index=False)
    }
    length_of = dict(zip(coverage["domain"], coverage["length_metric"], strict=True))
    in_common = [
        int(task) in compared_tasks.get(str(domain), set()) if not pd.isna(task) else False
        for domain, task in zip(measured["domain"], measured["task"], strict=True)
    ]
    ok = measured[
        (measured["status"] == ReportStatus.SUCCESS) & pd.Series(in_common, index=measured.index)
    ]
    per_seed = per_seed_means(ok)
    summary = cell_summary(identified, per_seed)
    solved = pd.Series(False, index=identified.index)
    for domain, metric in length_of.items():
        mask = identified["domain"] == domain
        solved[mask] = solved_runs(identified[mask], str(metric))
    lost = (
        identified.assign(_lost=(~solved).astype(int))
        .groupby(list(CELL_COLUMNS), dropna=False)["_lost"]
        .sum()
        .rename("n_lost")
        .reset_index()
    )
    summary = summary.merge(lost, on=list(CELL_COLUMNS), how="left")
    summary["n_lost"] = summary["n_lost"].fillna(0).astype(int)
    return summary, per_seed
