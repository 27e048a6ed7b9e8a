"""bench/bench_heldout.py: an LLM+P checkout laid out as a data root (checked by Fast
Downward and unified-planning on the files it writes), and bench_methods'
``--agent-predicates`` for a domain conf/domain/ does not have.

The LLM+P files themselves are not in the repository: the layout here is made by hand, in
LLM+P's shape (untyped blocksworld problems naming ``blocksworld-4ops``, no domain file:
the layout gives them ours, untyped and named so too).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from checkers import IndependentValidator, fast_downward
from evaluation import methods as runs
from evaluation.heldout import heldout_predicates, prepare, validate
from tests.conftest import DATA

# Two blocks on the table, b1 to go on b2: two steps for any planner (pick up, stack).
UNTYPED_PROBLEM = """(define (problem BW-rand-2)
(:domain blocksworld-4ops)
(:objects b1 b2 )
(:init (arm-empty) (on-table b1) (on-table b2) (clear b1) (clear b2))
(:goal (and (on b1 b2))))
"""


def typed_blocks(domain: str) -> str:
    """``domain`` with every predicate and action parameter of a type ``block``."""
    head, actions = domain.split("(:action", 1)  # the predicates come before the actions

    def typed(variables: str) -> str:
        return re.sub(r"(\?[\w-]+)", r"\1 - block", variables)

    head = re.sub(r"\(:predicates.*", lambda m: typed(m.group(0)), head, flags=re.DOTALL)
    head = head.replace("(:requirements :strips)", "(:requirements :strips :typing) (:types block)")
    params = re.sub(r":parameters \(([^)]*)\)", lambda m: f":parameters ({typed(m[1])})", actions)
    return f"{head}(:action{params}"


def _llmp(tmp_path: Path) -> Path:
    """A checkout in LLM+P's layout: blocksworld without a domain file, grippers with one."""
    root = tmp_path / "llm-pddl" / "domains"
    (root / "blocksworld").mkdir(parents=True)
    (root / "blocksworld" / "p01.pddl").write_text(UNTYPED_PROBLEM)
    (root / "blocksworld" / "p_example.pddl").write_text(UNTYPED_PROBLEM)  # not a task
    (root / "grippers").mkdir()
    for name in ("domain.pddl", "p01.pddl"):
        shutil.copyfile(DATA / "grippers" / name, root / "grippers" / name)
    return root.parent


def test_our_blocksworld_reads_the_untyped_problems(tmp_path: Path) -> None:
    out = tmp_path / "data"
    assert prepare(_llmp(tmp_path), out, ("blocksworld", "grippers")) == {
        "blocksworld": 1,
        "grippers": 1,
    }
    domain, problem = out / "blocksworld" / "domain.pddl", out / "blocksworld" / "p01.pddl"
    assert problem.read_text() == UNTYPED_PROBLEM  # copied as it is
    text = domain.read_text()
    assert text == (DATA / "blocksworld" / "domain.pddl").read_text()  # ours, as it is
    assert "(domain blocksworld-4ops)" in text and " - " not in text and ":typing" not in text
    # Fast Downward plans on the written files, unified-planning and its translation accept
    run = fast_downward.plan(domain, problem, time_limit_s=10)
    assert run.plan is not None and len(run.plan) == 2
    assert IndependentValidator(domain, problem).check_plan(run.plan).valid
    # the same domain with a type 'block' gives the untyped objects no action: no plan
    typed = tmp_path / "typed.pddl"
    typed.write_text(typed_blocks(text))
    assert typed.read_text().count(" - block") == 11  # 5 predicate and 6 action parameters
    assert fast_downward.plan(typed, problem, time_limit_s=10).plan is None


def test_a_problem_naming_another_domain_is_an_error(tmp_path: Path) -> None:
    llmp = _llmp(tmp_path)
    problem = llmp / "domains" / "blocksworld" / "p01.pddl"
    problem.write_text(UNTYPED_PROBLEM.replace("blocksworld-4ops", "blocks"))
    with pytest.raises(ValueError, match=r"names domain blocks, .* is blocksworld-4ops"):
        prepare(llmp, tmp_path / "data", ("blocksworld",))


def test_a_domain_without_its_domain_file_is_an_error(tmp_path: Path) -> None:
    llmp = _llmp(tmp_path)
    (llmp / "domains" / "grippers" / "domain.pddl").unlink()
    with pytest.raises(FileNotFoundError, match=r"no domain\.pddl"):
        prepare(llmp, tmp_path / "data", ("grippers",))


def test_agent_predicates_given_for_a_domain_conf_does_not_have(tmp_path: Path) -> None:
    # grippers under another name: conf/domain/ has no "grips", so the run reads the given
    # predicates (without them it cannot start)
    (tmp_path / "grips").mkdir()
    for name in ("domain.pddl", "p01.pddl"):
        shutil.copyfile(DATA / "grippers" / name, tmp_path / "grips" / name)
    job = runs.Job(str(tmp_path), str(tmp_path), "grips", 1, (1, 2), ("plan-deal",), "lama-first",
                 10.0, True, (), ("at-robby", "free", "carry"))  # fmt: skip
    rows = {(r["method"], r["agents"]): r for r in runs.run_job(job)}
    assert rows[("sa", 1)]["valid"] and rows[("plan-deal", 2)]["valid"]
    assert rows[("plan-deal", 2)]["exec_length"] < rows[("sa", 1)]["exec_length"]
    with pytest.raises(FileNotFoundError):
        runs.run_job(runs.Job(str(tmp_path), str(tmp_path), "grips", 1, (1, 2), ("plan-deal",),
                          "lama-first", 10.0, True, ()))  # fmt: skip


def test_validate_deals_the_stored_sa_plans_and_checks_them_apart(tmp_path: Path) -> None:
    out = tmp_path / "data"
    prepare(_llmp(tmp_path), out, ("blocksworld", "grippers"))
    hand = ["(pick robot1 ball2 room1 lgripper1)", "(move robot1 room1 room2)",
            "(drop robot1 ball2 room2 lgripper1)", "(pick robot1 ball1 room2 lgripper1)",
            "(move robot1 room2 room1)", "(drop robot1 ball1 room1 lgripper1)"]  # fmt: skip
    rows = [
        {"method": "sa", "valid": True, "domain": "blocksworld", "task": 1,
         "plan": ["(pickup b1)", "(stack b1 b2)"]},
        {"method": "sa", "valid": True, "domain": "grippers", "task": 1, "plan": hand},
        {"method": "sa", "valid": False, "domain": "grippers", "task": 2, "plan": None},
    ]  # fmt: skip
    counts = validate(out, rows, (2, 3))
    assert counts["valid"] == 4 and counts["not valid"] == 0
    assert counts["checked by: grounded-task simulator + unified-planning"] == 4
    assert heldout_predicates("grippers") == ["at-robby", "free", "carry"]
    assert heldout_predicates("storage") == ["at", "available", "lifting"]
