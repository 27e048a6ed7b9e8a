"""Our benchmark domains read problems written as the paper's task files write them.

The paper's (LLM+P) grippers problems name their domain ``gripper-strips``; its tyreworld
problems declare ``wrench``, ``jack`` and ``pump`` as objects, which our tyreworld domain
declares as constants. Small problems of that shape (written here) are read with
``data/grippers/domain.pddl`` and ``data/tyreworld/domain.pddl``, planned, and the plans
checked by the independent validator (unified-planning and Fast Downward's grounding, on
the files; tyreworld: on the problem without the second declaration of the tools, which
unified-planning and Fast Downward both refuse).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.independent import IndependentValidator
from twostep.pddl import load_problem
from twostep.planner import PlannerSettings, plan

REPO = Path(__file__).resolve().parent.parent

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
