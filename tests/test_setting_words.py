"""The library names its own parameters in its messages (``LLMSettings.mode``); a job
words them with the config keys (:mod:`flows.wording`), so what ``twostep`` prints and
stores reads as before the library stopped naming config keys.

The table is checked against the library (each name is a real field, class or argument)
and against the config (each key sets that very field: composed with Hydra and mapped by
``flows.build``); the command-line messages are hand-written here, as a user reads them."""

from __future__ import annotations

import ast
import dataclasses
import inspect
import json
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hydra import compose, initialize_config_dir

from flows.build import grounding_limits, llm_settings, planner_settings
from flows.config import register, schema_keys, typed
from flows.wording import SETTING_KEYS, worded, worded_error, worded_run
from tests.replay_logs import block
from twostep.methods import RunResult
from twostep.replay.importer import import_logs

REPO = Path(__file__).resolve().parent.parent
CONF = REPO / "conf"


@pytest.fixture(scope="module")
def hydra_conf() -> Iterator[None]:
    register()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        yield


# ----------------------------------------------------------------- the table


def _library_object(owner: str) -> Any:
    import twostep.decomposers.goal_split as goal_split
    import twostep.llm as llm
    import twostep.pddl.translator as translator
    import twostep.planner as planner
    import twostep.tasks.benchmark as benchmark

    for module in (llm, translator, planner, goal_split, benchmark):
        if hasattr(module, owner):
            return getattr(module, owner)
    raise AssertionError(f"{owner} is not a library name")


def test_every_name_is_the_library_s_and_every_key_the_config_s() -> None:
    keys = set(schema_keys())
    for name, key in SETTING_KEYS.items():
        call = re.fullmatch(r"(\w+)\((\w+)=\.\.\.\)", name)
        if call:  # a function's argument
            assert call.group(2) in inspect.signature(_library_object(call.group(1))).parameters
        elif "." in name:  # a dataclass's field
            owner, field = name.split(".")
            fields = {f.name for f in dataclasses.fields(_library_object(owner))}
            assert field in fields, name
        else:  # a class
            assert inspect.isclass(_library_object(name)), name
        if "=" in key:  # a group's option
            group, option = key.split("=")
            assert (CONF / group / f"{option}.yaml").is_file(), key
        else:
            assert key in keys, key


# Each config key set to a value of its own, and where the library receives it.
SET_BY = {
    "LLMSettings.model": ("llm.model", "openai/other-model", lambda c: llm_settings(c).model),
    "LLMSettings.api_key_env": ("llm.api_key_env", "MY_VAR", lambda c: llm_settings(c).api_key_env),
    "LLMSettings.mode": ("llm.mode", "replay", lambda c: llm_settings(c).mode),
    "LLMSettings.script": ("llm.script", "/x/a.yaml", lambda c: str(llm_settings(c).script)),
    "LLMSettings.bundle": ("llm.bundle", "/x/answers", lambda c: str(llm_settings(c).bundle)),
    "LLMSettings.translator": ("llm.translator", "rules", lambda c: llm_settings(c).translator),
    "GroundingLimits.memory_mb": (
        "planner.memory_limit_mb", 1234, lambda c: grounding_limits(c).memory_mb
    ),
    "GroundingLimits.time_s": (
        "planner.grounding_time_limit_s", 7.5, lambda c: grounding_limits(c).time_s
    ),
    "PlannerSettings.memory_limit_mb": (
        "planner.memory_limit_mb", 4321, lambda c: planner_settings(c).memory_limit_mb
    ),
}  # fmt: skip


def _composed(*overrides: str) -> Any:
    places = ["output.root=/tmp/twostep-out", "llm.cache_dir=/tmp/twostep-out/llm"]
    return typed(compose("config", overrides=[*places, "decomposer=llm", *overrides]))


