"""Shared helpers of the planning tests: planner settings, tasks on disk, and the checks
of a run against the task (the scorer's and unified-planning's)."""

from __future__ import annotations

import shutil
from pathlib import Path

from checkers import IndependentValidator
from tests.conftest import own_task
from tests.examples import CUPS_DOMAIN, CUPS_TASK, TWO_TOWERS
from tests.support.data import make_root
from twostep.methods import RunResult, check_run
from twostep.pddl import Problem
from twostep.planner import PlannerSettings, PlanResult, Status
from twostep.tasks.benchmark import BenchmarkTask, load_task
from twostep.verify.validation import validate_schedule


def agent_predicates_of(domain: str) -> list[str]:
    import yaml

    conf = Path(__file__).parents[2] / "conf" / "domain" / f"{domain}.yaml"
    return list(yaml.safe_load(conf.read_text())["agent_predicates"])


FAST = PlannerSettings("lama-first", 20)


def blocks_task(tmp_path: Path, problem: str = TWO_TOWERS) -> BenchmarkTask:
    root = make_root(tmp_path)
    (root / "blocks" / "p05.pddl").write_text(problem)
    return load_task("blocks", 5, root)


def copy_task(
    tmp_path: Path, data_root: Path, domain: str, problem: str | None = None
) -> BenchmarkTask:
    folder = tmp_path / domain
    folder.mkdir()
    shutil.copy(data_root / domain / "domain.pddl", folder / "domain.pddl")
    (folder / "domain.nl").write_text(domain)
    text = problem if problem is not None else (data_root / domain / "p01.pddl").read_text()
    (folder / "p01.pddl").write_text(text)
    return load_task(domain, 1, tmp_path)


def sa_result(plan: tuple[str, ...]) -> PlanResult:
    return PlanResult(Status.SOLVED, plan, 0.0, 0.0)


def up_validate_run(problem: Problem, run: RunResult, agent_predicates: list[str]) -> None:
    """unified-planning's verdict on the joint schedule, laid out sequentially.

    In the N-agent compilation every action names its agent; actions of one time step do
    not interfere (the scorer's rule), so any order of them is a valid sequential plan.
    """
    verdict = validate_schedule(problem, run.agent_order, run.schedule, agent_predicates)
    assert verdict.valid, verdict.message


def check_valid_run(problem: Problem, run: RunResult, agent_predicates: list[str]) -> None:
    assert run.success
    check_run(problem, run, agent_predicates)
    up_validate_run(problem, run, agent_predicates)


def cups_task(tmp_path: Path) -> BenchmarkTask:
    return own_task(tmp_path, "cups", CUPS_DOMAIN, CUPS_TASK)


def check_valid_task_run(task: BenchmarkTask, run: RunResult, predicates: list[str]) -> None:
    check_run(task.problem, run, predicates)
    verdict = IndependentValidator(task.domain_path, task.problem_path).check_schedule(
        run.agent_order, run.plans, run.schedule, predicates
    )
    assert verdict.valid, verdict
