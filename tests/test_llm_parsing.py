"""Reading LLM answers: the English condition, the PDDL goal, and the checks on both."""

from __future__ import annotations

import pytest

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.llm.parsing import (
    SubgoalError,
    extract_pddl_goal,
    parse_english_subgoal,
    parse_pddl_subgoal,
)
from twostep.pddl import Goal, Problem, parse_goal, parse_problem
from twostep.plans.subgoals import goal_conflict

INIT = "(arm-empty) (on-table a) (on-table c) (on b c) (clear a) (clear b)"


@pytest.fixture(scope="module")
def problem() -> Problem:
    return parse_problem(BLOCKS_DOMAIN, blocks_problem(INIT, "(on a b) (on c a)", "a b c"))


# ------------------------------------------------------------------ English


@pytest.mark.parametrize(
    "answer, condition",
    [
        (
            "It can unstack b from c and put it down. Therefore, agent1's clearly stated "
            "(with object names) complete and final goal condition is: b is on the table "
            "and the arm is empty.",
            "b is on the table and the arm is empty",
        ),
        ("**Final goal condition:** c is clear.\n\nThat's all.", "c is clear"),
        (
            "Final goal condition is:\n  a is clear and the arm is empty",
            "a is clear and the arm is empty",
        ),
        (
            "agent1: I would move b. The subgoal condition is: b is on the table",
            "b is on the table",
        ),
    ],
)
def test_condition_after_the_marker(answer: str, condition: str, problem: Problem) -> None:
    parsed = parse_english_subgoal(answer, 1, problem)
    assert (parsed.kind, parsed.text, parsed.note) == ("subgoal", condition, None)


def test_condition_for_the_asked_helper_when_several_are_given(problem: Problem) -> None:
    answer = (
        "agent1's final goal condition is: b is on the table.\n"
        "agent2's final goal condition is: c is clear and the arm is empty.\n"
        "agent3's final goal condition is: a is on c."
    )
    assert parse_english_subgoal(answer, 2, problem).text == "c is clear and the arm is empty"
    assert parse_english_subgoal(answer, 1, problem).text == "b is on the table"
    assert parse_english_subgoal(answer, 5, problem).text == "b is on the table"


def test_last_sentence_without_marker(problem: Problem) -> None:
    parsed = parse_english_subgoal("I would help. In the end b is on the table.", 1, problem)
    assert parsed.text == "In the end b is on the table"
    assert parsed.note and "last sentence" in parsed.note


@pytest.mark.parametrize(
    "answer",
    [
        "none",
        "None.",
        '"none"',
        "**None**",
        "agent2: none",
        "Final goal condition is: none.",
        "None. No further helper would make the task finish sooner.",
        "agent2: None - the main agent alone is fastest.",
    ],
)
def test_none(answer: str, problem: Problem) -> None:
    assert parse_english_subgoal(answer, 2, problem).kind == "none"


def test_none_of_is_not_none(problem: Problem) -> None:
    answer = "None of the blocks blocks b. Final goal condition is: b is on the table."
    assert parse_english_subgoal(answer, 1, problem).text == "b is on the table"
    assert parse_english_subgoal("None of the blocks is on b.", 1, problem).kind == "subgoal"


@pytest.mark.parametrize(
    "answer, reason",
    [
        ("", "empty answer"),
        ("   \n ", "empty answer"),
        ("The helpers should cooperate closely to speed things up!", "no final goal condition"),
        ("Final goal condition is:", "states none"),
    ],
)
def test_english_without_condition(answer: str, reason: str, problem: Problem) -> None:
    with pytest.raises(SubgoalError, match=reason):
        parse_english_subgoal(answer, 1, problem)


# ------------------------------------------------------------------ PDDL


@pytest.mark.parametrize(
    "answer, expected",
    [
        ("(:goal (and (on-table b) (arm-empty)))", "(:goal (and (on-table b) (arm-empty)))"),
        ("```pddl\n(:goal\n (and\n  (on-table b)))\n```", "(:goal\n (and\n  (on-table b)))"),
        (
            "Here it is:\n(and (on-table b) (clear c))\nThis puts b down.",
            "(and (on-table b) (clear c))",
        ),
        ("(on-table b) (arm-empty)\nDone.", "(on-table b) (arm-empty)"),
        ("(:goal (and (on-table b) (arm-empty))))))", "(:goal (and (on-table b) (arm-empty)))"),
        ("(:goal (and (on-table b) (arm-empty)", "(:goal (and (on-table b) (arm-empty)))"),
        ("```\n(:goal (and (on-table b)))\n", "(:goal (and (on-table b)))"),
        ("no parens here", None),
    ],
)
def test_extract_pddl_goal(answer: str, expected: str | None) -> None:
    assert extract_pddl_goal(answer) == expected


def test_extract_prefers_the_goal_of_a_full_problem() -> None:
    answer = "(define (problem x) (:domain blocks) (:init (clear a)) (:goal (and (clear b))))"
    assert extract_pddl_goal(answer) == "(:goal (and (clear b)))"


def test_parse_pddl_subgoal(problem: Problem) -> None:
    goal = parse_pddl_subgoal("```lisp\n(:goal (and (ON-TABLE b) (arm-empty)))\n```", problem)
    assert goal == Goal(frozenset({("on-table", "b"), ("arm-empty",)}))


@pytest.mark.parametrize(
    "answer, reason",
    [
        ("", "empty answer from the translator"),
        ("I cannot translate that.", "no PDDL goal"),
        ("(:goal (and (on-floor b)))", "unknown predicate 'on-floor'"),
        ("(:goal (and (on-table z)))", "unknown object 'z'"),
        ("(:goal (and (on a)))", "'on' takes 2 argument"),
        ("(:goal (and (on-table ?x)))", "unknown object '\\?x'"),
        ("(:goal (or (on-table a) (clear a)))", "not a ground literal"),
        ("(:goal (and))", "the goal is empty"),
        ("(:goal (and (clear a) (not (clear a))))", "a fact and its negation"),
    ],
)
def test_bad_pddl(answer: str, reason: str, problem: Problem) -> None:
    with pytest.raises(SubgoalError, match=reason):
        parse_pddl_subgoal(answer, problem)


def test_check_subgoal(problem: Problem) -> None:
    full = problem.goal
    assert goal_conflict(parse_goal("(and (on c a) (on a b))", problem), full) == (
        "equals the full goal"
    )
    assert "includes the full goal" in str(
        goal_conflict(parse_goal("(and (on c a) (on a b) (arm-empty))", problem), full)
    )
    reason = goal_conflict(parse_goal("(and (not (on a b)) (clear c))", problem), full)
    assert reason is not None and reason.startswith("contradicts the main goal: (not (on a b))")
    first = parse_goal("(on-table b)", problem)
    assert goal_conflict(first, full) is None
    assert goal_conflict(first, full, {1: first}) == "repeats the subgoal of agent1"