def test_each_key_sets_the_field_the_table_names(
    hydra_conf: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Composed with the key set, the library's object holds the value in that field (the
    data root: the argument the job's task is loaded with)."""
    for name, (key, value, read) in SET_BY.items():
        assert SETTING_KEYS[name] == key, name
        assert read(_composed(f"{key}={value}")) == value, name
    fields = {n for n in SETTING_KEYS if re.fullmatch(r"\w+\.\w+", n)}
    assert fields == set(SET_BY)

    import flows.build
    from twostep.tasks.benchmark import load_task

    given: list[inspect.BoundArguments] = []

    def loaded(*args: Any, **kwargs: Any) -> Any:
        given.append(inspect.signature(load_task).bind(*args, **kwargs))
        raise LookupError("enough")

    monkeypatch.setattr(flows.build, "load_task", loaded)
    assert SETTING_KEYS["load_task(root=...)"] == "data.root"
    with pytest.raises(LookupError):
        flows.build.load_job_task(_composed("data.root=/x/data"))
    assert Path(given[0].arguments["root"]) == Path("/x/data")


def _messages(path: Path) -> Iterator[str]:
    """The string constants of a module that are not docstrings (its messages)."""
    tree = ast.parse(path.read_text())
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            first = node.body[0] if node.body else None
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                docstrings.add(id(first.value))
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and id(node) not in docstrings
        ):
            yield node.value


def test_every_setting_a_library_message_names_is_worded() -> None:
    """A message that names a settings field (``LLMSettings.mode=...``,
    ``GroundingLimits.time_s``) names one the table words: a new one must be added."""
    owners = {n.split(".")[0] for n in SETTING_KEYS if re.fullmatch(r"\w+\.\w+", n)}
    pattern = re.compile(r"\b(" + "|".join(sorted(owners)) + r")\.(\w+)")
    named = {
        f"{m.group(1)}.{m.group(2)}"
        for path in (REPO / "twostep").rglob("*.py")
        for text in _messages(path)
        for m in pattern.finditer(text)
    }
    assert named, "the scan found no message"
    assert named <= set(SETTING_KEYS), named - set(SETTING_KEYS)


def test_worded_replaces_whole_names_only() -> None:
    assert (
        worded("LLMSettings.mode=bundle needs LLMSettings.bundle=<folder of a replay bundle>")
        == "llm.mode=bundle needs llm.bundle=<folder of a replay bundle>"
    )
    assert worded("run offline with GoalSplitDecomposer or LLMSettings.mode=replay.") == (
        "run offline with decomposer=goal-split or llm.mode=replay."
    )
    kept = "MyLLMSettings.mode, x.LLMSettings.model, LLMSettings.models, GoalSplitDecomposers"
    assert worded(kept) == kept
    called = "GoalSplitDecomposer.__init__() got 3 arguments; GoalSplitDecomposer(facts)"
    assert worded(called) == called
    assert worded("set LLMSettings.model.") == "set llm.model."


def test_a_run_s_message_and_reasons_are_worded() -> None:
    run = RunResult(domain="d", task=1, method="twostep", agents=2, seed=0)
    run.message = "LLM call failed: name it with LLMSettings.api_key_env=<VARIABLE>"
    run.subgoals = [{"reason": "set LLMSettings.model"}, {"reason": None}]
    worded_run(run)
    assert run.message == "LLM call failed: name it with llm.api_key_env=<VARIABLE>"
    assert run.subgoals == [{"reason": "set llm.model"}, {"reason": None}]


def test_a_failed_llm_task_s_prefect_state_names_the_key() -> None:
    from flows.prefect_flow import LLM_ERROR_STATE, _llm_call_outcome
    from twostep.llm import LLMCacheMiss

    def miss() -> Any:
        raise LLMCacheMiss("LLMSettings.mode=replay: no cached answer")

    state = _llm_call_outcome(miss)
    assert (state.name, state.message) == (LLM_ERROR_STATE, "llm.mode=replay: no cached answer")


# ----------------------------------------------------------------- through the command line


def _twostep(
    tmp_path: Path, *overrides: str, data: Path = REPO / "data"
) -> tuple[subprocess.CompletedProcess[str], Any]:
    """``twostep`` on blocksworld p01 with N = 2 and an LLM decomposer, no MLflow, no
    Prefect, no API key in the environment; its result.json (None: none written)."""
    out = tmp_path / "out"
    env = {k: v for k, v in os.environ.items() if k != "OPENAI_API_KEY"}
    done = subprocess.run(
        [sys.executable, "-m", "flows.cli", "domain=blocksworld", "task=1", "agents=2",
         "decomposer=llm", f"data.root={data}", f"output.root={out}",
         "mlflow.enabled=false", "orchestration.prefect=false", *overrides],
        capture_output=True, text=True, cwd=REPO, env=env, timeout=240,
    )  # fmt: skip
    results = sorted(out.glob("runs/**/result.json"))
    return done, json.loads(results[0].read_text()) if results else None


