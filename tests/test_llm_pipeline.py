"""The LLM decomposer inside the whole TwoStep pipeline, offline.

Answers come from scripts the tests write, or from a stand-in for ``litellm.completion``
(the network boundary); Fast Downward and the scorer are real. No model answers here.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from hydra import compose, initialize_config_dir

from flows.build import run_config
from flows.config import register
from twostep.decomposers.llm import LLMDecomposer
from twostep.llm import LLMClient, LLMSettings
from twostep.methods import MethodRequest, RunResult, check_run, run_twostep
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import BenchmarkTask, load_task

REPO = Path(__file__).resolve().parent.parent
BW = ["arm-empty", "holding"]
FAST = PlannerSettings("lama-first", 20)

# blocksworld p06 (generated data): b4 can be put on the table by a helper.
GOOD_EN = (
    "agent1 can take b4 off its tower and put it down while agent0 rearranges the rest. "
    "Therefore, agent1's complete and final goal condition, stated with object names, is: "
    "b4 is on the table and the arm is empty."
)
GOOD_PDDL = "```pddl\n(:goal\n  (and\n    (on-table b4)\n    (arm-empty)))\n```"


def english(condition: str) -> str:
    return f"It can help. Therefore, agent1's complete and final goal condition is: {condition}."


@pytest.fixture(scope="module")
def task(data_root: Path) -> BenchmarkTask:
    return load_task("blocksworld", 6, data_root)


def scripted(*answers: str) -> LLMDecomposer:
    return LLMDecomposer(LLMClient(LLMSettings(mode="scripted"), answers=list(answers)))


def assert_valid_schedule(task: BenchmarkTask, result: RunResult) -> None:
    check_run(task.problem, result, BW)
    assert result.success and result.exec_length == len(result.schedule)


def test_good_subgoal_is_planned_in_parallel(task: BenchmarkTask) -> None:
    result = run_twostep(MethodRequest(task, 3, FAST, BW, scripted(GOOD_EN, GOOD_PDDL, "None")))
    statuses = [(s["helper"], s["status"]) for s in result.subgoals]
    assert statuses == [(1, "accepted"), (2, "stopped")]
    assert result.subgoals[0]["pddl"] == "(and (arm-empty) (on-table b4))"
    assert result.subgoals[0]["english"].startswith("b4 is on the table")
    assert result.scripted_llm and result.fallback is None
    assert set(result.plans) == {"agent0", "agent1"}
    assert_valid_schedule(task, result)
    # the prompts and raw answers are recorded for every helper, the "none" too
    assert [len(s["exchanges"]) for s in result.subgoals] == [2, 1]


BAD_KINDS = [
    ("empty answer", ["", ""], "discarded", "empty"),
    (
        "prose without a condition",
        ["I think the agents should cooperate nicely.", ""],
        "discarded",
        "",
    ),
    (
        "PDDL syntax error",
        [english("b4 is on the table"), "(:goal (and on-table b4 (arm-empty)))"],
        "discarded",
        "",
    ),
    (
        "unknown predicate",
        [english("b4 is on the floor"), "(:goal (and (on-floor b4)))"],
        "discarded",
        "on-floor",
    ),
    (
        "unknown object",
        [english("b9 is on the table"), "(:goal (and (on-table b9)))"],
        "discarded",
        "b9",
    ),
    ("wrong arity", [english("b4 is on b1"), "(:goal (and (on b4)))"], "discarded", "argument"),
    ("already true", [english("the goal"), "(:goal (and (on-table b5)))"], "discarded", ""),
]


@pytest.mark.parametrize(
    ("kind", "answers", "status", "fragment"), BAD_KINDS, ids=[k[0] for k in BAD_KINDS]
)
def test_bad_answers_are_discarded_and_the_run_succeeds(
    task: BenchmarkTask, kind: str, answers: list[str], status: str, fragment: str
) -> None:
    if kind == "already true" and ("on-table", "b5") not in task.problem.init:
        pytest.skip("p06 changed: b5 is not on the table initially")
    result = run_twostep(MethodRequest(task, 2, FAST, BW, scripted(*answers)))
    [subgoal] = result.subgoals
    assert subgoal["status"] == status, subgoal
    assert subgoal["reason"] and fragment.lower() in subgoal["reason"].lower()
    assert result.fallback == "no helper subgoal accepted"
    assert list(result.plans) == ["agent0"]
    assert_valid_schedule(task, result)


def test_none_for_the_first_helper_falls_back_to_sa(task: BenchmarkTask) -> None:
    result = run_twostep(MethodRequest(task, 3, FAST, BW, scripted("none")))
    assert [s["status"] for s in result.subgoals] == ["stopped"]
    assert result.fallback == "no helper subgoal proposed"
    assert_valid_schedule(task, result)


def test_more_helpers_than_asked_are_ignored(task: BenchmarkTask) -> None:
    result = run_twostep(
        MethodRequest(task, 2, FAST, BW, scripted(GOOD_EN, GOOD_PDDL, GOOD_EN, GOOD_PDDL))
    )
    assert [s["helper"] for s in result.subgoals] == [1]
    assert_valid_schedule(task, result)


def test_whole_goal_and_contradiction_are_discarded(task: BenchmarkTask) -> None:
    whole = task.problem.goal.to_pddl()
    positive = sorted(task.problem.goal.positive)[0]
    undo = f"(and (not ({' '.join(positive)})) (arm-empty))"
    result = run_twostep(
        MethodRequest(
            task, 3, FAST, BW, scripted(english("everything"), whole, english("undo"), undo)
        )
    )
    reasons = [s["reason"] for s in result.subgoals]
    assert [s["status"] for s in result.subgoals] == ["discarded", "discarded"]
    assert "full goal" in reasons[0] and "contradict" in reasons[1]
    assert_valid_schedule(task, result)


# ------------------------------------------------------------ the CLI and replay

TIMING_KEYS = {
    "planning_time_s",
    "llm_time_s",
    "wall_time_s",
    "state_editing_time_s",
    "score_time_s",
}


def strip_timings(value: Any) -> Any:
    """result.json without timings (and without cache flags, which differ on replay)."""
    if isinstance(value, dict):
        return {
            k: strip_timings(v)
            for k, v in value.items()
            if k not in TIMING_KEYS
            and not k.endswith("_s")
            and k not in {"cached", "seconds", "recorded_seconds"}
        }
    if isinstance(value, list):
        return [strip_timings(v) for v in value]
    return value


@pytest.fixture
def hydra_conf() -> Iterator[None]:
    register()
    with initialize_config_dir(config_dir=str(REPO / "conf"), version_base="1.3"):
        yield


def test_replay_with_network_blocked_gives_identical_result(
    hydra_conf: None, data_root: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from twostep.llm.client import _import_litellm

    litellm = _import_litellm()
    real = litellm.completion
    calls: list[str] = []

    def provider(**kwargs: Any) -> Any:  # stands in for the API, answers by prompt kind
        user = str(kwargs["messages"][-1]["content"])
        calls.append(user)
        reply = GOOD_PDDL if "PDDL" in user.splitlines()[-1] else GOOD_EN
        return real(**kwargs, mock_response=reply if len(calls) < 3 else "none")

    overrides = [
        f"data.root={data_root}",
        f"output.root={tmp_path}",
        "domain=blocksworld",
        "task=6",
        "agents=3",
        "decomposer=llm",
        "llm=gpt-4o",
        "orchestration.prefect=false",
        "planner.time_limit_s=20",
    ]
    monkeypatch.setenv("OPENAI_API_KEY", "fake-test-key-not-real-000000")
    monkeypatch.setattr(litellm, "completion", provider)
    live = run_config(compose("config", overrides=overrides)).to_dict()
    assert len(calls) == 3 and [s["status"] for s in live["subgoals"]] == ["accepted", "stopped"]

    monkeypatch.setattr(litellm, "completion", None)  # the network is gone
    monkeypatch.delenv("OPENAI_API_KEY")
    replayed = run_config(compose("config", overrides=[*overrides, "llm.mode=replay"])).to_dict()
    assert strip_timings(replayed) == strip_timings(live)
    assert "fake-test-key" not in json.dumps(live) + json.dumps(replayed)

    # a replay of a request that was never recorded fails clearly (other seed)
    with pytest.raises(Exception, match=r"(?i)cache"):
        run_config(compose("config", overrides=[*overrides, "llm.mode=replay", "seed=7"]))


def test_cli_with_scripted_answers(data_root: Path, tmp_path: Path) -> None:
    script = tmp_path / "answers.yaml"
    script.write_text(yaml.safe_dump({"answers": [GOOD_EN, GOOD_PDDL, "none"]}))
    env = {**os.environ, "OPENAI_API_KEY": ""}
    proc = subprocess.run(
        [sys.executable, "-m", "flows.cli", "domain=blocksworld", "task=6", "agents=3",
         "decomposer=llm", "llm=scripted", f"llm.script={script}", f"data.root={data_root}",
         f"output.root={tmp_path / 'out'}", "orchestration.prefect=false", "planner.time_limit_s=20"],
        capture_output=True, text=True, cwd=REPO, env=env, timeout=240,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "success" in proc.stdout
    [result_file] = list((tmp_path / "out" / "runs").rglob("result.json"))
    result = json.loads(result_file.read_text())
    assert result["scripted_llm"] is True
    assert [s["status"] for s in result["subgoals"]] == ["accepted", "stopped"]
    assert len(result["schedule"]) == result["exec_length"]


def test_cli_missing_credentials_is_one_line(data_root: Path, tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != "OPENAI_API_KEY"}
    proc = subprocess.run(
        [sys.executable, "-m", "flows.cli", "domain=blocksworld", "task=6", "decomposer=llm",
         f"data.root={data_root}", f"output.root={tmp_path}", "orchestration.prefect=false"],
        capture_output=True, text=True, cwd=REPO, env=env, timeout=240,
    )  # fmt: skip
    assert proc.returncode != 0
    # The job's outcome (status llm_error, the summary line on stdout) or a job error (stderr).
    output = proc.stdout + proc.stderr
    message = [line for line in output.splitlines() if line.strip()]
    assert any("OPENAI_API_KEY" in line and "goal-split" in line for line in message), output
    assert "Traceback" not in output


# ------------------------------------------------- failed LLM calls fail the run

FAKE_KEY = "fake-test-key-not-real-000000"


def transport_error(litellm: Any, kind: str) -> Exception:
    """The exception litellm raises for ``kind`` (what the network would give us)."""
    made: dict[str, Any] = {
        "connection": lambda: litellm.APIConnectionError(
            message="Connection error.", llm_provider="openai", model="gpt-4o"
        ),
        "timeout": lambda: litellm.Timeout(
            "Request timed out.", model="gpt-4o", llm_provider="openai"
        ),
        "rate limit": lambda: litellm.RateLimitError(
            "Rate limit reached", llm_provider="openai", model="gpt-4o"
        ),
        "server error": lambda: litellm.InternalServerError(
            "upstream failed", llm_provider="openai", model="gpt-4o"
        ),
    }
    error: Exception = made[kind]()
    return error


class StandIn:
    """Stands in for ``litellm.completion``: answers by prompt kind, or raises ``error``."""

    def __init__(self, litellm: Any, generate: str = GOOD_EN, translate: str = GOOD_PDDL) -> None:
        self.real = litellm.completion
        self.answers = {"generate": generate, "translate": translate}
        self.error: Exception | None = None
        self.calls = 0

    def __call__(self, **kwargs: Any) -> Any:
        self.calls += 1
        if self.error is not None:
            raise self.error
        user = str(kwargs["messages"][-1]["content"])
        step = "translate" if "PDDL" in user.splitlines()[-1] else "generate"
        return self.real(**kwargs, mock_response=self.answers[step])


@pytest.fixture
def litellm(monkeypatch: pytest.MonkeyPatch) -> Any:
    from twostep.llm.client import _import_litellm

    monkeypatch.setenv("OPENAI_API_KEY", FAKE_KEY)
    return _import_litellm()


def live(tmp_path: Path, retries: int = 2) -> LLMDecomposer:
    settings = LLMSettings(cache_dir=tmp_path / "cache", max_retries=retries, backoff_s=0.001)
    return LLMDecomposer(LLMClient(settings))


@pytest.mark.parametrize("kind", ["connection", "timeout", "rate limit", "server error"])
def test_failed_llm_call_fails_the_run_without_fallback(
    task: BenchmarkTask, tmp_path: Path, litellm: Any, monkeypatch: pytest.MonkeyPatch, kind: str
) -> None:
    provider = StandIn(litellm)
    provider.error = transport_error(litellm, kind)
    monkeypatch.setattr(litellm, "completion", provider)
    result = run_twostep(MethodRequest(task, 3, FAST, BW, live(tmp_path, retries=2)))
    assert (result.status, result.success, result.fallback) == ("llm_error", False, None)
    assert type(provider.error).__name__ in result.message and "3 attempts" in result.message
    assert "generate for agent1" in result.message and FAKE_KEY not in result.message
    # the first call, tried 1 + 2 times by the client; no translate, no second helper, no plan
    assert provider.calls == 3
    assert result.planner_calls == [] and result.plans == {} and result.exec_length is None
    assert [s["status"] for s in result.subgoals] == ["discarded"]


def test_bad_live_answer_is_discarded_and_falls_back(
    task: BenchmarkTask, tmp_path: Path, litellm: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    provider = StandIn(litellm, translate="Sorry, I cannot write PDDL.")
    monkeypatch.setattr(litellm, "completion", provider)
    result = run_twostep(MethodRequest(task, 2, FAST, BW, live(tmp_path)))
    assert result.status == "solved" and result.success and provider.calls == 2
    assert result.fallback == "no helper subgoal accepted"
    [subgoal] = result.subgoals
    assert subgoal["status"] == "discarded" and "no PDDL goal" in subgoal["reason"]
    assert_valid_schedule(task, result)


def test_failed_llm_call_through_the_config(
    hydra_conf: None, data_root: Path, tmp_path: Path, litellm: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    provider = StandIn(litellm)
    provider.error = transport_error(litellm, "connection")
    monkeypatch.setattr(litellm, "completion", provider)
    overrides = [
        f"data.root={data_root}", f"output.root={tmp_path}", "domain=blocksworld", "task=6",
        "decomposer=llm", "llm=gpt-4o", "llm.max_retries=1", "llm.backoff_s=0.001",
        "orchestration.prefect=false", "compare_sa=false",
    ]  # fmt: skip
    result = run_config(compose("config", overrides=overrides)).to_dict()
    assert (result["status"], result["success"], result["fallback"]) == ("llm_error", False, None)
    assert "APIConnectionError" in result["message"] and provider.calls == 2


# ------------------------------------------------------------- under Prefect


@pytest.fixture(scope="module")
def prefect_api(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A Prefect server for this module's flow tests; stopped by PID."""
    from flows.servers import ServerSettings, spawn_server, stop_server, wait_until_healthy

    home = tmp_path_factory.mktemp("prefect-home")
    info = spawn_server(ServerSettings(home=str(home), startup_timeout_s=240), os.getpid())
    try:
        wait_until_healthy(info)
        yield info.api_url
    finally:
        from flows.prefect_flow import flush_to_server

        flush_to_server()  # the logs still queued for it, before it stops
        stop_server(info)


