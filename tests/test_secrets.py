"""No secret leaves the process: a canary API key goes through the real LLM path (litellm
over HTTP to a stand-in server on 127.0.0.1) and must appear in no file under
``output.root`` (results, job store, MLflow store and artifacts, LLM cache, logs) and
nowhere in the printed output; the stand-in must have received it, so the key was used."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

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


# ----------------------------------------------------------------- issue 20, finding 5


def _nothing_written_or_printed(out: Path, done: subprocess.CompletedProcess[str]) -> None:
    assert CANARY not in done.stdout and CANARY not in done.stderr
    found = _files_containing(out, CANARY.encode()) if out.exists() else []
    assert found == []


@pytest.mark.parametrize("sweep", [[], ["-m", "seed=0,1"]], ids=["single run", "sweep"])
def test_a_key_pasted_as_the_variable_name_is_refused_and_never_stored(
    data_root: Path, tmp_path: Path, sweep: list[str]
) -> None:
    """Before: the key was printed in the error line and stored in result.json, the MLflow
    store and .hydra/*.yaml."""
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "flows.cli", *sweep, "domain=blocksworld", "task=6",
         "method=twostep", "decomposer=llm", f"llm.api_key_env={CANARY}",
         f"data.root={data_root}", f"output.root={out}", "orchestration.prefect=false"],
        capture_output=True, text=True, cwd=REPO, timeout=240,
    )  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.startswith("error: llm.api_key_env looks like a key, not a variable name")
    _nothing_written_or_printed(out, done)
    assert not list(out.glob("*runs/*/*")) if out.exists() else True  # refused before Hydra


def test_credentials_in_a_url_are_masked_everywhere(data_root: Path, tmp_path: Path) -> None:
    """Before: `llm.api_base=https://user:pass@host` was stored as an MLflow param (and in
    the job store's config, .hydra/*.yaml, the sweep's files). A one-job sweep through the
    stand-in server, with the password in the URL: it is used, and found nowhere."""
    out = tmp_path / "out"
    with standin_server([ENGLISH, PDDL, "none"]) as server:
        host = server.address.removeprefix("http://")
        done = subprocess.run(
            [sys.executable, "-m", "flows.cli", "-m", "domain=blocksworld", "task=6",
             "agents=3", "method=twostep", "decomposer=llm", "llm=openai-compatible",
             "llm.model=openai/standin", f"llm.api_base=http://user:{CANARY}@{host}/v1",
             "llm.max_retries=0", f"data.root={data_root}", f"output.root={out}",
             "orchestration.prefect=false", "planner.time_limit_s=20"],
            capture_output=True, text=True, cwd=REPO, timeout=240,
        )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert server.requests, "the LLM path was not exercised"
    assert (out / "mlflow.db").is_file() and list(out.glob("jobs/*/config.json"))
    assert list(out.glob("multiruns/*/*/multirun.yaml"))
    _nothing_written_or_printed(out, done)
    masked = f"http://***@{host}/v1"
    (config,) = out.glob("jobs/*/config.json")
    assert masked in config.read_text()  # the URL is kept, without its credentials


# ----------------------------------------------------------------- issue 39, finding 7

KEY_SHAPED = "AIza" + "Canary0d1eNotARealKey7f3a9b"  # Google's key shape, made up here


@pytest.mark.parametrize("sweep", [[], ["-m", "seed=0"]], ids=["single run", "sweep"])
def test_a_key_in_the_api_base_query_string_is_masked_everywhere(
    data_root: Path, tmp_path: Path, sweep: list[str]
) -> None:
    """Before: `?api_key=<key>` in llm.api_base was stored as the MLflow param and in
    .hydra/{config,hydra,overrides}.yaml (and the Prefect parameters: see below). Nothing
    answers on port 9: the job fails on the LLM, and is recorded."""
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "flows.cli", *sweep, "domain=blocksworld", "task=6",
         "method=twostep", "decomposer=llm", "llm=gpt-4o", "llm.max_retries=0",
         f"llm.api_base='http://127.0.0.1:9/v1?api_key={KEY_SHAPED}&v=1'",
         f"data.root={data_root}", f"output.root={out}", "orchestration.prefect=false"],
        capture_output=True, text=True, cwd=REPO, timeout=240,
        env={**os.environ, "OPENAI_API_KEY": "not-used"},
    )  # fmt: skip
    assert "Traceback" not in done.stderr, done.stderr
    assert (out / "mlflow.db").is_file() and list(out.glob("*runs/**/.hydra/overrides.yaml"))
    assert KEY_SHAPED not in done.stdout + done.stderr
    assert [
        p for p in out.rglob("*") if p.is_file() and KEY_SHAPED.encode() in p.read_bytes()
    ] == []
    (overrides,) = out.glob("*runs/**/.hydra/overrides.yaml")
    assert "?api_key=***&v=1" in overrides.read_text()  # the URL is kept, its key masked


def test_prefect_parameters_mask_a_query_string_key() -> None:
    from flows.prefect_flow import flow_parameters

    config = {"method": {"name": "twostep"}, "decomposer": {"name": "llm"},
              "llm": {"api_base": f"https://h/v1?key={KEY_SHAPED}",
                      "headers": f"Bearer {KEY_SHAPED}"}}  # fmt: skip
    shown = str(flow_parameters(config))
    assert KEY_SHAPED not in shown and "https://h/v1?key=***" in shown


@pytest.mark.parametrize(
    "args",
    [
        ["llm.model=openai/sk-" + CANARY],
        ["llm.model=openai/" + KEY_SHAPED],
        ["-m", "llm.model=openai/gpt-4o,openai/sk-" + CANARY],
        ["llm.api_key=sk-" + CANARY],
        ["+llm.api_key=sk-" + CANARY],
        [f"+llm.extra_headers={{Authorization:'Bearer {CANARY}'}}"],
    ],
    ids=["model", "model-google-shape", "model-in-a-sweep", "api_key", "+api_key", "+headers"],
)
def test_a_key_in_a_name_or_an_unknown_key_is_refused_and_never_shown(
    data_root: Path, tmp_path: Path, args: list[str]
) -> None:
    """Before: a key in llm.model was printed in the credentials error and stored in five
    places; +llm.extra_headers was accepted and stored; Hydra echoed llm.api_key=<key>."""
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "flows.cli", *args, "domain=blocksworld", "task=6",
         "method=twostep", "decomposer=llm", "llm=gpt-4o",
         f"data.root={data_root}", f"output.root={out}", "orchestration.prefect=false"],
        capture_output=True, text=True, cwd=REPO, timeout=240,
    )  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.startswith("error: ") and len(done.stderr.splitlines()) == 1
    assert CANARY not in done.stderr and KEY_SHAPED not in done.stderr and not done.stdout
    assert not out.exists()  # refused before any folder
