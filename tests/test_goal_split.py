"""twostep.decomposers.goal_split: components, balancing and release conditions."""

from __future__ import annotations

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.decomposers.goal_split import (
    open_goal_components,
    positional_predicates,
    release_literals,
    split_goal,
)
from twostep.pddl import parse_problem

BW = ["arm-empty", "holding"]
INIT = " ".join(f"(on-table {b}) (clear {b})" for b in "abcdef") + " (arm-empty)"


def _problem(goal: str):
    return parse_problem(BLOCKS_DOMAIN, blocks_problem(INIT, goal, "a b c d e f"))


def test_towers_are_components() -> None:
    p = _problem("(on a b) (on b c) (on d e)")
    assert open_goal_components(p, BW) == [[("on", "a", "b"), ("on", "b", "c")], [("on", "d", "e")]]


def test_literals_already_true_are_not_split() -> None:
    p = _problem("(on a b) (on-table c)")
    assert open_goal_components(p, BW) == [[("on", "a", "b")]]
    assert split_goal(p, 2, BW) == []


def test_helpers_get_balanced_buckets_with_release_conditions() -> None:
    p = _problem("(on a b) (on b c) (on d e) (on f a)")
    # one tower a-b-c plus f on a is one component; d-e another
    goals = split_goal(p, 2, BW)
    assert len(goals) == 1
    assert goals[0].positive == {("on", "d", "e"), ("arm-empty",)}
    assert split_goal(p, 4, BW)[0] == goals[0]  # only two components: one helper at most
    assert split_goal(p, 1, BW) == []


def test_positional_predicates_are_not_release_conditions() -> None:
    p = _problem("(on a b)")
    assert (
        positional_predicates(p.domain) & set(BW) == set()
    )  # clear is positional, not an agent fact
    assert release_literals(p, BW).positive == {("arm-empty",)}
