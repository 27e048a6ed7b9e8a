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

from evaluation import method_tables as tables
from evaluation import methods as runs
from tests.conftest import DATA, REPO
from tools import record
from twostep.cli.data import compare_files
from twostep.generators import scale_files
from twostep.tasks.benchmark import list_tasks

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
    table = tables.summarise(ROWS, ["ma", "goal-split", "plan-split"], [1, 2])
    # MA: A = (0.5 + 1.0) / 2 = 0.75, B = 0.8; macro (0.75 + 0.8) / 2 = 0.775, not the
    # pooled mean over the three tasks (2.3 / 3 = 0.767)
    assert table[("A", 2, "ma")].ratio == pytest.approx(0.75)
    assert tables.macro_ratio(table, "ma", 2) == pytest.approx(0.775)
    assert table[("A", 2, "ma")].length == pytest.approx(12.5)
    assert table[("A", 2, "ma")].time_s == pytest.approx(4.0)
    # an invalid row counts as invalid, never as a length or a ratio
    ps = table[("A", 2, "plan-split")]
    assert (ps.tasks, ps.failed, ps.ratio, ps.length) == (2, 1, pytest.approx(0.75), 15)
    assert table[("B", 2, "plan-split")].longer_than_sa == 1
    assert tables.macro_ratio(table, "plan-split", 2) == pytest.approx((0.75 + 1.2) / 2)


def test_domains_no_longer_than_ma() -> None:
    table = tables.summarise(ROWS, ["ma", "goal-split", "plan-split"], [2])
    # goal-split: A 0.75 = MA 0.75 (a tie counts), B 0.9 > 0.8
    assert tables.no_longer_than_ma(table, "goal-split", 2) == (["A"], 2)
    # plan-split: A 0.75 <= 0.75, B 1.2 > 0.8
    assert tables.no_longer_than_ma(table, "plan-split", 2) == (["A"], 2)
    assert tables.no_longer_than_ma(table, "ma", 2) == (["A", "B"], 2)
    # where MA solves nothing, a method that solves is no longer than it
    failed = [r for r in ROWS if not (r["domain"] == "B" and r["method"] == "ma")]
    failed.append(row("B", 1, "ma", 2, None, 10, valid=False, time_s=90.0))
    table = tables.summarise(failed, ["ma", "goal-split"], [2])
    assert tables.no_longer_than_ma(table, "goal-split", 2) == (["A", "B"], 2)
    assert math.isnan(tables.macro_ratio(table, "ma", 2))
    assert table[("B", 2, "ma")].time_s == 90.0  # a timeout's time counts


def test_single_agent_rows_are_the_sa_plan_for_every_method() -> None:
    table = tables.summarise(ROWS, ["ma", "goal-split"], [1, 2])
    for method in ("sa", "ma", "goal-split"):
        one = table[("A", 1, method)]
        assert (one.length, one.ratio, one.time_s, one.tasks) == (15, 1.0, 2.0, 2)
    assert tables.macro_ratio(table, "goal-split", 1) == 1.0
    text = tables.report(ROWS, ["ma", "goal-split"], [1, 2], targets={2: 0.7})
    lines = {tuple(c.strip() for c in line.strip("|").split("|")) for line in text.splitlines()}
    # domain, N, tasks, SA len, SA (cleaned) len (no plan-deal rows: none), lengths, ratios,
    # SA time, times, goal-split/MA time, longer, inexact, failed
    assert ("A", "1", "2", "15.0", "", "15.0", "15.0", "1.000", "1.000", "2.00", "2.00", "2.00",
            "1.000", "0", "0", "0") in lines  # fmt: skip
    assert ("A", "2", "2", "15.0", "", "12.5", "10.0", "0.750", "0.750", "2.00", "4.00", "1.00",
            "0.250", "0", "0", "0") in lines  # fmt: skip
    # macro: N, target, ma, goal-split, goal-split / cleaned (none), goal-split domains <= MA
    assert ("2", "0.70", "0.775", "0.825", "", "1/2") in lines
    assert ("1", "", "1.000", "1.000", "", "2/2") in lines