def flow_cfg(data_root: Path, tmp_path: Path, api_url: str, *overrides: str) -> Any:
    return compose(
        "config",
        overrides=[
            f"data.root={data_root}", f"output.root={tmp_path}", "domain=blocksworld", "task=6",
            "agents=2", "decomposer=llm", "llm=gpt-4o", "compare_sa=false", "mlflow.enabled=false",
            "orchestration.prefect=true", f"orchestration.prefect_api_url={api_url}",
            "orchestration.reuse_results=false", *overrides,
        ],
    )  # fmt: skip


@pytest.mark.integration
def test_missing_key_under_prefect_is_one_line_and_one_attempt(
    hydra_conf: None,
    data_root: Path,
    tmp_path: Path,
    prefect_api: str,
    monkeypatch: pytest.MonkeyPatch,
    capfd: pytest.CaptureFixture[str],
) -> None:
    from flows.console import format_summary
    from flows.job import execute_job

    attempts: list[int] = []
    real_complete = LLMClient.complete

    def counted(self: LLMClient, *args: Any, **kwargs: Any) -> Any:
        attempts.append(1)
        return real_complete(self, *args, **kwargs)

    monkeypatch.setattr(LLMClient, "complete", counted)
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    capfd.readouterr()
    outcome = execute_job(flow_cfg(data_root, tmp_path, prefect_api), tmp_path / "job")
    output = "".join(capfd.readouterr())
    assert attempts == [1]  # no retry of something that can never succeed
    result = outcome.result
    assert (result["status"], result["success"], result["fallback"]) == ("llm_error", False, None)
    assert "OPENAI_API_KEY" in result["message"] and "goal-split" in result["message"]
    assert "Traceback" not in output and "OPENAI_API_KEY" not in output, output
    line = format_summary(result)
    assert "\n" not in line and "OPENAI_API_KEY" in line


