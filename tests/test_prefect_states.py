"""Prefect states tell the truth (issue 20, finding 6): a job that ends without success
ends its flow run in a Failed state named after how it ended, with the reason; the job is
still recorded and a sweep goes on. Before: an ``llm_error`` job's flow run was green
(COMPLETED) in the Prefect UI."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from flows.prefect_flow import final_state
from tests.support.commands import api
from tests.support.data import make_data

BASE = {"domain": "blocksworld", "task": 1, "method": "twostep", "agents": 2, "seed": 0}


@pytest.mark.parametrize(
    ("result", "name", "message"),
    [
        ({"status": "llm_error", "message": "LLM call failed: generate for agent1: 401"},
         "LLMError", "llm_error: LLM call failed: generate for agent1: 401"),
        ({"status": "timeout", "message": "search time limit"},
         "TimedOut", "timeout: search time limit"),
        ({"status": "error", "message": "planner exited 35"}, "Error", "error: planner exited 35"),
        ({"status": "unsolvable", "message": ""}, "Unsolvable", "unsolvable: unsolvable"),
        ({"status": "solved", "message": "", "executor": "embodied",
          "embodied_status": "deadlock"}, "EmbodiedFailed", "embodied_failed: solved"),
        # the result rule's verdict names its status already: said once
        ({"status": "embodied_failed", "message": "embodied_failed: boxed_in at step 0, agent1",
          "executor": "embodied", "embodied_status": "boxed_in"},
         "EmbodiedFailed", "embodied_failed: boxed_in at step 0, agent1"),
    ],
)  # fmt: skip
def test_a_job_without_success_ends_its_flow_run_failed(
    result: dict[str, Any], name: str, message: str
) -> None:
    state = final_state({**BASE, "success": False, **result})
    assert not isinstance(state, dict)
    assert state.type.value == "FAILED" and state.name == name
    assert state.message == message
    assert state.data == {**BASE, "success": False, **result}  # the result is kept


def test_a_successful_job_returns_its_result() -> None:
    result = {**BASE, "success": True, "status": "solved", "exec_length": 4}
    assert final_state(result) == result  # a plain value: the flow run is Completed


@pytest.mark.integration
def test_failed_jobs_flow_runs_are_failed_on_the_server_and_the_sweep_goes_on(
    tmp_path: Path, prefect_server: str
) -> None:
    """A 2-job sweep on a real Prefect server (the session's: its flow runs are told apart
    by the sweep's tag, and named unlike other tests'): goal-split succeeds; the LLM
    decomposer without credentials ends `llm_error` (no network is tried)."""
    data = make_data(tmp_path / "data")
    environment = {k: v for k, v in os.environ.items() if k != "OPENAI_API_KEY"}
    done = subprocess.run(
        [str(Path(sys.executable).parent / "twostep"), "-m", "method=twostep", "task=2", "agents=3",
         "decomposer=goal-split,llm", "llm=gpt-4o", f"data.root={data}",
         f"output.root={tmp_path / 'out'}", "mlflow.enabled=false",
         f"orchestration.prefect_api_url={prefect_server}", "planner.time_limit_s=20"],
        capture_output=True, text=True, timeout=300, env=environment,
    )  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr  # a job failed ...
    assert "sweep finished: 2/2 jobs: 1 ok, 1 failed, 0 timed out" in done.stdout  # goes on
    assert "prefect: " in done.stdout and "flow runs: 1 completed, 1 failed" in done.stdout
    (sweep_dir,) = (tmp_path / "out" / "multiruns").glob("*/*")
    tag = f"multirun:{sweep_dir.parent.name}_{sweep_dir.name}"
    runs = api(prefect_server, "/flow_runs/filter", {"flow_runs": {"tags": {"all_": [tag]}}})
    states = sorted((r["state"]["type"], r["state"]["name"]) for r in runs)
    assert states == [("COMPLETED", "Completed"), ("FAILED", "LLMError")]
    (failed,) = [r for r in runs if r["state"]["type"] == "FAILED"]
    assert failed["state"]["message"].startswith("llm_error: ")
    assert "LLM credentials missing" in failed["state"]["message"]


def _job(prefect_server: str, out: Path, *overrides: str) -> dict[str, Any]:
    """One job through the ``twostep`` command as a flow on the server; its result.json."""
    done = subprocess.run(
        [str(Path(sys.executable).parent / "twostep"), *overrides, f"output.root={out}",
         "mlflow.enabled=false", f"orchestration.prefect_api_url={prefect_server}"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode in (0, 1), done.stdout + done.stderr  # 1: no plan (timed out)
    (path,) = out.glob("runs/*/*/result.json")
    result: dict[str, Any] = json.loads(path.read_text())
    return result


def _flow_run(prefect_server: str, name: str, out: Path) -> dict[str, Any]:
    """The flow run of that name whose parameters are this test's (output.root)."""
    runs = api(prefect_server, "/flow_runs/filter", {"flow_runs": {"name": {"any_": [name]}}})
    (run,) = [r for r in runs if r["parameters"]["job"]["output"]["root"] == str(out)]
    return run


