"""Prefect states tell the truth (issue 20, finding 6): a job that ends without success
ends its flow run in a Failed state named after how it ended, with the reason; the job is
still recorded and a sweep goes on. Before: an ``llm_error`` job's flow run was green
(COMPLETED) in the Prefect UI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from flows.prefect_flow import final_state
from tests.test_flows import api, make_data

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
    assert "sweep finished: 2/2 jobs, 1 failed" in done.stdout  # ... and the sweep went on
    assert "prefect: " in done.stdout and "flow runs: 1 completed, 1 failed" in done.stdout
    (sweep_dir,) = (tmp_path / "out" / "multiruns").glob("*/*")
    tag = f"multirun:{sweep_dir.parent.name}_{sweep_dir.name}"
    runs = api(prefect_server, "/flow_runs/filter", {"flow_runs": {"tags": {"all_": [tag]}}})
    states = sorted((r["state"]["type"], r["state"]["name"]) for r in runs)
    assert states == [("COMPLETED", "Completed"), ("FAILED", "LLMError")]
    (failed,) = [r for r in runs if r["state"]["type"] == "FAILED"]
    assert failed["state"]["message"].startswith("llm_error: ")
    assert "LLM credentials missing" in failed["state"]["message"]