def test_a_task_without_its_sa_row_is_left_out() -> None:
    # every cell covers the same tasks: a TwoStep row whose SA row is missing does not count
    rows = [*ROWS, row("B", 2, "ma", 2, 1, 10)]
    table = tables.summarise(rows, ["ma"], [2])
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
    known = runs.reusable_rows(rows, ("sa", "ma", "goal-split"), "lama-first", 60.0, True)
    assert {k: r["exec_length"] for k, r in known.items()} == {
        ("data", "A", 1, 2, "ma"): 5,
        ("data/large", "A", 1, 2, "ma"): 6,
        ("data", "A", 1, 3, "ma"): 7,
    }
    # fallback_if_longer changes TwoStep rows, never SA or MA ones
    without = runs.reusable_rows(rows, ("ma", "goal-split"), "lama-first", 60.0, False)
    assert ("data", "A", 1, 2, "goal-split") in without
    assert ("data", "A", 1, 2, "ma") in without


def test_data_label_is_relative_to_the_repository() -> None:
    assert runs.data_label(DATA) == "data"
    assert runs.data_label(REPO / "data" / "large") == "data/large"
    assert runs.data_label(Path("/somewhere/else")) == "/somewhere/else"


def _job(known: tuple[dict[str, Any], ...], methods: tuple[str, ...]) -> runs.Job:
    return runs.Job(str(DATA), "data", "blocksworld", 1, (1, 2), methods, "lama-first", 60.0,
                  True, known)  # fmt: skip


def test_known_rows_are_not_planned_again() -> None:
    common = {"data": "data", "alias": "lama-first", "time_limit_s": 60.0}
    sa = row("blocksworld", 1, "sa", 1, 999, 999, plan=["(pick-up b1)"], **common)
    ma = row("blocksworld", 1, "ma", 2, 999, 999, **common)
    rows = runs.run_job(_job((sa, ma), ("ma",)))
    assert rows == [sa, ma]  # N = 1 is never run, and nothing is re-planned


def test_twostep_reads_the_plan_of_a_reused_sa_row() -> None:
    sa = row("blocksworld", 1, "sa", 1, 999, 999, plan=["(pick-up b1)"])
    plan = runs.stored_sa_plan(sa)
    assert plan is not None and plan.plan == ("(pick-up b1)",) and plan.planner_time_s == 1.0
    # an SA row without its plan (older runs) or unsolved gives none: SA is planned again
    assert runs.stored_sa_plan(row("blocksworld", 1, "sa", 1, 9, 9)) is None
    assert (
        runs.stored_sa_plan(row("blocksworld", 1, "sa", 1, None, 9, valid=False, plan=None)) is None
    )


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
    rows = record.rows_of(out)  # the bench record's rows
    assert sorted(rows, key=str) == sorted(done, key=str)


def test_overview_has_a_row_per_method_and_n_with_the_domains_across() -> None:
    text = tables.report(ROWS, ["ma", "goal-split"], [1, 2])
    lines = {tuple(c.strip() for c in line.strip("|").split("|")) for line in text.splitlines()}
    # method, N, A, B, macro, macro / cleaned SA (no plan-deal rows: none), macro planning
    # time, its ratio to MA's
    # goal-split times: A (1 + 1) / 2 = 1, B 2 -> 1.5; MA: A (2 + 6) / 2 = 4, B 4 -> 4
    assert ("goal-split", "2", "0.750", "0.900", "0.825", "", "1.50", "0.375") in lines
    assert ("ma", "2", "0.750", "0.800", "0.775", "", "4.00", "") in lines
    # SA: A (1 + 3) / 2 = 2, B 2
    assert ("sa", "1", "1.000", "1.000", "1.000", "", "2.00", "") in lines


@pytest.mark.parametrize(("domain", "size", "count"), LARGE)
def test_large_tasks_are_what_the_documented_command_writes(
    domain: str, size: int, count: int
) -> None:
    # data/large/README.md: twostep-data scale --domain D --size S --count C (seed 0)
    folder = DATA / "large" / domain
    assert compare_files(folder, scale_files(domain, size, count)) == []
    assert list_tasks(domain, DATA / "large") == list(range(1, count + 1))


