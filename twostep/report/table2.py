"""The paper's Table II: embodied execution length and planning time on the kitchen tasks.

One row per series (SA, MA, TwoStep with its decomposer), one column per task and a macro
column, headed by each task's short description when the data has one
(:func:`read_task_titles`). Execution length is the embodied length (``embodied_length``: environment steps on
the floor plan) when the runs have one, else the symbolic ``exec_length`` (said in the
table's ``length`` column). Cells: mean ± sample std over seeds (ddof = 1, as everywhere
in the reports); the macro column is, as in the paper, the mean of the task means ± the
mean of the task stds (the paper's MA macro std 105.8 is the mean of its four stds).

Planning time as in the paper: a task cell whose runs all hit the planner's time limit
reads ``timeout``; the macro column counts those cells. A run hit the limit when one of its
planner calls stopped for lack of time by the planner's own limit and exit code, whether
or not the anytime planner had found a plan by then (the paper's SA has a length and a
timeout). A call the wall-clock guard stopped first (a machine too loaded for the limit)
is no timeout: its run's planning time is left out of the cell and counted beside it
(``n guard stops``). Both counts come from :mod:`twostep.planner.limits`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from twostep.report.aggregation import sample_std
from twostep.report.seeds import distinct_label
from twostep.tasks.benchmark import TITLES_FILE, BenchmarkError, parse_task_titles
from twostep.util.files import FileFormatError, NotTextError, read_yaml_file
from twostep.util.outcome import ReportStatus

TABLE2_DOMAIN = "alfworld"
TABLE2_TASKS: tuple[int, ...] = (1, 2, 3, 4)
TABLE2_AGENTS = 2
PAPER_TIME_LIMIT_S = 3600.0

#: The paper's Table II: per series, per task then macro, (length mean, std or None) and
#: planning time in seconds (None: timeout at 60 minutes).
PAPER_TABLE2: tuple[tuple[str, list[tuple[float, float | None]], list[float | None]], ...] = (
    ("paper: SA", [(172.0, None), (201.0, None), (99.0, None), (44.0, None), (129.0, None)],
     [None, None, 11.3, None]),
    ("paper: MA", [(189.2, 16.7), (260.0, 248.5), (196.7, 88.3), (166.5, 69.6), (203.1, 105.8)],
     [None, None, None, None]),
    ("paper: TwoStep", [(113.6, 6.6), (147.0, 62.7), (204.5, 17.8), (54.2, 14.0), (129.8, 25.3)],
     [22.0, 14.8, 18.4, None]),
)  # fmt: skip


def _cell(runs: pd.DataFrame, length: str) -> dict[str, Any]:
    ok = runs[(runs["status"] == ReportStatus.SUCCESS) & runs[length].notna()]
    per_seed = ok.groupby("seed")[length].mean()
    limited = runs["planner_timeouts"].fillna(0) > 0
    guarded = runs["planner_guard_stops"].fillna(0) > 0
    timed = runs[~limited & ~guarded & runs["planning_time_s"].notna()]
    times = timed.groupby("seed")["planning_time_s"].mean()
    return {
        "length_mean": float(per_seed.mean()) if len(per_seed) else math.nan,
        "length_std": sample_std(per_seed),
        "n_seeds": len(per_seed),
        "time_mean": float(times.mean()) if len(times) else math.nan,
        "time_std": sample_std(times),
        "n_runs": len(runs),
        "n_timeouts": int(limited.sum()),
        "n_guard_stops": int(guarded.sum()),
        "n_failed": int((runs["status"] != ReportStatus.SUCCESS).sum()),
        # planned but not executed to the goal on the floor plan (embodied length only)
        "n_not_executed": int(
            ((runs["status"] == ReportStatus.SUCCESS) & runs[length].isna()).sum()
        ),
    }


def table_two(
    identified: pd.DataFrame,
    series: Sequence[tuple[str, str]],
    domain: str = TABLE2_DOMAIN,
    titles: Mapping[int, str] | None = None,
) -> pd.DataFrame:
    """Table II of ``identified`` runs (the report's counted runs) for ``series``:
    (series label, method) pairs in display order. Empty without runs of ``domain``.
    ``titles`` (task number -> short description) fills the ``title`` column."""
    runs = identified[identified["domain"] == domain]
    columns = [
        "series", "source", "task", "title", "length", "seeded",
        *_cell(runs.head(0), "exec_length"),
    ]  # fmt: skip
    if runs.empty:
        return pd.DataFrame(columns=columns)
    for metric in ("planner_timeouts", "planner_guard_stops"):
        if metric not in runs:  # a run table made before the metric existed
            runs = runs.assign(**{metric: math.nan})
    embodied = "embodied_length" in runs and bool(runs["embodied_length"].notna().any())
    length = "embodied_length" if embodied else "exec_length"
    rows: list[dict[str, Any]] = []
    for label, method in series:
        agents = 1 if method == "sa" else TABLE2_AGENTS
        mine = runs[(runs["series"] == label) & (runs["agents"] == agents)]
        if mine.empty:
            continue
        seeded = bool(mine["seeded"].any()) if "seeded" in mine else True
        cells = []
        for task in TABLE2_TASKS:
            cell = _cell(mine[mine["task"] == task], length)
            cells.append(cell)
            rows.append(
                {"series": label, "source": "ours", "task": str(task), "length": length,
                 "seeded": seeded, **cell}
            )  # fmt: skip
        means = [c["length_mean"] for c in cells]
        spread = any(not math.isnan(c["length_std"]) for c in cells)  # else one run each
        stds = [0.0 if math.isnan(c["length_std"]) else c["length_std"] for c in cells]
        complete = not any(math.isnan(m) for m in means)
        timeouts = sum(1 for c in cells if c["n_runs"] and c["n_timeouts"] == c["n_runs"])
        times = [c["time_mean"] for c in cells if not math.isnan(c["time_mean"])]
        rows.append(
            {
                "series": label,
                "source": "ours",
                "task": "macro",
                "length": length,
                "seeded": seeded,
                "length_mean": sum(means) / len(means) if complete else math.nan,
                "length_std": sum(stds) / len(stds) if complete and spread else math.nan,
                "n_seeds": min(c["n_seeds"] for c in cells),
                "time_mean": sum(times) / len(times) if times else math.nan,
                "time_std": math.nan,
                "n_runs": sum(c["n_runs"] for c in cells),
                "n_timeouts": timeouts,  # macro: task cells that timed out, as the paper
                "n_guard_stops": sum(c["n_guard_stops"] for c in cells),
                "n_failed": sum(c["n_failed"] for c in cells),
                "n_not_executed": sum(c["n_not_executed"] for c in cells),
            }
        )
    for label, lengths, times_paper in PAPER_TABLE2:
        for column, (mean, std) in zip([*map(str, TABLE2_TASKS), "macro"], lengths, strict=True):
            time = times_paper[int(column) - 1] if column != "macro" else None
            timeouts = sum(1 for t in times_paper if t is None)
            rows.append(
                {
                    "series": label,
                    "source": "paper",
                    "task": column,
                    "length": "embodied_length",
                    "length_mean": mean,
                    "length_std": math.nan if std is None else std,
                    "n_seeds": math.nan,
                    "time_mean": math.nan if time is None else time,
                    "time_std": math.nan,
                    "n_runs": math.nan,
                    "n_timeouts": timeouts if column == "macro" else int(time is None),
                    "n_guard_stops": math.nan,
                    "n_failed": math.nan,
                    "n_not_executed": math.nan,
                }
            )
    frame = pd.DataFrame.from_records(rows, columns=columns)
    frame["title"] = [
        (titles or {}).get(int(task), "") if task != "macro" else "" for task in frame["task"]
    ]
    return frame


def read_task_titles(domain_dir: Path) -> dict[int, str]:
    """Task number -> short description from ``<domain_dir>/titles.yaml``
    (:func:`twostep.tasks.benchmark.parse_task_titles` reads its lines); empty when the file is
    absent or not such a mapping."""
    path = domain_dir / TITLES_FILE
    if not path.is_file():
        return {}
    try:
        return parse_task_titles(read_yaml_file(path) or {}, path)
    except (OSError, NotTextError, FileFormatError, BenchmarkError):
        return {}


def _number(value: float, digits: int = 1) -> str:
    return f"{value:.{digits}f}"


def length_cell(row: Mapping[str, Any]) -> str:
    mean, std = row["length_mean"], row["length_std"]
    if pd.isna(mean):
        text = "n/a"
    else:
        text = _number(mean) if pd.isna(std) else f"{_number(mean)} ± {_number(std)}"
    if row["source"] == "ours":
        failed, unexecuted = row.get("n_failed"), row.get("n_not_executed")
        notes = [f"{int(failed)} failed"] if not pd.isna(failed) and failed else []
        if not pd.isna(unexecuted) and unexecuted:
            notes.append(f"{int(unexecuted)} not executed")
        if notes:
            text += f" ({', '.join(notes)})"
    return text


def _count(row: Mapping[str, Any], column: str) -> int:
    value = row.get(column)
    return 0 if value is None or pd.isna(value) else int(value)


def time_cell(row: Mapping[str, Any]) -> str:
    timeouts, guarded = _count(row, "n_timeouts"), _count(row, "n_guard_stops")
    guard_note = f" ({guarded} guard stop{'s' if guarded != 1 else ''})" if guarded else ""
    if row["task"] == "macro":
        return f"{timeouts} timeout{'s' if timeouts != 1 else ''}{guard_note}"
    if row["source"] == "paper":
        return "timeout" if timeouts else _number(row["time_mean"])
    runs = int(row["n_runs"])
    if runs and timeouts == runs:
        return "timeout"
    mean, std = row["time_mean"], row["time_std"]
    text = "n/a" if pd.isna(mean) else _number(mean, 2)
    if not pd.isna(std):
        text += f" ± {_number(std, 2)}"
    if timeouts:
        text += f" ({timeouts}/{runs} timeout)"
    return text + guard_note


def n_of(row: Mapping[str, Any]) -> str:
    """``n = 3 seeds`` or ``1 distinct run``: what a series' length cells average."""
    n = row.get("n_seeds")
    if n is None or pd.isna(n) or not int(n):
        return "n = 0"
    label = distinct_label(n, row.get("seeded", True))
    return label if label.startswith("1 distinct") else f"n = {label}"


def table_two_rows(frame: pd.DataFrame) -> tuple[list[str], list[list[str]]]:
    """Headers and rows of the printed table: the task descriptions when known, then a
    length row and a time row per series."""
    tasks = [*map(str, TABLE2_TASKS), "macro"]
    headers = ["series", "", *(f"task {t}" if t != "macro" else "macro" for t in tasks)]
    rows: list[list[str]] = []
    if "title" in frame:
        titles = {
            str(t): str(title) for t, title in zip(frame["task"], frame["title"], strict=True)
        }
        if any(titles.get(t) for t in tasks):
            rows.append(["tasks", "", *(titles.get(t, "") for t in tasks)])
    for label in dict.fromkeys(frame["series"]):
        cells = {str(r["task"]): r for r in frame[frame["series"] == label].to_dict("records")}
        macro = cells.get("macro", {})
        n = "paper" if macro.get("source") == "paper" else n_of(macro)
        rows.append(
            [label, f"length ({n})", *(length_cell(cells[t]) if t in cells else "" for t in tasks)]
        )
        rows.append(
            ["", "planning (s)", *(time_cell(cells[t]) if t in cells else "" for t in tasks)]
        )
    return headers, rows