@pytest.fixture
def bundle(tmp_path: Path) -> Path:
    """A bundle of one run (gpt-4o's answer for blocksworld p01 at N = 2), imported with
    the task files of ``other/``, whose p01 is data/'s with a comment added."""
    log = tmp_path / "run_2_agent.txt"
    log.write_text(block("blocksworld", 1, ["b3 is clear and on the table."], helper_costs=[2.0]))
    other = tmp_path / "other" / "blocksworld"
    other.mkdir(parents=True)
    original = (REPO / "data" / "blocksworld" / "p01.pddl").read_text()
    (other / "p01.pddl").write_text(original + "\n; another file\n")
    import_logs([log], "gpt-4o", tmp_path / "bundle", tasks=tmp_path / "other")
    return tmp_path / "bundle"


def test_missing_credentials_name_the_keys_in_the_line_and_result(tmp_path: Path) -> None:
    done, result = _twostep(tmp_path, "llm.model=openai/gpt-4o", "llm.use_cache=false")
    said = (
        "LLM credentials missing for model openai/gpt-4o: set the environment variable "
        "OPENAI_API_KEY, or run offline with decomposer=goal-split or llm.mode=replay "
        "(cached answers)."
    )
    assert done.returncode == 1
    assert f"FAILED (llm_error: LLM call failed: generate for agent1: {said})" in done.stdout
    assert result["status"] == "llm_error"
    assert result["message"] == f"LLM call failed: generate for agent1: {said}"
    assert [s["reason"] for s in result["subgoals"]] == [f"LLM call failed: {said}"]


def test_a_replay_miss_names_the_keys(tmp_path: Path) -> None:
    cache = tmp_path / "empty-cache"
    done, result = _twostep(tmp_path, "llm.mode=replay", f"llm.cache_dir={cache}")
    line = done.stderr.strip().splitlines()[-1]
    start = f"error: LLMCacheMiss: llm.mode=replay: no cached answer in {cache} for model "
    start += "openai/gpt-4o, seed 0 (request "
    assert done.returncode == 1
    assert line.startswith(start) and line.endswith("'); record it once with llm.mode=live")
    assert result["message"] == result["error"] == line.removeprefix("error: ")


def test_a_script_missing_names_the_keys(tmp_path: Path) -> None:
    done, result = _twostep(tmp_path, "llm.mode=scripted")
    assert done.returncode == 2
    assert done.stderr.strip().splitlines()[-1] == (
        "error: llm.mode=scripted needs llm.script=<file.yaml>"
    )
    assert result["error"] == "llm.mode=scripted needs llm.script=<file.yaml>"


@pytest.mark.parametrize(
    ("overrides", "code", "expected"),
    [
        (
            ["llm.model=openai/o1-mini"],
            2,
            "error: {bundle} holds no answers of model 'openai/o1-mini' (models: gpt-4o; "
            "set llm.model)",
        ),
        (
            ["llm.model=gpt-4o"],
            2,
            "error: {data}/blocksworld/p01.pddl is not the task file the bundle's answers "
            "for blocksworld/p01 refer to (imported with --tasks): point data.root at the "
            "folder the answers were given for",
        ),
        (
            ["llm.model=gpt-4o", "llm.translator=llm"],
            1,
            "error: LLMBundleMiss: run_2_agent.txt logs no translations of its model "
            "(llm.translator=llm replays them): use llm.translator=rules",
        ),
    ],
    ids=["other model", "other task file", "no translations"],
)
def test_a_bundle_that_cannot_answer_names_the_keys(
    tmp_path: Path, bundle: Path, overrides: list[str], code: int, expected: str
) -> None:
    # the bundle's own task files, but for the case about them
    data = REPO / "data" if "task file" in expected else tmp_path / "other"
    places = {"bundle": bundle, "data": data}
    done, result = _twostep(
        tmp_path, "llm.mode=bundle", f"llm.bundle={bundle}", *overrides, data=data
    )
    assert done.returncode == code, done.stderr
    assert done.stderr.strip().splitlines()[-1] == expected.format(**places)
    assert result["error"] == expected.format(**places).removeprefix("error: ")


def test_an_error_is_worded_as_a_copy_of_its_type() -> None:
    from twostep.llm import LLMCacheMiss

    error = LLMCacheMiss("LLMSettings.mode=replay: no cached answer")
    said = worded_error(error)
    assert type(said) is LLMCacheMiss and str(said) == "llm.mode=replay: no cached answer"
    assert str(error) == "LLMSettings.mode=replay: no cached answer"  # the library's, kept
    plain = LLMCacheMiss("no library name in it")
    assert worded_error(plain) is plain