# plan-deal rows of domain A (SA 10 and 20): the cleaned SA plans are 8 and 20 long.
DEAL_ROWS = [
    row("A", 1, "sa", 1, 10, 10, time_s=0.5, total_actions=10),
    row("A", 2, "sa", 1, 20, 20, time_s=1.5, total_actions=20),
    *(row("A", 1, "plan-deal", n, length, 10, cleaned_sa_length=8, total_actions=total,
          agents_used=used, fallback=None, deal_seconds={"walks": 0.25, "scoring": 0.05 * n})
      for n, length, total, used in ((2, 5, 9, 2), (3, 4, 10, 3), (4, 5, 10, 3))),
    *(row("A", 2, "plan-deal", n, length, 20, cleaned_sa_length=20, total_actions=20,
          agents_used=used, deal_seconds={"walks": 2.0 * n, "scoring": 1.0}, fallback=why,
          fallback_reason=why)
      for n, length, used, why in ((2, 20, 1, "no deal shorter than the cleaned SA plan"),
                                   (3, 10, 2, None), (4, 10, 2, None))),
]  # fmt: skip


def test_the_cleaned_sa_plan_and_the_lower_bound() -> None:
    table = tables.summarise(DEAL_ROWS, ["plan-deal"], [1, 2, 3])
    # SA (cleaned): 8/10 and 20/20, mean 0.9
    cleaned = table[("A", 1, "sa-cleaned")]
    assert (cleaned.length, cleaned.ratio) == (14.0, pytest.approx(0.9))
    # N = 2: ⌈9 / 2⌉ = 5 and ⌈20 / 2⌉ = 10; exec / cleaned (5/8 + 20/20) / 2
    two = table[("A", 2, "plan-deal")]
    assert two.bound == 7.5 and two.ratio_cleaned == pytest.approx((5 / 8 + 1) / 2)
    assert tables.macro_ratio(table, "plan-deal", 2, cleaned=True) == pytest.approx(0.8125)
    text = tables.report(DEAL_ROWS, ["plan-deal"], [1, 2, 3], default="plan-deal")
    lines = {tuple(c.strip() for c in line.strip("|").split("|")) for line in text.splitlines()}
    assert ("sa (cleaned)", "1", "0.900", "0.900", "1.000", "1.00", "") in lines
    # plan-deal at N = 3: lengths 4 and 10 ([⌈10/3⌉ = 4, ⌈20/3⌉ = 7])
    assert any(line[:6] == ("A", "3", "2", "15.0", "14.0", "7.0 [5.5]") for line in lines)


# grippers p01 of data/ by hand: robot1 takes ball2 to room2 and ball1 back (6 actions, each
# needed); robot2's trip there and back first changes nothing, so the clean-up drops it.
HAND_PLAN = ["(move robot2 room2 room1)", "(move robot2 room1 room2)",
             "(pick robot1 ball2 room1 lgripper1)", "(move robot1 room1 room2)",
             "(drop robot1 ball2 room2 lgripper1)", "(pick robot1 ball1 room2 lgripper1)",
             "(move robot1 room2 room1)", "(drop robot1 ball1 room1 lgripper1)"]  # fmt: skip


def test_the_cleaned_sa_plan_without_plan_deal_rows_comes_from_the_sa_plan() -> None:
    # a portfolio run records no deal: its task's cleaned SA length is the stored SA plan,
    # cleaned now (6 of 8 actions), and a plan-deal row's recorded length is kept as it is
    sa = row("grippers", 1, "sa", 1, 8, 8, data="data", plan=HAND_PLAN)
    portfolio = row("grippers", 1, "portfolio", 2, 3, 8, data="data")
    rows = tables.with_cleaned([sa, portfolio])
    assert [r["cleaned"] for r in rows] == [6, 6]
    table = tables.summarise([sa, portfolio], ["portfolio"], [1, 2])
    assert table[("grippers", 1, "sa-cleaned")].length == 6
    assert table[("grippers", 2, "portfolio")].ratio_cleaned == pytest.approx(3 / 6)
    recorded = row("grippers", 1, "plan-deal", 2, 3, 8, data="data", cleaned_sa_length=7)
    assert {r["cleaned"] for r in tables.with_cleaned([sa, recorded])} == {7}
    # a stored plan that does not apply (grippers has no pick-up) gives no cleaned length
    assert tables.cleaned_length({**sa, "plan": ["(pick-up ball1)"]}) is None


