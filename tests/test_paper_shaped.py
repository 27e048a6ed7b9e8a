"""Our benchmark domains read problems written as the paper's task files write them.

The paper's (LLM+P) blocksworld problems are untyped and name their domain
``blocksworld-4ops`` (its folder has no domain file); its grippers problems name their
domain ``gripper-strips``; its tyreworld problems declare ``wrench``, ``jack`` and ``pump``
as objects, which our tyreworld domain declares as constants. Small problems of that shape
(written here) are read with ``data/<domain>/domain.pddl``, planned, and the plans checked
by the independent validator (unified-planning and Fast Downward's grounding, on the files;
tyreworld: on the problem without the second declaration of the tools, which
unified-planning and Fast Downward both refuse).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from checkers import IndependentValidator
from twostep.pddl import load_problem
from twostep.planner import PlannerSettings, plan

REPO = Path(__file__).resolve().parent.parent

# Two towers, b3 on b1 and b4 on b2; the goal swaps what stands on the bottom blocks.
BLOCKSWORLD = """(define (problem swap-two-tops)
(:domain blocksworld-4ops)
(:objects b1 b2 b3 b4 )
(:init
(arm-empty)
(on-table b1)
(on-table b2)
(on b3 b1)
(on b4 b2)
(clear b3)
(clear b4)
)
(:goal
(and
(on b3 b2)
(on b4 b1))
)
)
"""

GRIPPERS = """(define (problem two-rooms-three-balls)
(:domain gripper-strips)
(:objects robot1 - robot
lgripper1 rgripper1 - gripper
hall yard attic - room
ball1 ball2 ball3 - object)
(:init
(at-robby robot1 hall)
(free robot1 lgripper1)
(free robot1 rgripper1)
(at ball1 hall)
(at ball2 yard)
(at ball3 attic)
)
(:goal
(and
(at ball1 attic)
(at ball2 hall)
(at ball3 yard)
)
)
)
"""

TOOLS = "wrench jack pump - tool\n"

TYREWORLD = f"""(define (problem one-flat)
(:domain tyreworld)
(:objects
{TOOLS}hub-a - hub
nuts-a - nut
trunk - container
spare flat - wheel
)
(:init
(in wrench trunk)
(in jack trunk)
(in pump trunk)
(unlocked trunk)
(closed trunk)
(intact spare)
(in spare trunk)
(not-inflated spare)
(on flat hub-a)
(on-ground hub-a)
(tight nuts-a hub-a)
(fastened hub-a)
)
(:goal
(and
(on spare hub-a)
(inflated spare)
(tight nuts-a hub-a)
(in flat trunk)
(in wrench trunk)
(in jack trunk)
(in pump trunk)
(closed trunk)
)
)
)
"""


@pytest.mark.parametrize(
    ("domain", "text", "as_checked"),
    [
        ("blocksworld", BLOCKSWORLD, BLOCKSWORLD),
        ("grippers", GRIPPERS, GRIPPERS),
        ("tyreworld", TYREWORLD, TYREWORLD.replace(TOOLS, "")),
    ],
)
def test_our_domain_reads_plans_and_validates_a_paper_shaped_problem(
    domain: str, text: str, as_checked: str, tmp_path: Path
) -> None:
    domain_file = REPO / "data" / domain / "domain.pddl"
    (tmp_path / "p01.pddl").write_text(text)
    task = load_problem(domain_file, tmp_path / "p01.pddl")
    result = plan(task, PlannerSettings("lama-first", 20))
    assert result.solved and result.plan, result.message
    (tmp_path / "checked.pddl").write_text(as_checked)
    validator = IndependentValidator(domain_file, tmp_path / "checked.pddl")
    verdict = validator.check_plan(list(result.plan))
    assert verdict.valid, verdict.reason
    assert "unified-planning" in verdict.checkers and "simulator" in verdict.checkers
    # every step matters in these tasks: without its last step the plan is not valid
    assert not validator.check_plan(list(result.plan)[:-1]).valid


def test_the_cross_check_reads_both_domains_and_checks_each_plan_on_the_other(
    tmp_path: Path,
) -> None:
    """bench_heldout --cross on a root in the paper's layout: grippers with our domain as
    "theirs", tyreworld with ours less its constants (the paper's shape: only the problems
    declare the tools), blocksworld without a domain file (read with ours alone)."""
    from evaluation.heldout import cross_check, cross_table

    ours_tyreworld = (REPO / "data" / "tyreworld" / "domain.pddl").read_text()
    theirs_tyreworld = ours_tyreworld.replace("(:constants wrench jack pump - tool)", "")
    assert theirs_tyreworld != ours_tyreworld
    for domain, domain_text, problem in (
        ("grippers", (REPO / "data" / "grippers" / "domain.pddl").read_text(), GRIPPERS),
        ("tyreworld", theirs_tyreworld, TYREWORLD),
    ):
        (tmp_path / domain).mkdir()
        (tmp_path / domain / "domain.pddl").write_text(domain_text)
        (tmp_path / domain / "p01.pddl").write_text(problem)
    (tmp_path / "blocksworld").mkdir()
    (tmp_path / "blocksworld" / "p01.pddl").write_text(BLOCKSWORLD)
    # a problem our blocksworld reads but no plan reaches: b1 cannot be on two blocks
    impossible = BLOCKSWORLD.replace("(on b4 b1))", "(on b1 b3) (on b1 b4))")
    (tmp_path / "blocksworld" / "p02.pddl").write_text(impossible)
    said: list[str] = []
    summary = cross_check(tmp_path, ("blocksworld", "grippers", "tyreworld"), said.append)
    for domain in ("grippers", "tyreworld"):
        counts = summary[domain]
        assert (counts["tasks"], counts["loaded"], counts["plans"]) == (1, 1, 1), said
        assert counts["valid both ways"] == 1, said
        assert counts["checked by: grounded-task simulator + unified-planning"] == 2, said
    blocks = summary["blocksworld"]
    assert (blocks["tasks"], blocks["loaded"], blocks["plans"], blocks["valid ours"]) == (
        2,
        2,
        1,
        1,
    ), said
    assert blocks["checked by: grounded-task simulator + unified-planning"] == 1, said
    assert any(line.startswith("blocksworld p02: no plan on ours domain") for line in said)
    (row,) = [line for line in cross_table(summary) if line.startswith("| blocksworld ")]
    assert "theirs: no domain file" in row


def test_a_data_root_whose_folder_has_tasks_but_no_domain_file_reads_them_with_ours(
    tmp_path: Path,
) -> None:
    # The paper's blocksworld folder ships problems only. A data root in that shape lists
    # the domain, loads its tasks with twostep's own domain file, and a job's inputs name
    # that file; a folder of a domain twostep does not ship stays unknown.
    from flows.identity import job_input_files
    from twostep.tasks.benchmark import (
        DEFAULT_DATA_ROOT,
        BenchmarkError,
        domain_file,
        list_domains,
        load_task,
    )

    (tmp_path / "blocksworld").mkdir()
    (tmp_path / "blocksworld" / "p01.pddl").write_text(BLOCKSWORLD)
    (tmp_path / "sokoban").mkdir()
    (tmp_path / "sokoban" / "p01.pddl").write_text(BLOCKSWORLD)
    ours = DEFAULT_DATA_ROOT / "blocksworld" / "domain.pddl"
    assert domain_file("blocksworld", tmp_path) == ours
    assert list_domains(tmp_path) == ["blocksworld"]
    task = load_task("blocksworld", 1, tmp_path)
    assert task.domain_path == ours and task.problem_path == tmp_path / "blocksworld" / "p01.pddl"
    result = plan(task.problem, PlannerSettings("lama-first", 20))
    assert result.solved and result.plan
    verdict = IndependentValidator(ours, task.problem_path).check_plan(list(result.plan))
    assert verdict.valid, verdict.reason
    config = {"data": {"root": str(tmp_path)}, "domain": {"name": "blocksworld"},
              "method": {"name": "sa"}}  # fmt: skip
    assert job_input_files(config, task.problem_path)["domain"] == ours
    with pytest.raises(BenchmarkError, match="unknown domain 'sokoban'"):
        load_task("sokoban", 1, tmp_path)
    # a folder with its own domain file keeps it
    (tmp_path / "blocksworld" / "domain.pddl").write_text(ours.read_text())
    assert (
        load_task("blocksworld", 1, tmp_path).domain_path
        == tmp_path / "blocksworld" / "domain.pddl"
    )
