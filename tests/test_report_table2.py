"""Table II (twostep/report/table2.py) from hand-made result.json files of a sweep directory.

Every expected number below is worked out by hand from the values written here.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from flows.report_sources import RUN_PARAMS, load_runs_from_sweep_dir
from twostep.planner.limits import guard_stops, planner_limit_hits
from twostep.report import build_report, format_console

FINISHED = {"status": "solved", "exit_code": 0, "message": "plan found"}
OUT_OF_TIME = {"status": "solved", "exit_code": 23, "message": "search out of time"}
GUARD = {"status": "solved", "exit_code": None, "guard_stopped": True, "message": "guard"}


def _result(
    method: str, task: int, seed: int, length: int | None, time_s: float, call: dict[str, Any]
) -> dict[str, Any]:
    return {
        "domain": "alfworld",
        "task": task,
        "method": method,
        "agents": 1 if method == "sa" else 2,
        "seed": seed,
        "success": True,
        "status": "solved",
        "exec_length": 9,
        "planning_time_s": time_s,
        "decomposer": "goal-split" if method == "twostep" else None,
        "planner_calls": [{"agent": "agent0", "role": "single", "planner_time_s": 1.0, **call}],
        "executor": "embodied",
        "embodied_status": "success" if length is not None else "deadlock",
        "embodied_length": length,
        "waits": 0,
        "backoffs": 0,
    }


def _write(root: Path, results: list[dict[str, Any]]) -> None:
    for i, result in enumerate(results):
        folder = root / f"{i}_job"
        folder.mkdir(parents=True)
        (folder / "result.json").write_text(json.dumps(result))


@pytest.fixture()
def table(tmp_path: Path) -> Any:
    sa = [
        # task 1: lengths 10, 12, 14 -> 12 +- 2; times 1, 2, 3 -> 2 +- 1
        *(_result("sa", 1, s, 10 + 2 * s, 1.0 + s, FINISHED) for s in range(3)),
        # task 2: every seed hit the time limit (with a plan): "timeout"
        *(_result("sa", 2, s, 20, 9.0, OUT_OF_TIME) for s in range(3)),
        # task 3: seed 2 not executed -> lengths 30, 34 -> 32 +- 2.828
        _result("sa", 3, 0, 30, 1.0, FINISHED),
        _result("sa", 3, 1, 34, 1.0, FINISHED),
        _result("sa", 3, 2, None, 1.0, FINISHED),
        # task 4: 40, 41, 42 -> 41 +- 1; seed 0 timed out, times 5 and 7 -> 6 +- 1.414
        _result("sa", 4, 0, 40, 9.0, OUT_OF_TIME),
        _result("sa", 4, 1, 41, 5.0, FINISHED),
        _result("sa", 4, 2, 42, 7.0, FINISHED),
    ]
    twostep = [_result("twostep", 1, s, 8 + 2 * s, 0.5, FINISHED) for s in range(2)]
    # task 2: the wall-clock guard stopped the planner (with a plan): a length, no time
    twostep.append(_result("twostep", 2, 0, 15, 40.0, GUARD))
    _write(tmp_path, [*sa, *twostep])
    report = build_report(load_runs_from_sweep_dir(tmp_path), params=RUN_PARAMS)
    return report


def _row(frame: Any, series: str, task: str) -> dict[str, Any]:
    rows = frame[(frame["series"] == series) & (frame["task"] == task)].to_dict("records")
    assert len(rows) == 1, (series, task)
    row: dict[str, Any] = rows[0]
    return row


def test_table2_means_stds_and_timeouts(table: Any) -> None:
    frame = table.table2
    ours = frame[frame["source"] == "ours"]
    assert set(ours["length"]) == {"embodied_length"}
    sa = {t: _row(frame, "SA", t) for t in ("1", "2", "3", "4", "macro")}
    assert (sa["1"]["length_mean"], sa["1"]["length_std"]) == (12.0, 2.0)
    assert (sa["1"]["time_mean"], sa["1"]["time_std"]) == (2.0, 1.0)
    assert sa["2"]["n_timeouts"] == sa["2"]["n_runs"] == 3
    assert sa["3"]["length_mean"] == 32.0
    assert sa["3"]["length_std"] == pytest.approx(math.sqrt(8))
    assert sa["3"]["n_not_executed"] == 1
    assert sa["4"]["n_timeouts"] == 1
    assert sa["4"]["time_mean"] == 6.0 and sa["4"]["time_std"] == pytest.approx(math.sqrt(2))
    # macro: mean of the task means, mean of the task stds (as the paper); timed-out cells
    assert sa["macro"]["length_mean"] == pytest.approx((12 + 20 + 32 + 41) / 4)
    assert sa["macro"]["length_std"] == pytest.approx((2 + 0 + math.sqrt(8) + 1) / 4)
    assert sa["macro"]["n_timeouts"] == 1  # task 2 only: task 4 timed out in 1 run of 3
    # TwoStep ran tasks 1 and 2 only: no macro length
    twostep = [r for r in ours["series"].unique() if str(r).startswith("TwoStep")]
    assert len(twostep) == 1
    t1 = _row(frame, twostep[0], "1")
    assert t1["length_mean"] == 9.0 and t1["length_std"] == pytest.approx(math.sqrt(2))
    assert math.isnan(_row(frame, twostep[0], "macro")["length_mean"])
    # the guard's stop is no timeout, and its time is no planning time
    t2 = _row(frame, twostep[0], "2")
    assert (t2["length_mean"], t2["n_timeouts"], t2["n_guard_stops"]) == (15.0, 0, 1)
    assert math.isnan(t2["time_mean"])
    # the paper's rows are beside ours
    assert _row(frame, "paper: TwoStep", "macro")["length_mean"] == 129.8
    assert _row(frame, "paper: SA", "macro")["n_timeouts"] == 3


def test_table2_printed(table: Any) -> None:
    text = format_console(table)
    sa_time = next(line for line in text.splitlines() if "planning" in line and "timeout" in line)
    cells = [c.strip() for c in sa_time.strip("|").split("|")]
    assert cells[2:] == [
        "2.00 ± 1.00",
        "timeout",
        "1.00 ± 0.00",
        "6.00 ± 1.41 (1/3 timeout)",
        "1 timeout",
    ]
    assert "12.0 ± 2.0" in text and "32.0 ± 2.8 (1 not executed)" in text
    lines = text.splitlines()
    twostep_row = next(i for i, line in enumerate(lines) if line.startswith("| TwoStep"))
    twostep_time = lines[twostep_row + 1]  # its planning-time row
    cells = [c.strip() for c in twostep_time.strip("|").split("|")]
    assert cells[2:4] == ["0.50 ± 0.00", "n/a (1 guard stop)"]
    assert cells[-1] == "0 timeouts (1 guard stop)"
    assert "paper: MA" in text and "260.0 ± 248.5" in text


def test_planner_limit_hits() -> None:
    assert planner_limit_hits({"planner_calls": [FINISHED, OUT_OF_TIME, OUT_OF_TIME]}) == 2
    assert planner_limit_hits({"planner_calls": [], "status": "timeout"}) == 1
    assert planner_limit_hits({"planner_calls": [FINISHED], "status": "solved"}) == 0
    # the wall-clock guard is reported apart: no timeout (issue 19), with or without the
    # flag (results written before it have no exit code and the guard's message)
    flagged = {**FINISHED, "exit_code": None, "guard_stopped": True, "status": "timeout"}
    before = {"status": "solved", "exit_code": None, "message": "wall-clock guard stopped it"}
    for killed in (flagged, before):
        result = {"planner_calls": [OUT_OF_TIME, killed], "status": killed["status"]}
        assert (planner_limit_hits(result), guard_stops(result)) == (1, 1)
        alone = {"planner_calls": [killed], "status": killed["status"]}
        assert (planner_limit_hits(alone), guard_stops(alone)) == (0, 1)
    assert guard_stops({"planner_calls": [FINISHED, OUT_OF_TIME]}) == 0
