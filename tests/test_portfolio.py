"""twostep.methods.portfolio: several decompositions through TwoStep, the shortest schedule kept.

Lengths are derived by hand on blocksworld tasks small enough for that; every returned
schedule is re-validated by ``check_run`` and by unified-planning on the sequentialised
N-agent schedule (:func:`tests.test_plan_split.up_validate_run`).
"""

from __future__ import annotations

from pathlib import Path

from tests.conftest import blocks_problem
from tests.test_plan_split import (
    BW,
    FAST,
    TALL_TOWER,
    TALL_TOWER_PLAN,
    TWO_TOWERS,
    _blocks,
    _check,
    sa_result,
)
from twostep.decomposers.base import DecompositionRequest, SubgoalProposal
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.methods import MethodRequest
from twostep.methods.portfolio import Portfolio, run_portfolio


class Scripted:
    """A decomposer with one fixed helper subgoal."""

    def __init__(self, name: str, pddl: str):
        self.name, self.pddl = name, pddl

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        return [SubgoalProposal(helper=1, pddl=self.pddl)]


def test_portfolio_keeps_the_shortest_candidate(tmp_path: Path) -> None:
    # Two towers a-b-c and d-e-f from blocks on the table (SA: 8 actions). goal-split gives
    # one tower to the helper: 4 steps. The scripted candidate puts a on b first, so the
    # main agent must take a off again before b goes on c: longer than 4.
    task = _blocks(tmp_path, TWO_TOWERS)
    wasteful = Scripted("wasteful", "(and (on a b) (arm-empty))")
    portfolio = Portfolio(members=[wasteful, GoalSplitDecomposer(BW)], deals=())
    run = run_portfolio(MethodRequest(task, 2, FAST, BW), portfolio)
    rows = run.extra["candidates"]
    assert [(r["decomposer"], r["agents"]) for r in rows] == [("wasteful", 2), ("goal-split", 2)]
    assert rows[1]["exec_length"] == 4 and rows[0]["exec_length"] > 4
    assert run.exec_length == 4 and run.fallback is None
    assert run.decomposer == "portfolio" and run.agents == 2 and run.extra["agents_used"] == 2
    assert run.subgoals[0]["pddl"] == "(and (arm-empty) (on d e) (on e f))"
    # every candidate's planner time counts, and the SA plan's once
    candidates = sum(r["planning_time_s"] for r in rows)
    assert abs(run.planning_time_s - candidates - (run.sa_time_included_s or 0.0)) < 1e-3
    _check(task.problem, run, BW)
    assert run.to_dict()["candidates"] == rows  # result.json lists them


def test_portfolio_finds_partial_progress_and_fewer_agents(tmp_path: Path) -> None:
    # The tall tower with the hand-written SA plan of test_plan_split (10 actions):
    # goal-split sees one component (no helper: the SA plan), plan-split lets a helper
    # clear b (the same subgoal for 3 agents as for 2). The candidates are the members with
    # 3 agents, then with 2; the repeats are recognised, not planned again.
    task = _blocks(tmp_path, TALL_TOWER)
    sa = sa_result(TALL_TOWER_PLAN)
    run = run_portfolio(MethodRequest(task, 3, FAST, BW, sa_plan=sa), Portfolio())
    rows = run.extra["candidates"]
    members = ["plan-split", "plan-split-holding", "plan-split-holding-goal", "goal-split"]
    members += [f"{m}-chunks" for m in members[:3]]
    assert [(r["decomposer"], r["agents"]) for r in rows] == [
        (m, n) for n in (3, 2) for m in members
    ] + [("plan-deal", 3)]
    assert rows[0]["accepted"] == 1 and rows[0]["exec_length"] < 10
    assert rows[1]["same_as"] == 0  # blocksworld: the same pieces either way
    # goal literals only: clearing b achieves none, so no helper and the SA plan
    assert rows[2]["fallback"] == "no helper subgoal proposed" and rows[2]["exec_length"] == 10
    assert rows[3]["same_as"] == 2  # goal-split: one component, no helper either
    assert [r.get("same_as") for r in rows[7:11]] == [0, 0, 2, 2]  # 2 agents: as with 3
    assert run.exec_length == min(r["exec_length"] for r in rows)
    assert run.success and run.exec_length < 10
    _check(task.problem, run, BW)


def test_portfolio_falls_back_to_sa_when_every_candidate_is_longer(tmp_path: Path) -> None:
    # One tower a-b-c (SA: 4 actions, nothing to share); the only candidate asks a helper
    # to put c on a, which the main agent has to undo.
    task = _blocks(
        tmp_path,
        blocks_problem(
            "(on-table a) (clear a) (on-table b) (clear b) (on-table c) (clear c) (arm-empty)",
            "(on a b) (on b c)",
            "a b c",
        ),
    )
    portfolio = Portfolio(members=[Scripted("wasteful", "(and (on c a) (arm-empty))")], deals=())
    run = run_portfolio(MethodRequest(task, 2, FAST, BW), portfolio)
    (row,) = run.extra["candidates"]
    assert row["exec_length"] > 4
    assert run.exec_length == 4 and list(run.plans) == ["agent0"]
    assert run.fallback == f"joint schedule longer than SA ({row['exec_length']} > 4)"
    _check(task.problem, run, BW)
    kept = run_portfolio(MethodRequest(task, 2, FAST, BW, fallback_if_longer=False), portfolio)
    assert kept.exec_length == row["exec_length"] and kept.fallback is None
    _check(task.problem, kept, BW)
    one = run_portfolio(MethodRequest(task, 1, FAST, BW), portfolio)
    assert one.extra["candidates"] == [] and one.exec_length == 4
    assert one.fallback == "no candidate (one agent)"
