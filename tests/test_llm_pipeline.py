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

from flows.config import register
from flows.job import run_job
from twostep.benchmark import BenchmarkTask, load_task
from twostep.decomposers.llm import LLMDecomposer
from twostep.llm import LLMClient, LLMSettings
from twostep.pipeline import RunResult, check_run, run_twostep
from twostep.planner import PlannerSettings

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
    result = run_twostep(task, 3, scripted(GOOD_EN, GOOD_PDDL, "None"), BW, FAST)
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
    result = run_twostep(task, 2, scripted(*answers), BW, FAST)
    [subgoal] = result.subgoals
    assert subgoal["status"] == status, subgoal
    assert subgoal["reason"] and fragment.lower() in subgoal["reason"].lower()
    assert result.fallback == "no helper subgoal accepted"
    assert list(result.plans) == ["agent0"]
    assert_valid_schedule(task, result)


def test_none_for_the_first_helper_falls_back_to_sa(task: BenchmarkTask) -> None:
    result = run_twostep(task, 3, scripted("none"), BW, FAST)
    assert [s["status"] for s in result.subgoals] == ["stopped"]
    assert result.fallback == "no helper subgoal proposed"
    assert_valid_schedule(task, result)


def test_more_helpers_than_asked_are_ignored(task: BenchmarkTask) -> None:
    result = run_twostep(task, 2, scripted(GOOD_EN, GOOD_PDDL, GOOD_EN, GOOD_PDDL), BW, FAST)
    assert [s["helper"] for s in result.subgoals] == [1]
    assert_valid_schedule(task, result)


def test_whole_goal_and_contradiction_are_discarded(task: BenchmarkTask) -> None:
    whole = task.problem.goal.to_pddl()
    positive = sorted(task.problem.goal.positive)[0]
    undo = f"(and (not ({' '.join(positive)})) (arm-empty))"
    result = run_twostep(
        task, 3, scripted(english("everything"), whole, english("undo"), undo), BW, FAST
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
    live = run_job(compose("config", overrides=overrides)).to_dict()
    assert len(calls) == 3 and [s["status"] for s in live["subgoals"]] == ["accepted", "stopped"]

    monkeypatch.setattr(litellm, "completion", None)  # the network is gone
    monkeypatch.delenv("OPENAI_API_KEY")
    replayed = run_job(compose("config", overrides=[*overrides, "llm.mode=replay"])).to_dict()
    assert strip_timings(replayed) == strip_timings(live)
    assert "fake-test-key" not in json.dumps(live) + json.dumps(replayed)

    # a replay of a request that was never recorded fails clearly (other seed)
    with pytest.raises(Exception, match=r"(?i)cache"):
        run_job(compose("config", overrides=[*overrides, "llm.mode=replay", "seed=7"]))


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
