"""bench/bench_methods.py: its tables, the N = 1 rows, and which rows a run reuses.

Rows are made by hand with lengths whose means were worked out here; the run tests use a
real task of ``data/`` but give every row as known, with lengths no planner would produce
(999), so a row that was planned again instead of reused shows.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from bench import bench_methods as bm
from tests.conftest import DATA, REPO
from twostep.cli.data import compare_files
from twostep.generators import scale_files

LARGE = [("blocksworld", 30, 3), ("grippers", 40, 3), ("tyreworld", 40, 1)]


def row(domain: str, task: int, method: str, agents: int, length: int | None, sa: int,
        time_s: float = 1.0, valid: bool = True, **extra: Any) -> dict[str, Any]:  # fmt: skip
    return {"domain": domain, "task": task, "method": method, "agents": agents,
            "exec_length": length, "sa_length": sa, "planning_time_s": time_s, "valid": valid,
            "status": "solved" if valid else "timeout", **extra}  # fmt: skip


# Domain A: two tasks (SA 10 and 20); domain B: one task (SA 10).
ROWS = [
    row("A", 1, "sa", 1, 10, 10, time_s=1.0),
    row("A", 2, "sa", 1, 20, 20, time_s=3.0),
    row("B", 1, "sa", 1, 10, 10, time_s=2.0),
    row("A", 1, "ma", 2, 5, 10, time_s=2.0),  # 0.5
    row("A", 2, "ma", 2, 20, 20, time_s=6.0),  # 1.0
    row("B", 1, "ma", 2, 8, 10, time_s=4.0),  # 0.8
    row("A", 1, "goal-split", 2, 10, 10, time_s=1.0),  # 1.0
    row("A", 2, "goal-split", 2, 10, 20, time_s=1.0),  # 0.5
    row("B", 1, "goal-split", 2, 9, 10, time_s=2.0),  # 0.9
    row("B", 1, "plan-split", 2, 12, 10),  # 1.2: longer than SA
    row("A", 1, "plan-split", 2, None, 10, valid=False),
    row("A", 2, "plan-split", 2, 15, 20),  # 0.75
]


def test_macro_is_the_mean_over_domains_of_the_per_task_mean() -> None:
    table = bm.summarise(ROWS, ["ma", "goal-split", "plan-split"], [1, 2])
    # MA: A = (0.5 + 1.0) / 2 = 0.75, B = 0.8; macro (0.75 + 0.8) / 2 = 0.775, not the
    # pooled mean over the three tasks (2.3 / 3 = 0.767)
    assert table[("A", 2, "ma")].ratio == pytest.approx(0.75)
    assert bm.macro_ratio(table, "ma", 2) == pytest.approx(0.775)
    assert table[("A", 2, "ma")].length == pytest.approx(12.5)
    assert table[("A", 2, "ma")].time_s == pytest.approx(4.0)
    # an invalid row counts as invalid, never as a length or a ratio
    ps = table[("A", 2, "plan-split")]
    assert (ps.tasks, ps.failed, ps.ratio, ps.length) == (2, 1, pytest.approx(0.75), 15)
    assert table[("B", 2, "plan-split")].longer_than_sa == 1
    assert bm.macro_ratio(table, "plan-split", 2) == pytest.approx((0.75 + 1.2) / 2)


def test_domains_no_longer_than_ma() -> None:
    table = bm.summarise(ROWS, ["ma", "goal-split", "plan-split"], [2])
    # goal-split: A 0.75 = MA 0.75 (a tie counts), B 0.9 > 0.8
    assert bm.no_longer_than_ma(table, "goal-split", 2) == (["A"], 2)
    # plan-split: A 0.75 <= 0.75, B 1.2 > 0.8
    assert bm.no_longer_than_ma(table, "plan-split", 2) == (["A"], 2)
    assert bm.no_longer_than_ma(table, "ma", 2) == (["A", "B"], 2)
    # where MA solves nothing, a method that solves is no longer than it
    failed = [r for r in ROWS if not (r["domain"] == "B" and r["method"] == "ma")]
    failed.append(row("B", 1, "ma", 2, None, 10, valid=False, time_s=90.0))
    table = bm.summarise(failed, ["ma", "goal-split"], [2])
    assert bm.no_longer_than_ma(table, "goal-split", 2) == (["A", "B"], 2)
    assert math.isnan(bm.macro_ratio(table, "ma", 2))
    assert table[("B", 2, "ma")].time_s == 90.0  # a timeout's time counts


def test_single_agent_rows_are_the_sa_plan_for_every_method() -> None:
    table = bm.summarise(ROWS, ["ma", "goal-split"], [1, 2])
    for method in ("sa", "ma", "goal-split"):
        one = table[("A", 1, method)]
        assert (one.length, one.ratio, one.time_s, one.tasks) == (15, 1.0, 2.0, 2)
    assert bm.macro_ratio(table, "goal-split", 1) == 1.0
    text = bm.report(ROWS, ["ma", "goal-split"], [1, 2], targets={2: 0.7})
    lines = {tuple(c.strip() for c in line.strip("|").split("|")) for line in text.splitlines()}
    # domain, N, tasks, SA len, lengths, ratios, SA time, times, goal-split/MA time, longer,
    # inexact, failed
    assert ("A", "1", "2", "15.0", "15.0", "15.0", "1.000", "1.000", "2.00", "2.00", "2.00",
            "1.000", "0", "0", "0") in lines  # fmt: skip
    assert ("A", "2", "2", "15.0", "12.5", "10.0", "0.750", "0.750", "2.00", "4.00", "1.00",
            "0.250", "0", "0", "0") in lines  # fmt: skip
    # macro: N, target, ma, goal-split, goal-split domains <= MA
    assert ("2", "0.70", "0.775", "0.825", "1/2") in lines
    assert ("1", "", "1.000", "1.000", "2/2") in lines


def test_a_task_without_its_sa_row_is_left_out() -> None:
    # every cell covers the same tasks: a TwoStep row whose SA row is missing does not count
    rows = [*ROWS, row("B", 2, "ma", 2, 1, 10)]
    table = bm.summarise(rows, ["ma"], [2])
    assert table[("B", 2, "ma")].tasks == 1


def test_reuse_keys_on_root_domain_task_agents_method_and_settings() -> None:
    rows = [
        row("A", 1, "ma", 2, 5, 10),  # legacy: data root data, lama-first, 60 s
        row("A", 1, "ma", 2, 6, 10, data="data/large"),
        row("A", 1, "ma", 3, 7, 10),
        row("A", 1, "ma", 4, 8, 10, time_limit_s=30.0),
        row("A", 1, "ma", 4, 9, 10, alias="lama"),
        row("A", 1, "goal-split", 2, 9, 10, fallback_if_longer=False),
        row("A", 1, "plan-split", 2, 9, 10),
    ]
    known = bm.reusable_rows(rows, ("sa", "ma", "goal-split"), "lama-first", 60.0, True)
    assert {k: r["exec_length"] for k, r in known.items()} == {
        ("data", "A", 1, 2, "ma"): 5,
        ("data/large", "A", 1, 2, "ma"): 6,
        ("data", "A", 1, 3, "ma"): 7,
    }
    # fallback_if_longer changes TwoStep rows, never SA or MA ones
    without = bm.reusable_rows(rows, ("ma", "goal-split"), "lama-first", 60.0, False)
    assert ("data", "A", 1, 2, "goal-split") in without
    assert ("data", "A", 1, 2, "ma") in without


def test_data_label_is_relative_to_the_repository() -> None:
    assert bm.data_label(DATA) == "data"
    assert bm.data_label(REPO / "data" / "large") == "data/large"
    assert bm.data_label(Path("/somewhere/else")) == "/somewhere/else"


def _job(known: tuple[dict[str, Any], ...], methods: tuple[str, ...]) -> bm.Job:
    return bm.Job(str(DATA), "data", "blocksworld", 1, (1, 2), methods, "lama-first", 60.0,
                  True, known)  # fmt: skip


def test_known_rows_are_not_planned_again() -> None:
    common = {"data": "data", "alias": "lama-first", "time_limit_s": 60.0}
    sa = row("blocksworld", 1, "sa", 1, 999, 999, plan=["(pick-up b1)"], **common)
    ma = row("blocksworld", 1, "ma", 2, 999, 999, **common)
    rows = bm.run_job(_job((sa, ma), ("ma",)))
    assert rows == [sa, ma]  # N = 1 is never run, and nothing is re-planned


def test_twostep_reads_the_plan_of_a_reused_sa_row() -> None:
    sa = row("blocksworld", 1, "sa", 1, 999, 999, plan=["(pick-up b1)"])
    plan = bm._sa_plan(sa)
    assert plan is not None and plan.plan == ("(pick-up b1)",) and plan.planner_time_s == 1.0
    # an SA row without its plan (older runs) or unsolved gives none: SA is planned again
    assert bm._sa_plan(row("blocksworld", 1, "sa", 1, 9, 9)) is None
    assert bm._sa_plan(row("blocksworld", 1, "sa", 1, None, 9, valid=False, plan=None)) is None


def test_resume_keeps_the_rows_of_tasks_outside_the_run(tmp_path: Path) -> None:
    common = {"data": "data", "alias": "lama-first", "time_limit_s": 60.0}
    out = tmp_path / "rows.json"
    done = [
        row("blocksworld", 1, "sa", 1, 999, 999, plan=["(pick-up b1)"], **common),
        row("blocksworld", 1, "ma", 2, 999, 999, **common),
        row("blocksworld", 2, "sa", 1, 998, 998, **common),  # not in this run: kept
    ]
    out.write_text(json.dumps(done))
    args = ["--domains", "blocksworld", "--tasks", "1", "--agents", "2", "--methods", "ma",
            "--workers", "1", "--out", str(out), "--resume"]  # fmt: skip
    result = subprocess.run(
        [sys.executable, str(REPO / "bench" / "bench_methods.py"), *args],
        capture_output=True, text=True, cwd=REPO, timeout=120, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "1 rows planned" not in result.stderr and "0 rows planned, 2 reused" in result.stderr
    rows = json.loads(out.read_text())
    assert sorted(rows, key=str) == sorted(done, key=str)


def test_overview_has_a_row_per_method_and_n_with_the_domains_across() -> None:
    text = bm.report(ROWS, ["ma", "goal-split"], [1, 2])
    lines = {tuple(c.strip() for c in line.strip("|").split("|")) for line in text.splitlines()}
    # method, N, A, B, macro, macro planning time, its ratio to MA's
    # goal-split times: A (1 + 1) / 2 = 1, B 2 -> 1.5; MA: A (2 + 6) / 2 = 4, B 4 -> 4
    assert ("goal-split", "2", "0.750", "0.900", "0.825", "1.50", "0.375") in lines
    assert ("ma", "2", "0.750", "0.800", "0.775", "4.00", "") in lines
    # SA: A (1 + 3) / 2 = 2, B 2
    assert ("sa", "1", "1.000", "1.000", "1.000", "2.00", "") in lines


@pytest.mark.parametrize(("domain", "size", "count"), LARGE)
def test_large_tasks_are_what_the_documented_command_writes(
    domain: str, size: int, count: int
) -> None:
    # data/large/README.md: twostep-data scale --domain D --size S --count C (seed 0)
    folder = DATA / "large" / domain
    assert compare_files(folder, scale_files(domain, size, count)) == []
    assert bm.list_tasks(domain, DATA / "large") == list(range(1, count + 1))
