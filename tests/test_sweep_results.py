"""flows/sweep_results.py: the results table at the end of a sweep and its results.csv."""

from __future__ import annotations

import csv
from pathlib import Path

from flows.sweep_results import format_results, result_rows, write_results_csv

SA = {"domain": "grippers", "method": "sa", "agents": 1}
TWOSTEP = {"domain": "grippers", "method": "twostep", "decomposer": "goal-split", "agents": 2}
RECORDS = [
    # Two SA jobs of a grid over N=2,3 ran one agent each: one row, N=1.
    {**SA, "success": True, "exec_length": 6, "planning_time_s": 0.10},
    {**SA, "success": True, "exec_length": 8, "planning_time_s": 0.30},
    {**TWOSTEP, "success": True, "exec_length": 3, "planning_time_s": 0.40},
    # A failed job counts as a job, not in the means.
    {**TWOSTEP, "success": False, "exec_length": None, "planning_time_s": 9.0},
    {"name": "bad input", "status": "failed"},  # said nothing about what it ran
]


def test_one_row_per_domain_method_and_n_with_means_of_the_successes() -> None:
    rows = result_rows(RECORDS)
    assert [(r.method, r.agents, r.jobs, r.successes) for r in rows] == [
        ("sa", 1, 2, 2),
        ("twostep (goal-split)", 2, 2, 1),
    ]
    assert rows[0].mean_exec_length == 7.0 and abs(rows[0].mean_planning_time_s - 0.2) < 1e-12
    assert rows[1].mean_exec_length == 3.0 and rows[1].mean_planning_time_s == 0.4


def test_table_and_csv(tmp_path: Path) -> None:
    rows = result_rows(RECORDS)
    lines = format_results(rows).splitlines()
    assert lines[0].split() == ["domain", "method", "N", "success", "exec", "length",
                                "planning", "time", "(s)"]  # fmt: skip
    assert lines[2].split() == ["grippers", "sa", "1", "2/2", "7.0", "0.20"]
    assert lines[3].split() == ["grippers", "twostep", "(goal-split)", "2", "1/2", "3.0", "0.40"]
    path = write_results_csv(rows, tmp_path / "results.csv")
    with open(path) as handle:
        read = list(csv.DictReader(handle))
    assert read[1]["successes"] == "1" and read[1]["jobs"] == "2"
    assert float(read[0]["mean_exec_length"]) == 7.0
    assert format_results([]) == ""
