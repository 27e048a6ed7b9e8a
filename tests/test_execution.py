"""Tests for twostep.makespan: parallel execution length of per-agent plans."""

from __future__ import annotations

import functools
import itertools
import random
from collections.abc import Sequence

import pytest

from tests.examples import (
    BLOCKSWORLD,
    TOY,
    TOY_AGENT,
    TOY_PROBLEM,
    TRACKS,
    ground,
    problem,
    tracks_problem,
)
from tests.support.brute_force import (
    JointState,
    brute_force_length,
    finished,
    interfere,
    joint_step,
    random_case,
    start_node,
)
from twostep.makespan import (
    ParallelExecution,
    ScheduleError,
    check_schedule,
    parallel_length,
    split_state,
)
from twostep.makespan.check import EnvironmentPart, may_interfere
from twostep.pddl import Fact, Goal, Problem, parse_goal
from twostep.plans.simulate import GroundAction

THREE_BLOCKS_ON_TABLE = """
(define (problem three) (:domain blocksworld)
 (:objects b1 b2 b3)
 (:init (clear b1) (clear b2) (clear b3) (ontable b1) (ontable b2) (ontable b3) (arm-empty))
 (:goal (and (on b1 b2))))
"""

BLOCKSWORLD_AGENT = ("arm-empty", "holding")

# Three agents: a1 enables c1; a and b are independent. Exact: {a1,b1} then {a2,b2,c1}.
# The paper's recursion cannot start with everyone (c1 is not applicable yet), and after
# one agent alone nobody can finish in one more step: 3.
STAGGERED = """
(define (domain staggered)
 (:requirements :strips)
 (:predicates (da1) (da2) (db1) (db2) (dc1))
 (:action a1 :parameters () :effect (da1))
 (:action a2 :parameters () :precondition (da1) :effect (da2))
 (:action b1 :parameters () :effect (db1))
 (:action b2 :parameters () :precondition (db1) :effect (db2))
 (:action c1 :parameters () :precondition (da1) :effect (dc1)))
"""
STAGGERED_PROBLEM = """
(define (problem staggered-1) (:domain staggered) (:init) (:goal (and (da2) (db2) (dc1))))
"""

LIGHTS = """
(define (domain lights)
 (:requirements :strips :negative-preconditions)
 (:predicates (lit ?r) (passed ?r))
 (:action sneak :parameters (?r) :precondition (not (lit ?r)) :effect (passed ?r))
 (:action switch-on :parameters (?r) :effect (lit ?r)))
"""
LIGHTS_PROBLEM = """
(define (problem dark) (:domain lights) (:objects r1) (:init)
 (:goal (and (passed r1) (lit r1))))
"""


def score(
    prob: Problem,
    plans: list[list[GroundAction]],
    agent_predicates: Sequence[str] = (),
    mode: str = "exact",
    goal: Goal | None = None,
) -> ParallelExecution:
    goal = goal if goal is not None else prob.goal
    result = parallel_length(plans, prob.init, goal, agent_predicates, mode)
    assert result.mode == mode
    assert result.length == len(result.steps)
    check_schedule(result.steps, plans, prob.init, goal, agent_predicates)
    return result


# ----------------------------------------------------------------- hand-made cases


def test_split_state_by_predicate() -> None:
    state = {("on", "b1", "b2"), ("arm-empty",), ("holding", "b3")}
    environment, agent = split_state(state, BLOCKSWORLD_AGENT)
    assert environment == {("on", "b1", "b2")}
    assert agent == {("arm-empty",), ("holding", "b3")}


def test_agents_needing_the_same_block_do_not_act_together() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    plans = ground(prob, ["(pickup b1)", "(putdown b1)"], ["(pickup b1)", "(stack b1 b2)"])
    for mode in ("exact", "paper"):
        result = score(prob, plans, BLOCKSWORLD_AGENT, mode)
        # Both pickups are applicable at the start but each deletes (clear b1): serial.
        assert result.length == 4
        assert all(len(step) == 1 for step in result.steps)
    together = [
        [(0, "(pickup b1)"), (1, "(pickup b1)")],
        [(0, "(putdown b1)")],
        [(1, "(stack b1 b2)")],
    ]
    with pytest.raises(ScheduleError, match="interfere") as info:
        check_schedule(together, plans, prob.init, prob.goal, BLOCKSWORLD_AGENT)
    assert info.value.time_step == 1


