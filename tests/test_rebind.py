"""twostep.dealing.rebind: an object's rounds in the SA plan spread over idle objects of its
kind, and plan-deal dealing the rebound plan beside the SA plan.

The cups bar of tests/test_portfolio.py: the SA plan serves three guests from one cup,
washing it between guests, so every deal of it is one chain. Rebound plans and makespans
are derived by hand in each test's comment; every schedule is checked by ``check_run`` and
by the independent validator on the task's files.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import own_task
from tests.examples import CUPS, CUPS_DOMAIN, CUPS_SA_PLAN, CUPS_TASK
from tests.support.plans import FAST, check_valid_task_run, cups_task, sa_result
from twostep.dealing.rebind import handling_predicates, rebind
from twostep.methods import MethodRequest, RunResult, run_single_agent
from twostep.methods.plan_deal import run_plan_deal
from twostep.tasks.benchmark import BenchmarkTask, load_task


def test_one_cups_rounds_go_to_the_idle_cups(tmp_path: Path) -> None:
    # Handling predicates: take and put change the hand (agent facts) and ``shelf``, so a
    # cup's own facts are clean / full / used. c1 starts clean; fill, serve g1, wash make it
    # clean again: round 1 (steps 2-4); fill, serve g2, wash: round 2; fill, serve g3 leave
    # it used: no round. Round 1 goes to c2 (mentioned never, before c1's take): put c1,
    # take c2 are inserted before it, and put c2, take c1 after it, where (fill c1) needs
    # c1 in hand. Round 2: c2 (its put) and c3 (never) were both mentioned before c1 last
    # was (its take again); c3 longest ago, so it goes to c3.
    task = cups_task(tmp_path)
    assert handling_predicates(task.problem, CUPS) == {"shelf"}
    assert rebind(task.problem, CUPS_SA_PLAN, CUPS) == CUPS_REBOUND


CUPS_REBOUND = [
    "(take c1)", "(put c1)",
    "(take c2)", "(fill c2)", "(serve c2 g1)", "(wash c2)", "(put c2)",
    "(take c1)", "(put c1)",
    "(take c3)", "(fill c3)", "(serve c3 g2)", "(wash c3)", "(put c3)",
    "(take c1)", "(fill c1)", "(serve c1 g3)",
]  # fmt: skip


def test_a_single_cup_or_a_plan_without_rounds_is_not_rebound(tmp_path: Path) -> None:
    # With c2 and c3 dirty from the start (used, not clean) no cup is in c1's state when
    # its rounds begin: nothing to rebind. A plan with one serve has no round at all.
    task = cups_task(tmp_path)
    text = task.problem_path.read_text().replace("(clean c2) (clean c3)", "(used c2) (used c3)")
    task.problem_path.write_text(text)
    dirty = load_task("cups", 1, tmp_path)
    assert rebind(dirty.problem, CUPS_SA_PLAN, CUPS) is None
    one = _one_guest(tmp_path)
    assert rebind(one.problem, ("(take c1)", "(fill c1)", "(serve c1 g1)"), CUPS) is None


def _dirty_cups(tmp_path: Path) -> BenchmarkTask:
    task = cups_task(tmp_path)
    text = task.problem_path.read_text().replace("(clean c2) (clean c3)", "(used c2) (used c3)")
    task.problem_path.write_text(text)
    return load_task("cups", 1, tmp_path)


def test_with_resets_a_round_goes_to_a_used_cup_washed_first(tmp_path: Path) -> None:
    # c2 and c3 start used, so no cup is in c1's state (clean) when its rounds begin.
    # With resets a round may go to a cup in another state, washed first: take, wash, put
    # (wash changes only the cup's own facts; the hand is free again after it). Round 1
    # (fill, serve g1, wash c1): c2 and c3 were never mentioned, c2 first by name; it has
    # no action before the round, so its reset goes first in the plan, then take c1 (the
    # plan's own), and the round renamed with put c1, take c2 before it and put c2, take c1
    # after it. Round 2 of c1: c2 (clean now, last mentioned by its put) and c3 (never
    # mentioned) both need put c1, take c2 / c3 before it and put, take c1 after it (a
    # reset's own actions do not count), so the one mentioned longest ago wins: c3, whose
    # reset goes first of all. Its last cup, c1, serves g3. After the two resets, it is the
    # plan that rebinding makes when the cups start clean.
    dirty = _dirty_cups(tmp_path)
    expected = ["(take c3)", "(wash c3)", "(put c3)", "(take c2)", "(wash c2)", "(put c2)",
                *CUPS_REBOUND]  # fmt: skip
    assert rebind(dirty.problem, CUPS_SA_PLAN, CUPS, resets=True) == expected
    assert rebind(dirty.problem, CUPS_SA_PLAN, CUPS, tails=True, resets=True) == expected


@pytest.mark.parametrize(("agents", "length"), [(2, 8), (3, 4), (4, 4)])
def test_plan_deal_deals_the_plan_with_resets(tmp_path: Path, agents: int, length: int) -> None:
    # The plan above, cleaned (the last washes, and c1's take-put pairs, serve nothing):
    # take, wash, fill, serve for c3 and for c2, take, fill, serve for c1: pieces of 4, 4
    # and 3 actions. Three agents take a cup each: 4 steps, a fourth has nothing to do;
    # two: one of them does two cups, putting the first down to take the second (one
    # hand): 4 + 1 + 3 = 8. The rounds plan is none (no cup is ready); the tails plan is
    # the plan above (it resets). Without rebinding every deal is the SA plan's one
    # chain: 9 steps.
    _, request, _ = _deal_cups(_dirty_cups(tmp_path), agents, length, "tails")
    assert run_plan_deal(request, rebind=False).exec_length == 9


def _deal_cups(
    task: BenchmarkTask, agents: int, length: int, rebound: str
) -> tuple[RunResult, MethodRequest, dict]:
    """plan-deal of the cups SA plan to ``agents``: ``length`` steps, no fallback, the
    chosen deal of the ``rebound`` plan on at most three agents (three cups), valid."""
    request = MethodRequest(task, agents, FAST, CUPS, sa_plan=sa_result(CUPS_SA_PLAN))
    run = run_plan_deal(request)
    assert run.exec_length == length and run.fallback is None
    (chosen,) = [row for row in run.extra["deal"] if row.get("chosen")]
    assert chosen["rebound"] == rebound and chosen["agents_used"] == min(agents, 3)
    check_valid_task_run(task, run, CUPS)
    return run, request, chosen


def _one_guest(tmp_path: Path) -> BenchmarkTask:
    text = CUPS_TASK.replace(
        "(:goal (and (served g1) (served g2) (served g3)))", "(:goal (served g1))"
    )
    return own_task(tmp_path / "one", "cups", CUPS_DOMAIN, text)


@pytest.mark.parametrize(("agents", "length"), [(2, 7), (3, 3), (4, 3)])
def test_plan_deal_deals_the_rebound_plan(tmp_path: Path, agents: int, length: int) -> None:
    # The rebound plan, cleaned (the washes serve nothing later, nor do c1's take-put
    # pairs): take, fill, serve, put for c2 and c3, then take, fill, serve c1: three
    # pieces of 4, 4 and 3 actions. Three agents take one cup each: 3 steps (the puts go
    # in the joint clean-up); two: one agent does two cups, 4 + 3 = 7 steps; a fourth agent
    # has nothing to do. Without rebinding every deal is the one chain: 9 steps.
    run, request, chosen = _deal_cups(cups_task(tmp_path), agents, length, "rounds")
    assert chosen["cleaned_sa_length"] == 11
    assert "rebinding" in run.extra["deal_seconds"]
    plain = run_plan_deal(request, rebind=False)
    assert plain.exec_length == 9 and plain.fallback == "no deal shorter than the cleaned SA plan"
    assert not any(row.get("rebound") for row in plain.extra["deal"])


def test_barman_glass_rounds_deal_shorter_and_stay_monotone(data_root: Path) -> None:
    # barman p01: Fast Downward's SA plan carries every ingredient in one shot glass.
    # Rebinding spreads its rounds over the goal glasses that stand clean until their
    # cocktail is poured. With it plan-deal is never longer (the SA plan's deals are still
    # candidates), shorter at N = 3 and 4, never longer with more agents, and valid.
    preds = ["handempty", "holding"]
    task = load_task("barman", 1, data_root)
    sa_plan = run_single_agent(MethodRequest(task, planner=FAST)).planner_calls[0].result
    lengths = {}
    for agents in (2, 3, 4):
        request = MethodRequest(task, agents, FAST, preds, sa_plan=sa_plan)
        run = run_plan_deal(request)
        plain = run_plan_deal(request, rebind=False)
        assert run.exec_length is not None and plain.exec_length is not None
        assert run.exec_length <= plain.exec_length
        if agents > 2:
            assert run.exec_length < plain.exec_length
        check_valid_task_run(task, run, preds)
        lengths[agents] = run.exec_length
    assert lengths[2] >= lengths[3] >= lengths[4]


# Jugs: a jug is filled at the tap, poured into a pot, filled again with the same drink
# (refill: it is used already), and washed. The SA plan fills both pots from jug j1.
JUGS_DOMAIN = """(define (domain jugs)
  (:requirements :strips)
  (:predicates (hand-free) (holding ?c) (shelf ?c) (clean ?c) (empty ?c) (full ?c)
    (used ?c) (filled ?p))
  (:action take :parameters (?c)
    :precondition (and (shelf ?c) (hand-free))
    :effect (and (holding ?c) (not (shelf ?c)) (not (hand-free))))
  (:action put :parameters (?c)
    :precondition (holding ?c)
    :effect (and (shelf ?c) (hand-free) (not (holding ?c))))
  (:action fill :parameters (?c)
    :precondition (and (holding ?c) (clean ?c) (empty ?c))
    :effect (and (full ?c) (used ?c) (not (clean ?c)) (not (empty ?c))))
  (:action refill :parameters (?c)
    :precondition (and (holding ?c) (used ?c) (empty ?c))
    :effect (and (full ?c) (not (empty ?c))))
  (:action pour :parameters (?c ?p)
    :precondition (and (holding ?c) (full ?c))
    :effect (and (filled ?p) (empty ?c) (not (full ?c))))
  (:action wash :parameters (?c)
    :precondition (and (holding ?c) (used ?c) (empty ?c))
    :effect (and (clean ?c) (not (used ?c)))))"""
JUGS_TASK = """(define (problem two-pots) (:domain jugs)
  (:objects j1 j2 p1 p2)
  (:init (hand-free) (shelf j1) (shelf j2) (clean j1) (clean j2) (empty j1) (empty j2))
  (:goal (and (filled p1) (filled p2) (clean j1) (clean j2))))"""
JUGS = ["hand-free", "holding"]
JUGS_SA_PLAN = ("(take j1)", "(fill j1)", "(pour j1 p1)", "(refill j1)", "(pour j1 p2)",
                "(wash j1)")  # fmt: skip


def _jugs(tmp_path: Path) -> BenchmarkTask:
    return own_task(tmp_path, "jugs", JUGS_DOMAIN, JUGS_TASK)


def test_a_tail_goes_to_the_idle_jug_and_the_jug_is_washed_where_it_stands(
    tmp_path: Path,
) -> None:
    # j1's own facts (shelf is handling): clean empty -> fill: full used -> pour: empty
    # used -> refill: full used -> pour: empty used -> wash: clean empty: one round, steps
    # 1-5. Without tails the only rename is the whole round, to j2 (never mentioned, as
    # clean and empty): put j1 and take j2 before it, still one chain. With tails, the
    # plan after that: j2's state after the first pour (empty used) comes back after the
    # second, so the tail from the refill on goes to j1 (mentioned before j2 was); j2
    # keeps the tail's actions after its last return to that state (the wash); where j1
    # is not used, refill gives way to fill (same arguments, adds all refill adds), after
    # put j2, take j1.
    task = _jugs(tmp_path)
    rounds = rebind(task.problem, JUGS_SA_PLAN, JUGS)
    assert rounds == ["(take j1)", "(put j1)", "(take j2)", "(fill j2)", "(pour j2 p1)",
                      "(refill j2)", "(pour j2 p2)", "(wash j2)"]  # fmt: skip
    assert rebind(task.problem, JUGS_SA_PLAN, JUGS, tails=True) == [
        "(take j1)", "(put j1)", "(take j2)", "(fill j2)", "(pour j2 p1)", "(wash j2)",
        "(put j2)", "(take j1)", "(fill j1)", "(pour j1 p2)", "(wash j1)",
    ]  # fmt: skip
    # Dealt to two agents: each jug's take, fill, pour, wash is a piece of its own: 4
    # steps; the SA plan and the rounds-only plan are one chain of 6 acting steps.
    request = MethodRequest(task, 2, FAST, JUGS, sa_plan=sa_result(JUGS_SA_PLAN))
    run = run_plan_deal(request)
    (chosen,) = [row for row in run.extra["deal"] if row.get("chosen")]
    assert run.exec_length == 4 and chosen["rebound"] == "tails"
    check_valid_task_run(task, run, JUGS)
    assert run_plan_deal(request, rebind=False).exec_length == 6


# grippers p01 (ours): robot1 in room1, robot2 in room2, ball1 in room2 to room1, ball2
# in room1 to room2. The SA plan has robot2 carry both.
GRIPPERS_SA_PLAN = (
    "(pick robot2 ball1 room2 lgripper2)", "(move robot2 room2 room1)",
    "(drop robot2 ball1 room1 lgripper2)", "(pick robot2 ball2 room1 lgripper2)",
    "(move robot2 room1 room2)", "(drop robot2 ball2 room2 lgripper2)",
)  # fmt: skip


def test_a_robots_second_trip_goes_to_the_idle_robot_with_its_grippers(data_root: Path) -> None:
    # A robot is a mover (it stays in at-robby as it moves): its own facts are its
    # grippers free or carrying. Its first trip (pick ... drop) is a round, so is its
    # second; robot1 was never mentioned, so the second trip goes to robot1, lgripper2 to
    # lgripper1 (robot1's free grippers, matched in order). robot1 stands in room1 where
    # ball2 is: nothing to repair. Dealt to two agents (each has its own copy of both
    # robots where they start): one trip each, 3 steps; without rebinding (and without
    # copies, which find the same robot1 for the second agent) the second agent's robot2
    # must first drive to room1: 4.
    preds = ["at-robby", "free", "carry"]
    task = load_task("grippers", 1, data_root)
    assert rebind(task.problem, GRIPPERS_SA_PLAN, preds) == [
        *GRIPPERS_SA_PLAN[:3],
        "(pick robot1 ball2 room1 lgripper1)", "(move robot1 room1 room2)",
        "(drop robot1 ball2 room2 lgripper1)",
    ]  # fmt: skip
    request = MethodRequest(task, 2, FAST, preds, sa_plan=sa_result(GRIPPERS_SA_PLAN))
    run = run_plan_deal(request)
    assert run.exec_length == 3 and run.fallback is None
    check_valid_task_run(task, run, preds)
    assert run_plan_deal(request, rebind=False, copies=False).exec_length == 4
