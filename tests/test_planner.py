"""twostep.planner: statuses, plans that validate, the quirky real-world files."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from tests.examples import DRIVE_OR_FLY, DRIVE_OR_FLY_PROBLEM, ROAD_COSTS
from twostep.pddl import parse_problem
from twostep.planner import (
    PlannerSettings,
    PlanResult,
    Status,
    plan,
    plan_pddl,
    read_plan_file,
    returncodes,
)
from twostep.planner import driver as planner_driver
from twostep.plans.simulate import Grounder, simulate
from twostep.tasks.benchmark import load_task
from twostep.verify.validation import validate_plan

TOWER = blocks_problem(
    "(on-table a) (on b a) (on c b) (clear c) (on-table d) (clear d) (arm-empty)",
    "(on a b) (on b c) (on c d)",
)


def test_lama_first_solves_and_plan_validates() -> None:
    problem = parse_problem(BLOCKS_DOMAIN, TOWER)
    result = plan(problem, PlannerSettings("lama-first", 10))
    assert result.status is Status.SOLVED and result.plan
    assert result.cost == len(result.plan)
    assert 0 < result.planner_time_s <= result.wall_time_s + 0.05
    assert validate_plan(problem, result.plan).valid
    assert problem.goal.holds(simulate(problem.init, Grounder(problem).ground_plan(result.plan)))


def test_anytime_lama_keeps_the_best_plan() -> None:
    problem = parse_problem(BLOCKS_DOMAIN, TOWER)
    first = plan(problem, PlannerSettings("lama-first", 10))
    best = plan(problem, PlannerSettings("lama", 5))
    assert best.status is Status.SOLVED and best.plan is not None and first.plan is not None
    assert best.plans_found >= 1
    assert len(best.plan) <= len(first.plan)
    assert validate_plan(problem, best.plan).valid


def test_goal_already_true_gives_empty_plan() -> None:
    problem = parse_problem(
        BLOCKS_DOMAIN, blocks_problem("(on-table a) (clear a) (arm-empty)", "(on-table a)")
    )
    result = plan(problem)
    assert result.status is Status.SOLVED and result.plan == () and result.cost == 0


def test_unsolvable_is_a_status() -> None:
    problem = parse_problem(
        BLOCKS_DOMAIN, blocks_problem("(on-table a) (clear a)", "(on-table b)", "a b")
    )
    result = plan(problem, PlannerSettings("lama-first", 10))
    assert result.status is Status.UNSOLVABLE and result.plan is None
    assert result.exit_code in (10, 11, 12)


def test_wall_clock_guard_gives_timeout_status() -> None:
    problem = parse_problem(BLOCKS_DOMAIN, TOWER)
    result = plan(problem, PlannerSettings("lama-first", 10, wall_time_limit_s=0.01))
    assert result.status is Status.TIMEOUT and result.plan is None and result.exit_code is None
    assert result.guard_stopped and result.to_dict()["guard_stopped"] is True
    finished = plan(problem, PlannerSettings("lama-first", 10))
    assert finished.solved and finished.exit_code == 0 and not finished.guard_stopped


def test_unknown_alias_is_an_error_status() -> None:
    problem = parse_problem(BLOCKS_DOMAIN, TOWER)
    result = plan(problem, PlannerSettings("lama-fast"))
    assert result.status is Status.ERROR and "lama-first" in result.message


def test_quirky_real_world_files_plan_and_validate(quirks_root: Path) -> None:
    task = load_task("tyreworld", 1, quirks_root)
    result = plan(task.problem, PlannerSettings("lama-first", 20))
    assert result.status is Status.SOLVED and result.plan is not None
    assert any(step.startswith("(open ") for step in result.plan)
    assert validate_plan(task.problem, result.plan).valid


# ------------------------------------------------ exit codes and plan files (fake driver)


def _fake_driver(tmp_path: Path, exit_code: int, files: dict[str, str]) -> Path:
    """A stand-in for fast-downward.py: writes ``files`` into its cwd and exits."""
    script = tmp_path / "fake-fast-downward.py"
    script.write_text(
        textwrap.dedent(
            f"""
            import json, pathlib, sys
            for name, text in json.loads({json.dumps(json.dumps(files))}).items():
                pathlib.Path(name).write_text(text)
            print("Planner time: 0.25s")
            sys.exit({exit_code})
            """
        )
    )
    return script


def _run_fake(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, code: int, files: dict[str, str]
) -> PlanResult:
    script = _fake_driver(tmp_path, code, files)
    monkeypatch.setattr(planner_driver, "driver_path", lambda: script)
    problem = parse_problem(BLOCKS_DOMAIN, TOWER)
    return plan(problem, PlannerSettings("lama", 5))


COMPLETE = "(unstack c b)\n(putdown c)\n; cost = 2 (unit cost)\n"
TRUNCATED = "(unstack c b)\n(putdo"


def test_exhausted_incomplete_search_is_not_reported_unsolvable(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    incomplete = _run_fake(tmp_path, monkeypatch, returncodes.SEARCH_UNSOLVED_INCOMPLETE, {})
    unsolvable = _run_fake(tmp_path, monkeypatch, returncodes.SEARCH_UNSOLVABLE, {})
    assert incomplete.status is Status.INCOMPLETE and incomplete.status.value == "incomplete"
    assert incomplete.exit_code == 12 and incomplete.plan is None
    assert unsolvable.status is Status.UNSOLVABLE and unsolvable.exit_code == 11
    assert incomplete.message != unsolvable.message


def test_truncated_plan_file_is_not_trusted(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The search was stopped mid-write: a time-out with a cut-off plan is no plan.
    timed_out = _run_fake(
        tmp_path, monkeypatch, returncodes.SEARCH_OUT_OF_TIME, {"plan.1": TRUNCATED}
    )
    assert timed_out.status is Status.TIMEOUT and timed_out.plan is None
    assert timed_out.plans_found == 0 and "incomplete plan file" in timed_out.message
    # Exit 0 without a complete plan file is a planner error, not a solution.
    success = _run_fake(tmp_path, monkeypatch, returncodes.SUCCESS, {"plan": TRUNCATED})
    assert success.status is Status.ERROR and success.plan is None


def test_anytime_run_keeps_the_last_complete_plan(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    longer = "(unstack c b)\n(stack c d)\n(unstack c d)\n(putdown c)\n; cost = 4 (unit cost)\n"
    files = {"plan.1": longer, "plan.2": COMPLETE, "plan.3": TRUNCATED}
    result = _run_fake(tmp_path, monkeypatch, returncodes.SEARCH_OUT_OF_TIME, files)
    assert result.status is Status.SOLVED
    assert result.plan == ("(unstack c b)", "(putdown c)") and result.cost == 2
    assert result.plans_found == 2 and result.planner_time_s == 0.25


def test_read_plan_file_needs_the_cost_trailer_with_its_newline(tmp_path: Path) -> None:
    path = tmp_path / "plan"
    path.write_text("(fly a d)\n; cost = 12 (general cost)\n")
    complete = read_plan_file(path)
    assert complete is not None
    assert (complete.actions, complete.cost, complete.general_cost) == (("(fly a d)",), 12, True)
    for cut in (
        "(fly a d)\n",
        "(fly a d)\n; cost = 12 (general",
        "(fly a d)\n; cost = 12 (general cost)",
        "",
    ):
        path.write_text(cut)
        assert read_plan_file(path) is None, cut


# ------------------------------------------------------------------ action costs


def test_domain_with_action_costs_gives_the_plan_cost() -> None:
    problem = parse_problem(DRIVE_OR_FLY, DRIVE_OR_FLY_PROBLEM)
    # By hand: fly a->d costs 12; driving a->b->c->d costs 3 * 5 = 15; any mix costs more.
    optimal = plan(problem, PlannerSettings("seq-opt-lmcut", 10))
    assert optimal.status is Status.SOLVED
    assert optimal.plan == ("(fly a d)",) and optimal.cost == 12
    first = plan(problem, PlannerSettings("lama-first", 10))
    assert first.status is Status.SOLVED and first.plan is not None
    assert first.cost == sum(ROAD_COSTS[step[1:].split()[0]] for step in first.plan)
    assert validate_plan(problem, first.plan).valid


def test_unit_cost_domain_cost_is_the_plan_length_from_the_trailer() -> None:
    problem = parse_problem(BLOCKS_DOMAIN, TOWER)
    result = plan_pddl(*planner_driver.planner_input(problem), PlannerSettings("lama-first", 10))
    assert result.status is Status.SOLVED and result.plan is not None
    assert result.cost == len(result.plan) > 0