def test_main_agent_waits_for_the_helper_effect() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    goal = parse_goal("(and (on b1 b2) (on b3 b1))", prob)
    plans = ground(prob, ["(pickup b1)", "(stack b1 b2)"], ["(pickup b3)", "(stack b3 b1)"])
    result = score(prob, plans, BLOCKSWORLD_AGENT, goal=goal)
    # (stack b3 b1) needs (clear b1), which only the helper's (stack b1 b2) restores.
    assert result.steps == (
        ((0, "(pickup b1)"), (1, "(pickup b3)")),
        ((0, "(stack b1 b2)"),),
        ((1, "(stack b3 b1)"),),
    )
    assert score(prob, plans, BLOCKSWORLD_AGENT, "paper", goal=goal).length == 3


def test_without_agent_predicates_the_arm_is_shared() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    goal = parse_goal("(and (on b1 b2) (on b3 b1))", prob)
    plans = ground(prob, ["(pickup b1)", "(stack b1 b2)"], ["(pickup b3)", "(stack b3 b1)"])
    # One shared (arm-empty): the two pickups interfere, so nothing runs in parallel.
    assert score(prob, plans, (), goal=goal).length == 4


def test_three_agents_paper_mode_is_longer_than_exact() -> None:
    prob = problem(STAGGERED, STAGGERED_PROBLEM)
    plans = ground(prob, ["(a1)", "(a2)"], ["(b1)", "(b2)"], ["(c1)"])
    exact = score(prob, plans, mode="exact")
    paper = score(prob, plans, mode="paper")
    assert exact.length == 2
    assert exact.steps == (((0, "(a1)"), (1, "(b1)")), ((0, "(a2)"), (1, "(b2)"), (2, "(c1)")))
    assert paper.length == 3


def test_goal_already_holds_with_empty_plans() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    goal = parse_goal("(ontable b1)", prob)
    for mode in ("exact", "paper"):
        result = score(prob, [[], []], BLOCKSWORLD_AGENT, mode, goal=goal)
        assert (result.length, result.steps) == (0, ())
    assert score(prob, [], BLOCKSWORLD_AGENT, goal=goal).length == 0


def test_empty_plans_fail_when_the_goal_does_not_hold() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    with pytest.raises(ScheduleError) as info:
        parallel_length([[], []], prob.init, prob.goal, BLOCKSWORLD_AGENT)
    assert info.value.goal == "(on b1 b2)"


def test_single_agent_length_is_its_plan_length() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    plans = ground(prob, ["(pickup b3)", "(putdown b3)", "(pickup b1)", "(stack b1 b2)"])
    for mode in ("exact", "paper"):
        assert score(prob, plans, BLOCKSWORLD_AGENT, mode).length == 4


def test_independent_plans_of_three_and_five_take_five() -> None:
    text, plans = tracks_problem([3, 5])
    prob = problem(TRACKS, text)
    for mode in ("exact", "paper"):
        result = score(prob, ground(prob, *plans), ["ready"], mode)
        assert result.length == 5
        assert [len(step) for step in result.steps] == [2, 2, 2, 1, 1]


def test_four_independent_sixty_step_plans_go_straight_down() -> None:
    text, plans = tracks_problem([60, 60, 60, 60])
    prob = problem(TRACKS, text)
    result = score(prob, ground(prob, *plans), ["ready"])
    assert result.length == 60
    assert result.nodes_expanded == 61  # one node per time step: no branching at all


def test_shared_hub_staggers_the_carts() -> None:
    text, plans = tracks_problem([8, 8, 8], hub_at=4)
    prob = problem(TRACKS, text)
    grounded = ground(prob, *plans)
    # Each cart holds the hub for two steps (enter, leave); the next one enters after.
    assert score(prob, grounded, ["ready"]).length == 12
    assert score(prob, grounded, ["ready"], "paper").length >= 12


