"""twostep.dealing.copies: an agent does a piece with whichever of its own robots stands
ready, and the ``mover`` cut, which cuts each robot's work where its grippers are free.

Two grippers tasks written here (the repository's grippers domain). Every makespan is
derived by hand in the test's comment; every schedule is checked by ``check_run`` and by
the independent validator on the task's files.
"""

from __future__ import annotations

from pathlib import Path

from tests.conftest import own_task
from tests.support.plans import FAST, check_valid_task_run, sa_result
from twostep.dealing import Dealer
from twostep.dealing.copies import carries_through, piece_copies
from twostep.methods import MethodRequest
from twostep.methods.plan_deal import run_plan_deal
from twostep.tasks.benchmark import BenchmarkTask

GRIPPERS = ["at-robby", "free", "carry"]


def _task(
    tmp_path: Path, data_root: Path, robots: dict[str, str], balls: str, goal: str
) -> BenchmarkTask:
    names = sorted(robots)
    grippers = " ".join(f"lgripper{r[-1]} rgripper{r[-1]}" for r in names)
    init = " ".join(
        f"(at-robby {r} {room}) (free {r} lgripper{r[-1]}) (free {r} rgripper{r[-1]})"
        for r, room in sorted(robots.items())
    )
    problem = (
        f"(define (problem p) (:domain gripper-strips) (:objects {' '.join(names)} - robot "
        f"room1 room2 - room {grippers} - gripper ball1 ball2 ball3 ball4 ball5 - object) "
        f"(:init {init} {balls}) (:goal (and {goal})))"
    )
    domain = (data_root / "grippers" / "domain.pddl").read_text()
    return own_task(tmp_path, "robots", domain, problem)


# robot1 in room1, robot2 and robot3 in room2; ball1 goes from room2 to room1, balls 2-4
# from room1 to room2 (ball5 stays). The SA plan: robot3 takes ball1 over, then ball2
# back; robot1 takes balls 3 and 4 together.
ONE_ROOM = {"robot1": "room1", "robot2": "room2", "robot3": "room2"}
ONE_BALLS = "(at ball1 room2) (at ball2 room1) (at ball3 room1) (at ball4 room1) (at ball5 room1)"
ONE_GOAL = "(at ball1 room1) (at ball2 room2) (at ball3 room2) (at ball4 room2)"
ONE_PLAN = (
    "(pick robot3 ball1 room2 lgripper3)", "(move robot3 room2 room1)",
    "(drop robot3 ball1 room1 lgripper3)", "(pick robot3 ball2 room1 lgripper3)",
    "(move robot3 room1 room2)", "(drop robot3 ball2 room2 lgripper3)",
    "(pick robot1 ball3 room1 lgripper1)", "(pick robot1 ball4 room1 rgripper1)",
    "(move robot1 room1 room2)", "(drop robot1 ball3 room2 lgripper1)",
    "(drop robot1 ball4 room2 rgripper1)",
)  # fmt: skip


def test_an_agent_takes_the_robot_that_stands_where_the_piece_begins(
    tmp_path: Path, data_root: Path
) -> None:
    # Every ball that moves needs a pick, a move and a drop by one robot, one action per
    # agent and step: 3 steps at least. Four agents, each with its own three robots where
    # the task starts them: one takes ball1 with robot3 (in room2), and each of the others
    # one of balls 2-4 with its robot1 (in room1): 3 steps. Without copies (and without
    # rebinding) ball2's trip is robot3's, and every agent's robot3 starts in room2: the
    # agent that takes it drives over first (4 steps), or takes ball1 before it (6).
    task = _task(tmp_path, data_root, ONE_ROOM, ONE_BALLS, ONE_GOAL)
    request = MethodRequest(task, 4, FAST, GRIPPERS, sa_plan=sa_result(ONE_PLAN))
    run = run_plan_deal(request, rebind=False)
    assert run.exec_length == 3
    check_valid_task_run(task, run, GRIPPERS)
    # in 3 steps ball2 goes with a robot that starts in room1: robot1, not the plan's robot3
    actions = [action for plan in run.plans.values() for action in plan]
    assert any(action.startswith("(pick robot1 ball2 room1 ") for action in actions)
    assert run_plan_deal(request, rebind=False, copies=False).exec_length == 4


def test_a_copy_renames_the_robot_and_its_grippers_and_needs_them_free(
    tmp_path: Path, data_root: Path
) -> None:
    # Pieces of the free cut: robot3's two trips and robot1's double trip. ball2's trip
    # (robot3 from room1) has copies with robot1 (lgripper3 -> lgripper1, the first of its
    # grippers as matched in order) and robot2; ball1's trip too; robot1's trip with robot2
    # and robot3. A copy needs its robot's grippers free: an agent whose robot1 carries a
    # ball cannot carry ball2 with robot1's left gripper.
    task = _task(tmp_path, data_root, ONE_ROOM, ONE_BALLS, ONE_GOAL)
    dealer = Dealer(task.problem, ONE_PLAN, GRIPPERS)
    pieces, _ = dealer.pieces("free", keep_walks=False)
    texts = [[str(dealer.steps[i]) for i in piece] for piece in pieces]
    second = texts.index(
        ["(pick robot3 ball2 room1 lgripper3)", "(drop robot3 ball2 room2 lgripper3)"]
    )
    copies = piece_copies(task.problem, dealer.space, dealer.steps, pieces, GRIPPERS)
    assert [[str(s) for s in copy] for copy in copies[second]] == [
        ["(pick robot1 ball2 room1 lgripper1)", "(drop robot1 ball2 room2 lgripper1)"],
        ["(pick robot2 ball2 room1 lgripper2)", "(drop robot2 ball2 room2 lgripper2)"],
    ]
    assert sorted(map(len, copies.values())) == [2, 2, 2]
    where = dealer.space.where
    env, own = dealer.init[0], dealer.init[1]
    with_robot1 = copies[second][0]
    assert carries_through(own, with_robot1, where)
    # robot1 picks ball3 with its left gripper: that gripper is no longer free
    pick = dealer.steps[pieces[-1][0]]  # robot1's trip, the last piece
    assert str(pick) == "(pick robot1 ball3 room1 lgripper1)"
    _, carrying = pick.apply(env, own)
    assert not carries_through(carrying, with_robot1, where)