def test_a_task_whose_goal_holds_at_the_start_counts_in_the_cleaned_length() -> None:
    # task 1's SA plan is empty (its cleaned plan too), task 2's 10 steps clean to 8: the
    # lengths average both tasks ((0 + 8) / 2, as SA's (0 + 10) / 2), ratios task 2 only
    rows = [row("A", 1, "sa", 1, 0, 0), row("A", 2, "sa", 1, 10, 10),
            row("A", 1, "plan-deal", 2, 0, 0, cleaned_sa_length=0),
            row("A", 2, "plan-deal", 2, 5, 10, cleaned_sa_length=8)]  # fmt: skip
    table = tables.summarise(rows, ["plan-deal"], [1, 2])
    cleaned, sa = table[("A", 1, "sa-cleaned")], table[("A", 1, "sa")]
    assert (cleaned.length, sa.length) == (4.0, 5.0)
    assert cleaned.ratio == pytest.approx(0.8)


def test_plan_deal_in_detail() -> None:
    lines = tables.deal_report(DEAL_ROWS, [2, 3, 4], "plan-deal")
    text = "\n".join(lines)
    # one fallback (task 2, N = 2: one agent), three runs with an idle agent
    assert "(fallback): 1 of 6; no deal shorter than the cleaned SA plan: 1" in text
    assert "fewer agents than N (an agent idle): 3" in text  # task 1 N=4, task 2 N=3 and N=4
    # task 1: 10 (SA), 5, 4, 5: N = 4 is longer than N = 3
    assert "1 violations in 6 pairs (N, N-1); A p01 N=4: 5 > 4" in text
    table = {tuple(c.strip() for c in line.strip("|").split("|")) for line in lines}
    # N = 3: dealing 0.25 + 0.15 = 0.40 s and 6 + 1 = 7 s; median 3.7 > SA's median 1.0
    assert ("A", "3", "1.000", "3.700", "no", "7.00", "no") in {row[:7] for row in table}


def test_tyreworld_one_jack_floor_line() -> None:
    # data/tyreworld/p03 has three hubs (the-hub1..3 in its goal): 6 * 3 + 6 = 24 steps.
    assert tables.tyreworld_floor("data", 3) == 24
    assert tables.tyreworld_floor("no/such/root", 3) is None
    rows = [
        {**row("tyreworld", 3, "sa", 1, 40, 40), "data": "data"},
        {**row("tyreworld", 3, "plan-deal", 2, 24, 40), "data": "data"},
        {**row("tyreworld", 3, "plan-deal", 3, 25, 40), "data": "data"},
    ]
    (line,) = tables.one_jack_floor(rows, rows[1:])
    assert "reached in 1 of 2 runs" in line and "floor / SA, mean over tasks: 0.600" in line


def test_the_plot_draws_the_macro_against_n_and_against_planning_time(tmp_path: Path) -> None:
    methods = ["ma", "goal-split", "plan-split"]
    table = tables.summarise(ROWS, methods, [1, 2])
    path = tmp_path / "methods.png"
    figure = tables.plot_methods(table, methods, [1, 2], {2: 0.55}, "goal-split", path)
    assert path.read_bytes().startswith(b"\x89PNG")
    by_n, by_time = figure.axes
    lines = {line.get_label(): line for line in by_n.get_lines()}
    # against N: (1, the SA plan) then N = 2; MA's macro (0.75 + 0.8) / 2, goal-split's
    # ((1.0 + 0.5) / 2 + 0.9) / 2 = 0.825, the default decomposer starred
    assert list(lines["ma"].get_xdata()) == [1, 2]
    assert list(lines["ma"].get_ydata()) == pytest.approx([1.0, 0.775])
    assert list(lines["goal-split*"].get_ydata()) == pytest.approx([1.0, 0.825])
    # against time, one point per method at N = 2: MA's macro planning time (A (2 + 6) / 2
    # = 4, B 4), goal-split's (A 1, B 2: 1.5), plan-split's (1: its failed run's time
    # counts; macro (0.75 + 1.2) / 2); SA's (A (1 + 3) / 2 = 2, B 2) is the vertical line
    timed = [line for line in by_time.get_lines() if len(line.get_xdata()) == 1]
    points = sorted((line.get_xdata()[0], line.get_ydata()[0]) for line in timed)
    flat = [x for point in points for x in point]
    assert flat == pytest.approx([1.0, 0.975, 1.5, 0.825, 4.0, 0.775])
    sa_line = [line for line in by_time.get_lines() if line.get_linestyle() == "--"]
    assert list(sa_line[0].get_xdata()) == pytest.approx([2.0, 2.0])