FINAL_STATES = {"COMPLETED", "FAILED", "CRASHED", "CANCELLED"}


def _task_runs(prefect_server: str, flow_run_id: str) -> list[dict[str, Any]]:
    """The flow run's task runs once the server has written them all: they reach it as
    events, which its recorder writes in batches at least every second."""
    body = {"flow_runs": {"id": {"any_": [flow_run_id]}}}
    seen: list[tuple[str, str]] | None = None
    for _ in range(20):
        runs = list(api(prefect_server, "/task_runs/filter", body))
        states = sorted((t["name"], str((t.get("state") or {}).get("type"))) for t in runs)
        if states == seen and all(state in FINAL_STATES for _, state in states):
            break
        seen = states
        time.sleep(1.2)
    return runs


def _log_lines(prefect_server: str, flow_run_id: str) -> list[str]:
    body = {"logs": {"flow_run_id": {"any_": [flow_run_id]}}, "sort": "TIMESTAMP_ASC"}
    for _ in range(20):  # logs reach the server from a background worker
        lines = [entry["message"] for entry in api(prefect_server, "/logs/filter", body)]
        if any(line.startswith("result: ") for line in lines):
            return lines
        time.sleep(0.5)
    return lines


@pytest.mark.integration
def test_prefect_tells_the_story_of_a_job(
    tmp_path: Path, prefect_server: str, data_root: Path
) -> None:
    """Issue 37: task runs named by step, role and agent (``plan-505`` before); a planner
    call that ran out of time is not green; log lines; only the config groups the job
    reads; tags to filter by. Checked through Prefect's API, against the jobs' result.json
    (which the library writes, not Prefect)."""
    split = _job(prefect_server, tmp_path / "a", "domain=grippers", "task=1", "method=twostep",
                 "decomposer=goal-split", "agents=3", f"data.root={data_root}")  # fmt: skip
    run = _flow_run(prefect_server, "grippers-p01-twostep-goal-split-n3-s0", tmp_path / "a")
    names = sorted(t["name"] for t in _task_runs(prefect_server, run["id"]))
    calls = split["planner_calls"]
    roles = {"single": "sa", "multi": "ma"}
    planned = [f"plan {roles.get(c['role']) or c['role'] + ' ' + c['agent']}" for c in calls]
    if "sa_planning_time_s" in split:  # the SA plan solved beside it (sa_length, fallback)
        planned.append("plan sa")
    helpers = [c["agent"] for c in calls if c["role"] == "helper" and c["status"] == "solved"]
    assert helpers  # grippers p01: a helper takes a ball (README)
    want = [*planned, *(f"progress after {agent}" for agent in helpers), "score"]
    assert names == sorted(want)
    assert "plan sa" in names and "plan main agent0" in names  # SA first, then main
    # what the job reads, nothing else: no llm block for goal-split
    assert "llm" not in run["parameters"]["job"] and "decomposer" in run["parameters"]["job"]
    tags = set(run["tags"])
    assert {"task:1", "seed:0", "decomposer:goal-split", "agents:3", "method:twostep"} <= tags
    lines = _log_lines(prefect_server, run["id"])
    assert lines[0].startswith("start grippers-p01-twostep-goal-split-n3-s0: TwoStep")
    assert any(line.startswith("plan helper agent1: solved, ") for line in lines)
    assert lines[-1].startswith("result: grippers-p01-twostep-goal-split-n3-s0 | success")

    # termes p06's SA search runs out of a 1 s limit (its plan takes seconds more)
    timed = _job(prefect_server, tmp_path / "b", "domain=termes", "task=6", "method=sa",
                 "planner.time_limit_s=1", f"data.root={data_root}")  # fmt: skip
    assert timed["status"] == "timeout"
    run = _flow_run(prefect_server, "termes-p06-sa-n1-s0", tmp_path / "b")
    assert (run["state"]["type"], run["state"]["name"]) == ("FAILED", "TimedOut")
    (plan,) = _task_runs(prefect_server, run["id"])
    assert plan["name"] == "plan sa"
    assert (plan["state"]["type"], plan["state"]["name"]) == ("FAILED", "TimedOut")
    assert plan["state"]["message"].startswith("timeout: ")
    assert "llm" not in run["parameters"]["job"] and "decomposer" not in run["parameters"]["job"]
    lines = _log_lines(prefect_server, run["id"])
    assert any(line.startswith("plan sa: timeout") for line in lines)
    assert lines[-1].startswith("result: termes-p06-sa-n1-s0 | TIMED OUT")
