"""twostep.decomposers.plan_split: hand-written SA plans, hand-derived pieces and subgoals.

Each case gives plan-split a single-agent plan written by hand, so the pieces, their
order and the helper subgoals can be derived by hand (see each test's comment). The
TwoStep runs then plan for real (Fast Downward) and every joint schedule is checked twice:
``check_run`` (our simulator) and unified-planning's validator on the N-agent compilation
of the task, with the schedule's parallel steps laid out one action after the other.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import blocks_problem
from tests.examples import (
    BW,
    TALL_TOWER,
    TALL_TOWER_PLAN,
    TERMES,
    TERMES_PLAN,
    TERMES_TOWER,
    TWO_TOWERS,
    TWO_TOWERS_PLAN,
)
from tests.support.plans import FAST, blocks_task, check_valid_run, copy_task, sa_result
from twostep.decomposers.base import DecompositionRequest
from twostep.decomposers.plan_split import PlanSplitDecomposer, split_plan
from twostep.methods import MethodRequest, run_single_agent, run_twostep
from twostep.pddl import Goal, Problem, parse_goal
from twostep.tasks.benchmark import load_task

BARMAN = ["handempty", "holding"]


# one cocktail per shaker; each shot is filled, poured and cleaned in turn, then shaken
BARMAN_PLAN = tuple(
    line
    for shot, shaker, cocktail, (d1, i1), (d2, i2) in (
        ("shot1", "shaker1", "cocktail1", ("dispenser1", "ingredient2"), ("dispenser2", "ingredient1")),
        ("shot2", "shaker2", "cocktail2", ("dispenser2", "ingredient1"), ("dispenser1", "ingredient2")),
        ("shot4", "shaker3", "cocktail3", ("dispenser3", "ingredient3"), ("dispenser1", "ingredient2")),
    )
    for line in (
        f"(grasp left {shot})",
        f"(fill-shot {shot} {i1} left right {d1})",
        f"(pour-shot-to-clean-shaker {shot} {i1} {shaker} left l0 l1)",
        f"(clean-shot {shot} {i1} left right)",
        f"(fill-shot {shot} {i2} left right {d2})",
        f"(pour-shot-to-used-shaker {shot} {i2} {shaker} left l1 l2)",
        f"(clean-shot {shot} {i2} left right)",
        f"(leave left {shot})",
        f"(grasp left {shaker})",
        f"(shake {cocktail} {i1} {i2} {shaker} left right)",
        f"(pour-shaker-to-shot {cocktail} {shot} left {shaker} l2 l1)",
        f"(leave left {shaker})",
    )
)  # fmt: skip


def goal(problem: Problem, pddl: str) -> Goal:
    return parse_goal(pddl, problem)


def test_two_independent_towers(tmp_path: Path) -> None:
    # Pieces (pickup, stack): b-c before a-b (stack b c gives clear b back), e-f before
    # d-e. The first agent builds a-b-c, the second d-e-f: 4 steps instead of 8. The
    # helper keeps what its pieces achieved that the goal wants, and the empty arm.
    task = blocks_task(tmp_path, TWO_TOWERS)
    problem = task.problem
    for agents in (2, 3):  # a third agent finds nothing to do in parallel
        split = split_plan(problem, TWO_TOWERS_PLAN, agents, BW)
        assert [list(r) for r in split.pieces] == [[0, 1], [2, 3], [4, 5], [6, 7]]
        assert split.owner == [0, 0, 1, 1] and split.makespan == 4
        assert split.subgoals == [goal(problem, "(and (on a b) (on b c) (arm-empty))")]
    run = run_twostep(
        MethodRequest(
            task, 2, FAST, BW, PlanSplitDecomposer(BW), sa_plan=sa_result(TWO_TOWERS_PLAN)
        )
    )
    assert [s["status"] for s in run.subgoals] == ["accepted"] and run.fallback is None
    assert run.exec_length == 4  # each agent builds one tower, 4 actions each, in parallel
    check_valid_run(problem, run, BW)


def test_one_tall_tower_gives_partial_progress(tmp_path: Path) -> None:
    # Pieces: P1 clears a (c to the table), P2 clears b (d to the table), P3 c on d, P4 b
    # on c, P5 a on b. Order: P1, P2 -> P3 -> P4 -> P5 and P1 -> P5. Only P2 runs beside
    # P1, so the helper clears b: its subgoal is (clear b), a fact no goal literal names
    # (goal-split has nothing to offer here: the goal is one component).
    task = blocks_task(tmp_path, TALL_TOWER)
    problem = task.problem
    split = split_plan(problem, TALL_TOWER_PLAN, 2, BW)
    assert [list(r) for r in split.pieces] == [[0, 1], [2, 3], [4, 5], [6, 7], [8, 9]]
    assert split.owner == [1, 0, 1, 1, 1] and split.makespan == 8
    assert split.subgoals == [goal(problem, "(and (clear b) (arm-empty))")]
    # Consecutive stretches for 3 agents (10 actions, a third each by the pieces' middles):
    # P1 P2 | P3 | P4 P5. The first agent leaves what later stretches use and it made
    # true (clear c and clear d held initially), the second the goal literal c on d.
    chunks = split_plan(problem, TALL_TOWER_PLAN, 3, BW, assign="chunks")
    assert chunks.owner == [0, 0, 1, 2, 2]
    assert chunks.subgoals == [
        goal(problem, "(and (clear a) (clear b) (on-table c) (arm-empty))"),
        goal(problem, "(and (on c d) (arm-empty))"),
    ]
    run = run_twostep(
        MethodRequest(
            task, 2, FAST, BW, PlanSplitDecomposer(BW), sa_plan=sa_result(TALL_TOWER_PLAN)
        )
    )
    assert [s["status"] for s in run.subgoals] == ["accepted"]
    assert run.exec_length is not None and run.exec_length < len(TALL_TOWER_PLAN)
    check_valid_run(problem, run, BW)


def test_barman_three_shakers(tmp_path: Path, data_root: Path) -> None:
    # Each cocktail is two pieces (prepare the shaker with both hands free at the end, then
    # shake and pour), on its own shot and shaker: three independent chains of 8 + 4
    # actions. Three agents take one cocktail each (12 steps); the helpers keep their
    # cocktail and hand both hands back empty.
    task = copy_task(tmp_path, data_root, "barman")
    problem = task.problem
    assert len(BARMAN_PLAN) == 36
    split = split_plan(problem, BARMAN_PLAN, 3, BARMAN)
    assert [len(r) for r in split.pieces] == [8, 4] * 3
    assert split.owner == [0, 0, 1, 1, 2, 2] and split.makespan == 12
    # the same pieces when cut by what is held: no hand holds two things at once here
    held = split_plan(problem, BARMAN_PLAN, 3, BARMAN, cut="holding")
    assert held.pieces == split.pieces and held.subgoals == split.subgoals
    hands = "(handempty left) (handempty right)"
    assert split.subgoals == [
        goal(problem, f"(and (contains shot1 cocktail1) {hands})"),
        goal(problem, f"(and (contains shot2 cocktail2) {hands})"),
    ]
    # Two agents: the first takes cocktails 1 and 3 (24 steps either way)
    two = split_plan(problem, BARMAN_PLAN, 2, BARMAN)
    assert two.makespan == 24
    assert two.subgoals == [
        goal(problem, f"(and (contains shot1 cocktail1) (contains shot4 cocktail3) {hands})")
    ]
    run = run_twostep(
        MethodRequest(
            task, 3, FAST, BARMAN, PlanSplitDecomposer(BARMAN), sa_plan=sa_result(BARMAN_PLAN)
        )
    )
    assert [s["status"] for s in run.subgoals] == ["accepted", "accepted"]
    assert run.exec_length is not None and run.exec_length < len(BARMAN_PLAN)
    check_valid_run(problem, run, BARMAN)


def test_termes_tower_helper_builds_the_ramp(tmp_path: Path, data_root: Path) -> None:
    # Free states are those without a block in hand, so the moves back to the depot are
    # pieces of their own. The ramp on p1 (create, place d->p1) does not depend on the
    # base on p2 (built from p3), so a second agent builds it meanwhile; the top needs
    # both, and taking the ramp away needs the top. Helper subgoal: the ramp, height 1 on
    # p1 -- partial progress that is not a goal literal (the goal wants p1 at 0).
    task = copy_task(tmp_path, data_root, "termes", TERMES_TOWER)
    problem = task.problem
    split = split_plan(problem, TERMES_PLAN, 2, TERMES)
    assert [list(r) for r in split.pieces] == [[0, 1, 2], [3], [4, 5], [6, 7, 8], [9], [10, 11]]
    assert split.owner == [1, 0, 0, 1, 0, 1] and split.makespan == 8
    assert split.subgoals == [goal(problem, "(and (height p1 n1) (not (has-block)))")]
    # Cut by what the agent holds: a piece is a block's way from creation to placement
    # (or removal to destruction); walking is left to the planner and counted as travel
    # of the next piece, so every piece takes 3 steps. Same helper, same subgoal.
    held = split_plan(problem, TERMES_PLAN, 2, TERMES, cut="holding")
    assert held.pieces == [[0, 2], [4, 5], [6, 8], [10, 11]]
    assert held.owner == [1, 0, 1, 1] and held.makespan == 9
    assert held.subgoals == split.subgoals
    # lama-first's main plan after the ramp is not the shortest (it dismantles the ramp
    # for the base): the joint schedule is valid, and the fallback keeps it from costing.
    run = run_twostep(MethodRequest(task, 2, FAST, TERMES, PlanSplitDecomposer(TERMES), sa_plan=sa_result(TERMES_PLAN), fallback_if_longer=False))  # fmt: skip
    assert [s["status"] for s in run.subgoals] == ["accepted"]
    assert run.plans["agent1"] == ["(create-block d)", "(place-block d p1 n0 n1)"]
    check_valid_run(problem, run, TERMES)
    run = run_twostep(
        MethodRequest(
            task, 2, FAST, TERMES, PlanSplitDecomposer(TERMES), sa_plan=sa_result(TERMES_PLAN)
        )
    )
    assert run.exec_length is not None and run.exec_length <= len(TERMES_PLAN)
    check_valid_run(problem, run, TERMES)


def test_pipeline_plans_sa_itself_when_not_given(tmp_path: Path) -> None:
    task = blocks_task(tmp_path, TWO_TOWERS)
    run = run_twostep(MethodRequest(task, 2, FAST, BW, PlanSplitDecomposer(BW)))
    assert [c.role for c in run.planner_calls][-2:] == ["helper", "main"]
    assert run.sa_length is not None and run.sa_time_included_s is not None
    assert run.planning_time_s >= sum(c.result.planner_time_s for c in run.planner_calls)
    check_valid_run(task.problem, run, BW)


def test_no_plan_no_helper(tmp_path: Path) -> None:
    task = blocks_task(tmp_path, TWO_TOWERS)
    decomposer = PlanSplitDecomposer(BW)
    assert decomposer.propose(DecompositionRequest(task, 2)) == []
    assert decomposer.propose(DecompositionRequest(task, 1, sa_plan=TWO_TOWERS_PLAN)) == []


def test_fallback_if_longer(tmp_path: Path) -> None:
    # A helper that builds the d-e-f tower "the long way" (via a detour the scorer cannot
    # hide) cannot beat SA's 4 steps for a one-tower task; with the fallback on, the SA
    # plan comes back and says why, with it off the longer schedule stays.
    task = blocks_task(
        tmp_path,
        blocks_problem(
            "(on-table a) (clear a) (on-table b) (clear b) (on-table c) (clear c) (arm-empty)",
            "(on a b) (on b c)",
            "a b c",
        ),
    )
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    assert sa.exec_length == 4
    sa_plan = sa.planner_calls[0].result

    class Wasteful:  # asks a helper to stack c on a first: the main agent must undo it
        name = "wasteful"

        def propose(self, request: DecompositionRequest) -> list:
            from twostep.decomposers.base import SubgoalProposal

            return [SubgoalProposal(helper=1, pddl="(and (on c a) (arm-empty))")]

    kept = run_twostep(
        MethodRequest(task, 2, FAST, BW, Wasteful(), sa_plan=sa_plan, fallback_if_longer=False)
    )
    assert kept.exec_length is not None and kept.exec_length > 4 and kept.fallback is None
    check_valid_run(task.problem, kept, BW)
    back = run_twostep(MethodRequest(task, 2, FAST, BW, Wasteful(), sa_plan=sa_plan))
    assert back.exec_length == 4 and list(back.plans) == ["agent0"]
    assert back.fallback == f"joint schedule longer than SA ({kept.exec_length} > 4)"
    assert [s["status"] for s in back.subgoals] == ["unused"]
    assert back.to_dict()["sa_time_included_s"] == round(sa_plan.planner_time_s, 4)
    check_valid_run(task.problem, back, BW)


@pytest.mark.slow
@pytest.mark.parametrize("agents", [2, 3])
def test_real_sa_plans_revalidate(tmp_path: Path, data_root: Path, agents: int) -> None:
    """On a real barman and termes task the schedules re-validate both ways."""
    for domain, preds in (("barman", BARMAN), ("termes", TERMES)):
        task = load_task(domain, 1, data_root)
        run = run_twostep(
            MethodRequest(
                task, agents, FAST, preds, PlanSplitDecomposer(preds), fallback_if_longer=False
            )
        )
        check_valid_run(task.problem, run, preds)
