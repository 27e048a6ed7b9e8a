"""No secret leaves the process: a canary API key goes through the real LLM path (litellm
over HTTP to a stand-in server on 127.0.0.1) and must appear in no file under
``output.root`` (results, job store, MLflow store and artifacts, LLM cache, logs) and
nowhere in the printed output; the stand-in must have received it, so the key was used."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.llm_standin import standin_server

REPO = Path(__file__).resolve().parent.parent
CANARY = "canary-0d1e-not-a-real-key-7f3a9b"
# blocksworld p06 (generated data): a helper can clear b4; then "none" stops the loop.
ENGLISH = "agent1 puts b4 on the table. Final goal condition: b4 is on the table, arm empty."
PDDL = "```pddl\n(:goal (and (on-table b4) (arm-empty)))\n```"


def _files_containing(root: Path, needle: bytes) -> list[Path]:
    return [p for p in root.rglob("*") if p.is_file() and needle in p.read_bytes()]


def test_canary_key_is_used_but_never_written_or_printed(data_root: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    with standin_server([ENGLISH, PDDL, "none"]) as server:
        env = {**os.environ, "TWOSTEP_TEST_CANARY_KEY": CANARY}
        proc = subprocess.run(
            [sys.executable, "-m", "flows.cli", "domain=blocksworld", "task=6", "agents=3",
             "method=twostep", "decomposer=llm", "llm=openai-compatible",
             "llm.model=openai/standin", f"llm.api_base={server.api_base}",
             "llm.api_key_env=TWOSTEP_TEST_CANARY_KEY", "llm.max_retries=0",
             f"data.root={data_root}", f"output.root={out}", "orchestration.prefect=false",
             "planner.time_limit_s=20"],
            capture_output=True, text=True, cwd=REPO, env=env, timeout=240,
        )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert server.requests, "the LLM path was not exercised"
    assert any(CANARY in a for a in server.authorizations), "the key never reached the server"
    assert CANARY not in proc.stdout and CANARY not in proc.stderr
    assert list(out.rglob("result.json")), "the run wrote no result"
    assert (out / "mlflow.db").is_file(), "MLflow logging did not run"
    assert _files_containing(out, CANARY.encode()) == []