def test_four_carts_queue_at_a_hub_with_little_search() -> None:
    text, plans = tracks_problem([30, 30, 30, 30], hub_at=15)
    prob = problem(TRACKS, text)
    grounded = ground(prob, *plans)
    result = score(prob, grounded, ["ready"])
    assert result.length == 36  # three carts wait 2, 4 and 6 steps for the hub
    assert result.nodes_expanded < 500  # 31^4 index tuples exist


def test_unreachable_goal_is_refuted_without_search() -> None:
    text, plans = tracks_problem([30, 30, 30, 30])
    prob = problem(TRACKS, text)
    goal = parse_goal("(and (at c0 k0-30) (at c1 k1-0))", prob)
    with pytest.raises(ScheduleError) as info:
        parallel_length(ground(prob, *plans), prob.init, goal, ["ready"])
    assert info.value.goal == "(at c1 k1-0)"


def test_agent_specific_goal_must_hold_for_every_agent() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    goal = parse_goal("(and (on b1 b2) (arm-empty))", prob)
    plans = ground(prob, ["(pickup b1)", "(stack b1 b2)"], ["(pickup b3)"])
    with pytest.raises(ScheduleError, match="agent 1") as info:
        parallel_length(plans, prob.init, goal, BLOCKSWORLD_AGENT)
    assert (info.value.agent, info.value.goal) == (1, "(arm-empty)")
    # The helper alone satisfies it: every copy ends with an empty arm.
    assert score(prob, plans[:1], BLOCKSWORLD_AGENT, goal=goal).length == 2


def test_negative_precondition_blocks_a_parallel_add() -> None:
    prob = problem(LIGHTS, LIGHTS_PROBLEM)
    plans = ground(prob, ["(sneak r1)"], ["(switch-on r1)"])
    for mode in ("exact", "paper"):
        result = score(prob, plans, (), mode)
        assert result.steps == (((0, "(sneak r1)"),), ((1, "(switch-on r1)"),))
    together = [[(0, "(sneak r1)"), (1, "(switch-on r1)")]]
    with pytest.raises(ScheduleError, match=r"adds \(lit r1\)"):
        check_schedule(together, plans, prob.init, prob.goal, ())


def test_inapplicable_plan_is_diagnosed_in_hand_off_order() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    plans = ground(prob, ["(pickup b1)", "(stack b1 b2)"], ["(pickup b3)", "(stack b3 b2)"])
    for mode in ("exact", "paper"):
        with pytest.raises(ScheduleError) as info:
            parallel_length(plans, prob.init, prob.goal, BLOCKSWORLD_AGENT, mode)
        error = info.value
        assert (error.agent, error.step, error.action) == (1, 2, "(stack b3 b2)")
        assert error.precondition == "(clear b2)"
        assert "agent 1 step 2 (stack b3 b2)" in str(error)


def test_agent_copy_precondition_is_diagnosed_before_search() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    plans = ground(prob, ["(pickup b1)", "(stack b1 b2)"], ["(stack b3 b1)"])
    with pytest.raises(ScheduleError) as info:
        parallel_length(plans, prob.init, prob.goal, BLOCKSWORLD_AGENT)
    assert (info.value.agent, info.value.step, info.value.precondition) == (1, 1, "(holding b3)")


def test_plans_that_only_work_interleaved_are_accepted() -> None:
    # Not in hand-off order: agent 1 must put b3 down before agent 0 can stack on it.
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    goal = parse_goal("(and (on b1 b3) (ontable b3))", prob)
    plans = ground(prob, ["(pickup b1)", "(stack b1 b3)"], ["(pickup b3)", "(putdown b3)"])
    result = score(prob, plans, BLOCKSWORLD_AGENT, goal=goal)
    assert result.length == 3
    assert score(prob, plans, BLOCKSWORLD_AGENT, "paper", goal=goal).length == 3


