"""twostep.planner: statuses, plans that validate, the quirky real-world files."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.benchmark import load_task
from twostep.pddl import parse_problem
from twostep.planner import PlannerSettings, Status, plan
from twostep.strips import Grounder, simulate
from twostep.validation import validate_plan

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
