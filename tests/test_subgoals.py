"""twostep.plans.subgoals: the one subgoal checker, on cases derived by hand.

The task: blocks a, b, c; b is on c, a and c on the table, the arm is empty.
Goal: (on a b) (on c a), i.e. the tower c-a-b from the top.
"""

from __future__ import annotations

import json

import pytest

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.decomposers.base import SubgoalProposal
from twostep.pddl import Problem, parse_problem
from twostep.plans.subgoals import SubgoalError, SubgoalStatus, check_subgoal

INIT = "(arm-empty) (on-table a) (on-table c) (on b c) (clear a) (clear b)"


@pytest.fixture(scope="module")
def problem() -> Problem:
    return parse_problem(BLOCKS_DOMAIN, blocks_problem(INIT, "(on a b) (on c a)", "a b c"))


@pytest.mark.parametrize(
    "text, reason",
    [
        (None, "no PDDL subgoal"),
        ("  ", "no PDDL subgoal"),
        ("(and (stacked a b))", "invalid PDDL subgoal: unknown predicate 'stacked'"),
        ("(and (on-table d))", "invalid PDDL subgoal: unknown object 'd'"),
        ("(on a)", "invalid PDDL subgoal: 'on' takes 2 argument(s), got 1"),
        # b is on c in the initial state
        ("(and (on b c) (arm-empty))", "already true in the helper's initial state"),
        ("(and (on c a) (on a b))", "equals the full goal"),
        ("(and (on a b) (on c a) (clear c))", "includes the full goal"),
        ("(and (not (on a b)) (clear c))", "contradicts the main goal: (not (on a b))"),
    ],
)
def test_rejected_with_the_reason(problem: Problem, text: str | None, reason: str) -> None:
    with pytest.raises(SubgoalError) as info:
        check_subgoal(text, problem, start=problem.init)
    assert str(info.value).startswith(reason)


def test_accepted_subgoal_is_the_parsed_goal(problem: Problem) -> None:
    # b on the table: not true initially (b is on c), not a goal literal, no contradiction
    goal = check_subgoal("(:goal (and (on-table b) (arm-empty)))", problem, start=problem.init)
    assert goal.positive == {("on-table", "b"), ("arm-empty",)} and not goal.negative


def test_already_true_needs_the_start_state(problem: Problem) -> None:
    # Without a start state (the LLM decomposer's check) the rule is not applied ...
    assert check_subgoal("(on b c)", problem).positive == {("on", "b", "c")}
    # ... and a state where b is elsewhere makes the same subgoal useful.
    moved = (problem.init - {("on", "b", "c")}) | {("on-table", "b")}
    assert check_subgoal("(on b c)", problem, start=moved).positive == {("on", "b", "c")}


def test_repeat_of_an_earlier_helper(problem: Problem) -> None:
    first = check_subgoal("(on-table b)", problem, start=problem.init)
    with pytest.raises(SubgoalError, match="repeats the subgoal of agent1"):
        check_subgoal("(and (on-table b))", problem, start=problem.init, earlier={1: first})


def test_status_strings_stay_those_of_result_json() -> None:
    assert [s.value for s in SubgoalStatus] == [
        "proposed",
        "accepted",
        "discarded",
        "stopped",
        "unused",
    ]
    proposal = SubgoalProposal(1, "(on-table b)", status=SubgoalStatus.DISCARDED)
    assert json.loads(json.dumps(proposal.to_dict()))["status"] == "discarded"
    # a plain string status from a decomposer is checked against the enum
    assert SubgoalProposal(1, None, status="stopped").to_dict()["status"] == "stopped"  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        SubgoalProposal(1, None, status="maybe").to_dict()  # type: ignore[arg-type]