@pytest.mark.integration
def test_llm_tasks_under_prefect_neither_cache_nor_retry(
    hydra_conf: None,
    data_root: Path,
    tmp_path: Path,
    prefect_api: str,
    litellm: Any,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from flows.job import execute_job

    provider = StandIn(litellm)
    monkeypatch.setattr(litellm, "completion", provider)
    cfg = flow_cfg(data_root, tmp_path, prefect_api, "llm.max_retries=1", "llm.backoff_s=0.001")
    first = execute_job(cfg, tmp_path / "job1")
    assert first.status == "success", first.error
    assert first.result["subgoals"][0]["status"] == "accepted" and provider.calls == 2
    assert (first.stats.llm_calls, first.stats.llm_cache_hits) == (2, 0)
    # Run again: the LLM client's disk cache answers (the one cache), no provider call.
    second = execute_job(cfg, tmp_path / "job2")
    assert provider.calls == 2 and (second.stats.llm_calls, second.stats.llm_cache_hits) == (0, 2)
    assert second.result["subgoals"][0]["pddl"] == first.result["subgoals"][0]["pddl"]
    # A new seed asks the provider again; it is down: the client's 1 + 1 attempts, no
    # task retry on top, and the run fails as llm_error (no fallback).
    provider.error = transport_error(litellm, "connection")
    down = execute_job(
        flow_cfg(data_root, tmp_path, prefect_api, "llm.max_retries=1", "llm.backoff_s=0.001",
                 "seed=1"),
        tmp_path / "job3",
    )  # fmt: skip
    assert provider.calls == 4 and down.stats.llm_calls == 1  # one generate task run
    assert (down.result["status"], down.result["fallback"]) == ("llm_error", None)
    assert "APIConnectionError" in down.result["message"]


def test_steps_replace_the_llm_calls(task: BenchmarkTask) -> None:
    """Steps.generate / Steps.translate are what the pipeline calls for the LLM decomposer."""
    from twostep.decomposers.llm import generate_subgoal, translate_subgoal
    from twostep.methods import Steps

    seen: list[tuple[str, int]] = []

    def generate(
        client: Any, task: BenchmarkTask, agents: int, helper: int, *a: Any, **k: Any
    ) -> Any:
        seen.append(("generate", helper))
        return generate_subgoal(client, task, agents, helper, *a, **k)

    def translate(*args: Any, **kwargs: Any) -> Any:
        seen.append(("translate", kwargs["helper"]))
        return translate_subgoal(*args, **kwargs)

    steps = Steps(generate=generate, translate=translate)
    result = run_twostep(
        MethodRequest(task, 3, FAST, BW, scripted(GOOD_EN, GOOD_PDDL, "None"), steps=steps)
    )
    assert seen == [("generate", 1), ("translate", 1), ("generate", 2)]
    assert [s["status"] for s in result.subgoals] == ["accepted", "stopped"]
