"""Tests for the twostep-score command line (twostep.cli.score)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.examples import BLOCKSWORLD as DOMAIN
from tests.examples import STAGGERED, TRACKS, two_hub_tracks_text
from twostep.cli.score import EXIT_BAD_INPUT, EXIT_INVALID_PLANS, EXIT_VALID, main

PROBLEM = """
(define (problem three) (:domain blocksworld)
 (:objects b1 b2 b3)
 (:init (clear b1) (clear b2) (clear b3) (ontable b1) (ontable b2) (ontable b3) (arm-empty))
 (:goal (and (on b1 b2) (on b3 b1))))
"""

HELPER = "(pickup b1)\n(stack b1 b2)\n; cost = 2 (unit cost)\n"
MAIN = "(pickup b3)\n(stack b3 b1)\n; cost = 2 (unit cost)\n"


@pytest.fixture
def files(tmp_path: Path) -> dict[str, str]:
    contents = {
        "domain": DOMAIN,
        "problem": PROBLEM,
        "helper": HELPER,
        "main": MAIN,
        "bad_main": "(pickup b3)\n(stack b3 b2)\n",
        "unknown_action": "(fly b1)\n",
    }
    paths = {}
    for name, text in contents.items():
        path = tmp_path / f"{name}.txt"
        path.write_text(text)
        paths[name] = str(path)
    return paths


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_valid_plans_print_length_and_schedule(
    files: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [files["domain"], files["problem"], files["helper"], files["main"]]
    code, out, err = run([*argv, "--agent-predicates", "arm-empty,holding"], capsys)
    assert code == EXIT_VALID
    assert err == ""
    assert json.loads(out) == {
        "exec_length": 3,
        "schedule": [
            [["agent0", "(pickup b1)"], ["agent1", "(pickup b3)"]],
            [["agent0", "(stack b1 b2)"]],
            [["agent1", "(stack b3 b1)"]],
        ],
        "valid": True,
        "exact": True,
        "lower_bound": 3,
        "gap": 0,
    }
    # Without agent predicates the arm is shared and nothing runs in parallel.
    code, out, _ = run(argv, capsys)
    assert (code, json.loads(out)["exec_length"]) == (EXIT_VALID, 4)


def test_paper_mode(files: dict[str, str], capsys: pytest.CaptureFixture[str]) -> None:
    argv = [files["domain"], files["problem"], files["helper"], files["main"], "--mode", "paper"]
    code, out, _ = run([*argv, "--agent-predicates", "arm-empty, holding"], capsys)
    assert (code, json.loads(out)["exec_length"]) == (EXIT_VALID, 3)


def test_inapplicable_plan_names_agent_step_and_precondition(
    files: dict[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [files["domain"], files["problem"], files["helper"], files["bad_main"]]
    code, out, err = run([*argv, "--agent-predicates", "arm-empty,holding"], capsys)
    assert code == EXIT_INVALID_PLANS
    result = json.loads(out)
    assert (result["valid"], result["exec_length"], result["schedule"]) == (False, None, [])
    assert err.count("\n") == 1
    assert "agent1" in err
    assert "step 2 (stack b3 b2)" in err
    assert "precondition (clear b2) does not hold" in err


def test_malformed_pddl_exits_2_without_traceback(
    files: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    broken = tmp_path / "broken.pddl"
    broken.write_text(PROBLEM.replace("(ontable b3)", "(ontable b3"))
    code, out, err = run([files["domain"], str(broken), files["helper"]], capsys)
    assert code == EXIT_BAD_INPUT
    assert out == ""
    assert err.count("\n") == 1
    assert "broken.pddl" in err
    assert "Traceback" not in err


def test_bad_plan_line_exits_2(files: dict[str, str], capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(
        [files["domain"], files["problem"], files["helper"], files["unknown_action"]], capsys
    )
    assert code == EXIT_BAD_INPUT
    assert out == ""
    assert "unknown_action.txt" in err
    assert "unknown action 'fly'" in err


def test_missing_plan_file_and_unknown_predicate_exit_2(
    files: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = str(tmp_path / "nowhere.plan")
    code, _, err = run([files["domain"], files["problem"], missing], capsys)
    assert code == EXIT_BAD_INPUT
    assert "nowhere.plan" in err
    code, _, err = run(
        [files["domain"], files["problem"], files["helper"], "--agent-predicates", "arm-empy"],
        capsys,
    )
    assert code == EXIT_BAD_INPUT
    assert "unknown agent predicate(s) arm-empy" in err


def test_runs_as_a_module(files: dict[str, str]) -> None:
    completed = subprocess.run(
        [
            sys.executable,
            "-m",
            "twostep.cli.score",
            files["domain"],
            files["problem"],
            files["helper"],
            files["main"],
            "--agent-predicates",
            "arm-empty,holding",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert completed.returncode == EXIT_VALID, completed.stderr
    assert json.loads(completed.stdout)["exec_length"] == 3


def test_parsed_tasks_are_cached_by_content(
    files: dict[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cache = tmp_path / "cache"
    argv = [files["domain"], files["problem"], files["helper"], files["main"]]
    argv += ["--agent-predicates", "arm-empty,holding", "--cache-dir", str(cache)]
    code, first, _ = run(argv, capsys)
    assert code == EXIT_VALID and len(list(cache.iterdir())) == 1
    code, again, _ = run(argv, capsys)
    assert (code, again) == (EXIT_VALID, first)  # read back from the cache: same answer
    # An edited goal is a new entry, never the stale one: the same plans no longer reach it.
    edited = Path(files["problem"]).read_text().replace("(on b3 b1)", "(on b2 b3)")
    Path(files["problem"]).write_text(edited)
    code, _, err = run(argv, capsys)
    assert code == EXIT_INVALID_PLANS and "(on b2 b3)" in err
    assert len(list(cache.iterdir())) == 2
    nocache = tmp_path / "unused"
    run([*argv[:-2], "--cache-dir", str(nocache), "--no-cache"], capsys)
    assert not nocache.exists()


def test_budget_options_and_a_stated_gap(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text, plans = two_hub_tracks_text(STAGGERED, 14)
    (tmp_path / "domain.pddl").write_text(TRACKS)
    (tmp_path / "problem.pddl").write_text(text)
    argv = [str(tmp_path / "domain.pddl"), str(tmp_path / "problem.pddl")]
    for cart, plan in enumerate(plans):
        (tmp_path / f"cart{cart}.plan").write_text("\n".join(plan) + "\n")
        argv.append(str(tmp_path / f"cart{cart}.plan"))
    argv += ["--agent-predicates", "ready", "--no-cache"]
    code, out, err = run([*argv, "--max-nodes", "none", "--time-limit", "none"], capsys)
    full = json.loads(out)
    assert (code, full["exact"], full["gap"], err) == (EXIT_VALID, True, 0, "")
    assert full["lower_bound"] == full["exec_length"]
    # No search at all: a valid schedule whose optimality is not proven, and says so.
    code, out, err = run([*argv, "--max-nodes", "0", "--time-limit", "none"], capsys)
    cut = json.loads(out)
    assert code == EXIT_VALID and cut["valid"] and not cut["exact"]
    assert cut["lower_bound"] < full["exec_length"] <= cut["exec_length"]
    assert cut["gap"] == cut["exec_length"] - cut["lower_bound"]
    assert f"proven lower bound {cut['lower_bound']} (gap {cut['gap']})" in err
    with pytest.raises(SystemExit) as exited:
        main([*argv, "--max-nodes", "-3"])
    assert exited.value.code == EXIT_BAD_INPUT
    assert "must be >= 0" in capsys.readouterr().err