def test_check_schedule_rejects_bad_schedules() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    plans = ground(prob, ["(pickup b1)", "(stack b1 b2)"], ["(pickup b3)"])
    goal = parse_goal("(on b1 b2)", prob)
    good = [[(0, "(pickup b1)"), (1, "(pickup b3)")], [(0, "(stack b1 b2)")]]
    check_schedule(good, plans, prob.init, goal, BLOCKSWORLD_AGENT)
    bad = {
        "not .stack b1 b3.": [[(0, "(pickup b1)"), (1, "(pickup b3)")], [(0, "(stack b1 b3)")]],
        "increasing order": [[(1, "(pickup b3)"), (0, "(pickup b1)")], [(0, "(stack b1 b2)")]],
        "stops after 1 of its 2": [[(0, "(pickup b1)"), (1, "(pickup b3)")]],
        "empty": [[(0, "(pickup b1)"), (1, "(pickup b3)")], [], [(0, "(stack b1 b2)")]],
        "no action left": [[(1, "(pickup b3)")], [(1, "(pickup b3)")]],
    }
    for message, steps in bad.items():
        with pytest.raises(ScheduleError, match=message):
            check_schedule(steps, plans, prob.init, goal, BLOCKSWORLD_AGENT)


def test_unknown_mode_is_rejected() -> None:
    prob = problem(BLOCKSWORLD, THREE_BLOCKS_ON_TABLE)
    with pytest.raises(ValueError, match="unknown mode"):
        parallel_length([], prob.init, prob.goal, (), mode="optimal")


# ------------------------------------------------------------ randomised checks


def algorithm_one(
    plans: list[list[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Sequence[str],
) -> int | None:
    """The paper's Algorithm 1 as a memoised recursion (the oracle for mode 'paper')."""
    infinity = 10**9

    @functools.cache
    def solve(node: JointState) -> int:
        done = finished(plans, node, goal)
        if done is not None:
            return 0 if done else infinity
        active = [i for i, p in enumerate(plans) if node[0][i] < len(p)]
        options = [[i] for i in active] + ([active] if len(active) > 1 else [])
        best = infinity
        for chosen in options:
            child = joint_step(plans, node, chosen, agent_predicates)
            if child is not None:
                best = min(best, 1 + solve(child))
        return best

    result = solve(start_node(plans, init, agent_predicates))
    return None if result >= infinity else result


def test_random_cases_against_oracles() -> None:
    prob = problem(TOY, TOY_PROBLEM)
    rng = random.Random(20240521)
    valid = 0
    for _ in range(300):
        plans, init, goal = random_case(rng, prob)
        expected = brute_force_length(plans, init, goal, TOY_AGENT)
        expected_paper = algorithm_one(plans, init, goal, TOY_AGENT)
        assert (expected is None) == (expected_paper is None)  # serialising keeps validity
        if expected is None:
            for mode in ("exact", "paper"):
                with pytest.raises(ScheduleError):
                    parallel_length(plans, init, goal, TOY_AGENT, mode)
            continue
        valid += 1
        exact = parallel_length(plans, init, goal, TOY_AGENT, "exact")
        paper = parallel_length(plans, init, goal, TOY_AGENT, "paper")
        for result in (exact, paper):
            check_schedule(result.steps, plans, init, goal, TOY_AGENT)
        assert exact.length == expected
        assert paper.length == expected_paper
        assert max(map(len, plans)) <= exact.length <= paper.length <= sum(map(len, plans))
    assert valid >= 150  # the generator must mostly produce schedulable cases


def test_interference_screen_agrees_with_the_plain_pairwise_rule() -> None:
    """check_schedule screens a step in linear time before naming the interfering pair;
    the screen must flag exactly the steps in which some pair interferes (the oracle's
    rule above), on random actions over a few facts, with and without agent facts."""
    rng = random.Random(11)
    pool = [("e", str(i)) for i in range(4)] + [("h", "0")]

    def facts(most: int) -> frozenset[Fact]:
        return frozenset(rng.sample(pool, rng.randint(0, most)))

    flagged = 0
    for trial in range(2000):
        predicates = ("h",) if trial % 2 else ()
        actions = []
        for k in range(rng.randint(2, 5)):
            add = facts(2)
            actions.append(GroundAction("a", (str(k),), facts(2), facts(1), add, facts(2) - add))

        def environment_of(action: GroundAction, predicates=predicates) -> EnvironmentPart:
            return EnvironmentPart(
                *(
                    split_state(f, predicates)[0]
                    for f in (action.pre_positive, action.pre_negative, action.add, action.delete)
                )
            )

        expected = any(interfere(a, b, predicates) for a, b in itertools.combinations(actions, 2))
        assert may_interfere(actions, environment_of) == expected
        flagged += expected
    assert 200 < flagged < 1800  # both answers are exercised
