"""Table I of a replay (twostep.report.replay): hand-made runs and bundle, hand-computed
cells (common tasks, mean of per-run means, spread only with several runs)."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from twostep.replay import Answer, Bundle, Entry, OfficialNumbers, Run
from twostep.report.replay import replay_tables, table_markdown


def entry(run: str, task: int, length: float | None, sa: float) -> Entry:
    official = OfficialNumbers(sa_cost=sa, exec_length=length)
    return Entry(run, "grippers", task, 2, 1, (Answer(1, "ball1 is in room1.", 1),), official)


def job(
    decomposer: str, task: int, seed: int, length: float, sa: float, status: str = "success"
) -> dict:
    return {
        "domain": "grippers", "task": task, "method": "twostep", "decomposer": decomposer,
        "agents": 2, "seed": seed, "status": status, "exec_length": length, "sa_length": sa,
        "counted": True,
    }  # fmt: skip


@pytest.fixture
def bundle() -> Bundle:
    runs = [Run("a", "gpt-4o", "a.txt", "a.txt", "0"), Run("b", "gpt-4o", "b.txt", "b.txt", "1")]
    # run a finished tasks 1-3, run b tasks 1 and 2 (its task 3 crashed: no length)
    entries = [
        entry("a", 1, 4.0, 6.0), entry("a", 2, 6.0, 8.0), entry("a", 3, 3.0, 4.0),
        entry("b", 1, 5.0, 6.0), entry("b", 2, 8.0, 8.0), entry("b", 3, None, 4.0),
    ]  # fmt: skip
    return Bundle(runs=runs, entries=entries)


def test_three_rows_on_the_tasks_all_cover(bundle: Bundle) -> None:
    runs = pd.DataFrame(
        [
            job("llm", 1, 0, 5.0, 7.0), job("llm", 2, 0, 7.0, 9.0), job("llm", 3, 0, 3.0, 5.0),
            job("llm", 1, 1, 4.0, 7.0), job("llm", 2, 1, 6.0, 9.0),
            job("plan-deal", 1, 0, 3.0, 7.0), job("plan-deal", 2, 0, 5.0, 9.0),
            job("plan-deal", 3, 0, 0.0, 5.0, status="failed"),
        ]
    )  # fmt: skip
    tables = replay_tables(runs, bundle, "openai/gpt-4o")
    rows = {r["source"]: r for r in tables.table.to_dict("records")}
    # common tasks: 1 and 2 (official run b has no task 3, plan-deal failed it)
    assert {s: (r["tasks"], r["own_tasks"], r["runs"]) for s, r in rows.items()} == {
        "official": (2, 3, 2),
        "twostep": (2, 3, 2),
        "plan-deal": (2, 2, 1),
    }
    # official: run a (4 + 6) / 2 = 5, run b (5 + 8) / 2 = 6.5: mean 5.75, std 1.0607
    assert rows["official"]["exec_length"] == pytest.approx(5.75)
    assert rows["official"]["std"] == pytest.approx(math.sqrt(2 * 0.75**2))
    assert rows["official"]["sa_length"] == pytest.approx(7.0)
    # twostep: seed 0 (5 + 7) / 2 = 6, seed 1 (4 + 6) / 2 = 5
    assert (rows["twostep"]["exec_length"], rows["twostep"]["sa_length"]) == (5.5, 8.0)
    # plan-deal: one run, no spread
    assert rows["plan-deal"]["exec_length"] == 4.0 and math.isnan(rows["plan-deal"]["std"])
    assert rows["plan-deal"]["length_over_sa"] == pytest.approx(0.5)
    macro = {r["source"]: r["length_over_sa"] for r in tables.macro.to_dict("records")}
    assert macro == pytest.approx({"official": 5.75 / 7, "twostep": 5.5 / 8, "plan-deal": 0.5})
    text = table_markdown(tables)
    assert (
        "| grippers | 2 | official TwoStep (its logs) | 2 | 3 | 2 | 5.8 ± 1.1 | 7.0 | 0.82 |"
        in text
    )


def test_cells_the_sweep_did_not_run_are_left_out(bundle: Bundle) -> None:
    tables = replay_tables(pd.DataFrame([job("llm", 1, 0, 5.0, 7.0)]).iloc[0:0], bundle, "gpt-4o")
    assert tables.empty