def test_no_copies_without_robots_or_when_the_goal_names_one(
    tmp_path: Path, data_root: Path
) -> None:
    # termes has no mover (its robot's ``at`` names a place, no object that moves), and a
    # goal that says where robot1 ends could tell the copies apart.
    task = _task(tmp_path, data_root, ONE_ROOM, ONE_BALLS, ONE_GOAL + " (at-robby robot1 room1)")
    dealer = Dealer(task.problem, ONE_PLAN, GRIPPERS)
    pieces, _ = dealer.pieces("free", keep_walks=False)
    assert piece_copies(task.problem, dealer.space, dealer.steps, pieces, GRIPPERS) == {}


# robot1 and robot3 in room2, robot2 in room1; balls 1 and 3 go from room1 to room2,
# balls 2, 4 and 5 from room2 to room1. In the SA plan robot3 holds ball2 while robot2
# carries balls 1 and 3: the agent (all robots) is never free in between.
TWO_ROOM = {"robot1": "room2", "robot2": "room1", "robot3": "room2"}
TWO_BALLS = "(at ball1 room1) (at ball2 room2) (at ball3 room1) (at ball4 room2) (at ball5 room2)"
TWO_GOAL = "(at ball1 room2) (at ball2 room1) (at ball3 room2) (at ball4 room1) (at ball5 room1)"
TWO_PLAN = (
    "(pick robot3 ball2 room2 lgripper3)", "(pick robot2 ball1 room1 lgripper2)",
    "(pick robot2 ball3 room1 rgripper2)", "(move robot2 room1 room2)",
    "(drop robot2 ball1 room2 lgripper2)", "(drop robot2 ball3 room2 rgripper2)",
    "(move robot3 room2 room1)", "(drop robot3 ball2 room1 lgripper3)",
    "(pick robot2 ball4 room2 lgripper2)", "(pick robot2 ball5 room2 rgripper2)",
    "(move robot2 room2 room1)", "(drop robot2 ball4 room1 lgripper2)",
    "(drop robot2 ball5 room1 rgripper2)",
)  # fmt: skip


def test_the_mover_cut_frees_each_robot_on_its_own(tmp_path: Path, data_root: Path) -> None:
    # Five balls, four agents: one agent moves two. Two trips take 6 steps, both at once
    # pick, pick, move, drop, drop: 5, and no agent moves two balls in fewer (two picks,
    # two drops and a move, one action a step). The free cut has two pieces (robot3's trip
    # joined to robot2's first, which it overlaps, then robot2's second): the first is 8
    # actions one agent takes in turn. The mover cut has three: ball2 (3 steps), balls 1
    # and 3 (5), balls 4 and 5 (5), one agent each: 5.
    task = _task(tmp_path, data_root, TWO_ROOM, TWO_BALLS, TWO_GOAL)
    request = MethodRequest(task, 4, FAST, GRIPPERS, sa_plan=sa_result(TWO_PLAN))
    run = run_plan_deal(request)
    assert run.exec_length == 5
    check_valid_task_run(task, run, GRIPPERS)
    rows = [r for r in run.extra["deal"] if r["agents"] == 4 and "rebound" not in r]
    assert {r["cut"]: r["pieces"] for r in rows if not r.get("improved")} == {
        "free": 2, "holding": 5, "mover": 3,
    }  # fmt: skip
    assert run_plan_deal(request, cut="free").exec_length == 8
    by_mover = run_plan_deal(request, cut="mover")
    assert by_mover.exec_length == 5
    check_valid_task_run(task, by_mover, GRIPPERS)


def test_without_robots_the_mover_cut_is_the_free_cut_and_is_not_dealt_again(
    tmp_path: Path, data_root: Path
) -> None:
    # termes: no mover, so no row of the mover cut beside the free cut (its pieces are the
    # free cut's; 7 steps, derived in tests/test_plan_deal.py).
    from tests.examples import TERMES, TERMES_PLAN, TERMES_TOWER
    from tests.support.plans import copy_task

    task = copy_task(tmp_path, data_root, "termes", TERMES_TOWER)
    assert Dealer(task.problem, TERMES_PLAN, TERMES).mover_cut_is_free()
    request = MethodRequest(task, 2, FAST, TERMES, sa_plan=sa_result(TERMES_PLAN))
    run = run_plan_deal(request)
    assert not [r for r in run.extra["deal"] if r.get("cut") == "mover"]
    # asked for alone, the mover cut is dealt: the free cut's pieces, the free cut's length
    by_mover = run_plan_deal(request, cut="mover")
    assert {r["cut"] for r in by_mover.extra["deal"] if r["agents"] == 2} == {"mover"}
    assert by_mover.exec_length == run_plan_deal(request, cut="free").exec_length == 7
