"""The rules translator (twostep.english): English subgoals into PDDL goals of a task.

Every expected goal here is written by hand from the task's PDDL (data/<domain>/p01.pddl
and p02.pddl, our own generated tasks) and the sentence; none is copied from the
translator's output. The sentences are phrased as models phrase subgoals, in our words.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from twostep.english import translate_english
from twostep.generators.describe import NOUNS, describe_problem
from twostep.pddl import parse_goal
from twostep.tasks.benchmark import BenchmarkTask, load_task


def task(root: Path, domain: str, number: int = 1) -> BenchmarkTask:
    return load_task(domain, number, root)


def goal(text: str, problem: object) -> tuple[frozenset, frozenset]:
    parsed = parse_goal(text, problem)  # type: ignore[arg-type]
    return parsed.positive, parsed.negative


CASES = [
    # blocksworld p01: b1 on b2, b3 on b1, b2 on the table; the arm is empty (untyped)
    ("blocksworld", 1, "b3 is clear and all hands are empty.", "(and (clear b3) (arm-empty))"),
    ("blocksworld", 1, "b3 is clear and on the table", "(and (clear b3) (on-table b3))"),
    (
        "blocksworld",
        1,
        "b3 should be on top of b2 and the arm is empty",
        "(and (on b3 b2) (arm-empty))",
    ),
    ("blocksworld", 1, "B1 is not on b2.", "(and (not (on b1 b2)))"),
    ("blocksworld", 1, "You are holding b3", "(and (holding b3))"),
    (
        "blocksworld",
        1,
        "block b3 is stacked on b2 and the robot arm is not holding anything",
        "(and (on b3 b2) (arm-empty))",
    ),
    (
        "blocksworld",
        1,
        "All blocks are clear and on the table.",
        "(and (clear b1) (clear b2) (clear b3) (on-table b1) (on-table b2) (on-table b3))",
    ),
    # grippers p01: robot1 (lgripper1, rgripper1) in room1, robot2 (lgripper2, rgripper2)
    # in room2; the balls are untyped objects
    (
        "grippers",
        1,
        "ball1 is in room1 and all grippers are free.",
        "(and (at ball1 room1) (free robot1 lgripper1) (free robot1 rgripper1)"
        " (free robot2 lgripper2) (free robot2 rgripper2))",
    ),
    ("grippers", 1, "Robot1 is in room2.", "(and (at-robby robot1 room2))"),
    ("grippers", 1, "Room1 contains ball1", "(and (at ball1 room1))"),
    (
        "grippers",
        1,
        "robot2 is in room1 and its grippers are free",
        "(and (at-robby robot2 room1) (free robot2 lgripper2) (free robot2 rgripper2))",
    ),
    (
        "grippers",
        1,
        "robot1 carries ball2 in lgripper1 and all other grippers are free",
        "(and (carry robot1 ball2 lgripper1) (free robot1 rgripper1)"
        " (free robot2 lgripper2) (free robot2 rgripper2))",
    ),
    ("grippers", 1, "robot2's left gripper is free", "(and (free robot2 lgripper2))"),
    (
        "grippers",
        1,
        "robot1 is holding ball2 in its right gripper",
        "(and (carry robot1 ball2 rgripper1))",
    ),
    (
        "grippers",
        1,
        "robot2's right gripper holds ball1 and all other grippers are free",
        "(and (carry robot2 ball1 rgripper2) (free robot1 lgripper1) (free robot1 rgripper1)"
        " (free robot2 lgripper2))",
    ),
    ("grippers", 1, "ball2 is at room2", "(and (at ball2 room2))"),
    ("grippers", 1, "(and (at ball2 room2))", "(and (at ball2 room2))"),  # PDDL already
    # barman p01: shaker1..3, shot1..4, hands left and right
    (
        "barman",
        1,
        "shotglass4 contains ingredient3 and all hands are empty.",
        "(and (contains shot4 ingredient3) (handempty left) (handempty right))",
    ),
    (
        "barman",
        1,
        "shaker2 contains ingredient1 and ingredient2 and both hands are free",
        "(and (contains shaker2 ingredient1) (contains shaker2 ingredient2)"
        " (handempty left) (handempty right))",
    ),
    ("barman", 1, "shot glass 2 is clean and on the table", "(and (clean shot2) (ontable shot2))"),
    ("barman", 1, "The right hand holds shaker3.", "(and (holding right shaker3))"),
    (
        "barman",
        1,
        "shot1 contains ingredient2 and the robot is not holding anything",
        "(and (contains shot1 ingredient2) (handempty left) (handempty right))",
    ),
    (
        "barman",
        1,
        "the left and right hands hold nothing",
        "(and (handempty left) (handempty right))",
    ),
    ("barman", 1, "shot3 does not contain ingredient1", "(and (not (contains shot3 ingredient1)))"),
    # tyreworld p01: one hub, one nut, flat tyre w1 on it, intact tyre r1 in the boot
    ("tyreworld", 1, "The intact tyre is inflated and all hands are empty.", "(and (inflated r1))"),
    (
        "tyreworld",
        1,
        "The hub1 has an inflated intact tyre and the nuts on hub1 are tight.",
        "(and (on r1 the-hub1) (inflated r1) (tight nuts1 the-hub1))",
    ),
    ("tyreworld", 1, "The flat tyre is removed from the hub.", "(and (not (on w1 the-hub1)))"),
    ("tyreworld", 1, "the intact tyre is placed on the hub", "(and (on r1 the-hub1))"),
    (
        "tyreworld",
        1,
        "The boot is open and the jack is out and ready to use",
        "(and (opened boot) (have jack))",
    ),
    # tyreworld p02: nine hubs; the goal puts r_i on the-hub_i
    (
        "tyreworld",
        2,
        "The hub2 has an inflated intact tyre and the nut2 is tight on the hub2. All hands are empty.",
        "(and (on r2 the-hub2) (inflated r2) (tight nuts2 the-hub2))",
    ),
    (
        "tyreworld",
        2,
        "The third hub has an inflated intact tyre, the nut on the third hub is tight",
        "(and (on r3 the-hub3) (inflated r3) (tight nuts3 the-hub3))",
    ),
    (
        "tyreworld",
        2,
        "The flat tyres, wrench and pump are in the boot and the boot is closed",
        "(and (in w1 boot) (in w2 boot) (in w3 boot) (in w4 boot) (in w5 boot) (in w6 boot)"
        " (in w7 boot) (in w8 boot) (in w9 boot) (in wrench boot) (in pump boot) (closed boot))",
    ),
]


@pytest.mark.parametrize("domain, number, sentence, expected", CASES)
def test_reads_what_models_write(
    data_root: Path, domain: str, number: int, sentence: str, expected: str
) -> None:
    problem = task(data_root, domain, number).problem
    translation = translate_english(problem, sentence, domain)
    assert translation.ok, translation.reason
    assert translation.pddl is not None
    assert goal(translation.pddl, problem) == goal(expected, problem)


@pytest.mark.parametrize(
    "domain, number, sentence, reason",
    [
        # an object the task does not have
        ("blocksworld", 1, "b7 is clear and all hands are empty", "no phrase"),
        # wording no phrase of the domain has
        ("tyreworld", 1, "The nut is loosened from the hub", "no phrase"),
        # an argument of the wrong type: dispensers do not contain anything
        ("barman", 1, "dispenser1 contains ingredient2", "cannot be argument 1 of contains"),
        # nine flat tyres: which one?
        ("tyreworld", 2, "the flat tyre is in the boot", "ambiguous"),
        # a gripper is no room, and which gripper is not said
        ("grippers", 1, "ball1 is in the gripper of robot1", "cannot be argument 2 of at"),
        # says a fact and its negation
        ("blocksworld", 1, "b3 is clear and b3 is not clear", "its negation"),
        # only the agent's state, in a domain that has none
        ("tyreworld", 1, "All hands are empty.", "names no condition"),
        ("blocksworld", 1, "", "empty"),
    ],
)
def test_what_it_cannot_read_is_a_failure_with_the_reason(
    data_root: Path, domain: str, number: int, sentence: str, reason: str
) -> None:
    translation = translate_english(task(data_root, domain, number).problem, sentence, domain)
    assert translation.pddl is None
    assert translation.reason is not None and reason in translation.reason


def test_a_release_phrase_adds_nothing_where_there_is_no_agent_state(data_root: Path) -> None:
    problem = task(data_root, "tyreworld").problem
    translation = translate_english(
        problem, "the boot is closed and all hands are empty", "tyreworld"
    )
    assert translation.pddl == "(and (closed boot))"
    assert any("no agent state" in note for note in translation.notes)


def test_real_world_pddl_as_the_llmp_files_are(quirks_root: Path) -> None:
    """LLM+P's tyreworld: tools only the problem declares, actions named like predicates."""
    problem = load_task("tyreworld", 1, quirks_root).problem
    translation = translate_english(problem, "the wrench is in the boot", "tyreworld")
    assert translation.pddl == "(and (in wrench boot))"


def test_the_nouns_are_the_describers_words(data_root: Path) -> None:
    """Every noun the translator knows names objects the domain's describer lists under
    that noun in the task's description (the same words, the same objects)."""
    for domain in ("barman", "blocksworld", "grippers", "tyreworld"):
        problem = task(data_root, domain, 2).problem
        text = describe_problem(problem, domain)
        for noun in NOUNS[domain]:
            members = noun.select(problem)
            if noun.singular in (
                "left gripper",
                "right gripper",
                "tyre",
                "wheel",
                "container",
                "hand",
                "cocktail",
            ):
                continue  # not listed by these words in the text (the describer says it otherwise)
            assert members, (domain, noun.singular)
            word = noun.plural if len(members) > 1 else noun.singular
            assert word in text, (domain, word)
            for name in members:
                assert name in text
