"""twostep.methods.twostep: SA, MA and TwoStep end to end on small tasks (real Fast Downward)."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import blocks_problem
from tests.examples import BW
from tests.support.plans import FAST, blocks_task
from twostep.decomposers.base import DecompositionRequest, SubgoalProposal
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.methods import (
    MethodRequest,
    check_run,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)
from twostep.verify.validation import validate_plan


class Scripted:
    """A decomposer that returns fixed PDDL subgoals (for tests)."""

    name = "scripted"

    def __init__(self, *goals: str | None):
        self.goals = goals

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        return [SubgoalProposal(helper=i, pddl=g) for i, g in enumerate(self.goals, start=1)]


def _check(task, result) -> None:
    """The schedule re-validates and every agent's plan is valid in single-agent terms."""
    assert sorted(result.agent_order) == sorted(result.plans)
    check_run(task.problem, result, BW)
    assert result.exec_length == len(result.schedule)


def test_single_agent(tmp_path: Path) -> None:
    task = blocks_task(tmp_path)
    result = run_single_agent(MethodRequest(task, planner=FAST))
    assert result.success and result.exec_length == result.sa_length == len(result.plans["agent0"])
    assert validate_plan(task.problem, result.plans["agent0"]).valid
    assert result.to_dict()["schedule"][0][0][0] == "agent0"


def test_multi_agent_is_split_and_scored(tmp_path: Path) -> None:
    task = blocks_task(tmp_path)
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    result = run_multi_agent(MethodRequest(task, 2, FAST, BW, sa_length=sa.sa_length))
    assert result.success and result.exec_length is not None
    assert result.exec_length <= result.extra["sequential_length"]
    assert set(result.plans) <= {"agent0", "agent1"}
    _check(task, result)


def test_twostep_goal_split_runs_in_parallel(tmp_path: Path) -> None:
    task = blocks_task(tmp_path)
    result = run_twostep(MethodRequest(task, 2, FAST, BW, GoalSplitDecomposer(BW)))
    assert result.success and result.fallback is None
    assert [s["status"] for s in result.subgoals] == ["accepted"]
    assert set(result.plans) == {"agent0", "agent1"}
    total = sum(len(p) for p in result.plans.values())
    assert result.exec_length is not None and result.exec_length < total  # some steps in parallel
    assert any(len(step) == 2 for step in result.schedule)
    _check(task, result)
    roles = [c.role for c in result.planner_calls]
    assert roles == ["helper", "main"]
    assert result.planning_time_s >= sum(c.result.planner_time_s for c in result.planner_calls)


def test_bad_subgoals_are_discarded_with_reasons(tmp_path: Path) -> None:
    task = blocks_task(tmp_path)
    decomposer = Scripted(
        "(and (stacked a b))",  # unknown predicate
        "(on-table a)",  # already true
        "(and (on a b) (on b c) (on d e) (on e f))",  # the whole goal
    )
    result = run_twostep(MethodRequest(task, 4, FAST, BW, decomposer))
    reasons = [s["reason"] for s in result.subgoals]
    assert [s["status"] for s in result.subgoals] == ["discarded"] * 3
    assert "unknown predicate" in reasons[0]
    assert "already true" in reasons[1]
    assert "full goal" in reasons[2]
    # nothing survived: the single-agent plan, success guaranteed
    assert result.success and result.fallback == "no helper subgoal accepted"
    assert list(result.plans) == ["agent0"]


def test_unsolvable_subgoal_is_discarded(tmp_path: Path) -> None:
    task = blocks_task(tmp_path)
    result = run_twostep(
        MethodRequest(task, 3, FAST, BW, Scripted("(and (on a a))", "(and (on d e) (arm-empty))"))
    )
    assert result.subgoals[0]["status"] == "discarded"
    assert "unsolvable" in result.subgoals[0]["reason"]
    assert result.subgoals[1]["status"] == "accepted"
    assert set(result.plans) == {"agent0", "agent2"}
    _check(task, result)


def test_goal_already_holds(tmp_path: Path) -> None:
    task = blocks_task(
        tmp_path, blocks_problem("(on-table a) (clear a) (arm-empty)", "(on-table a)", "a")
    )
    for result in (
        run_single_agent(MethodRequest(task, planner=FAST)),
        run_multi_agent(MethodRequest(task, 3, FAST, BW)),
        run_twostep(MethodRequest(task, 3, FAST, BW, GoalSplitDecomposer(BW))),
    ):
        assert result.success and result.exec_length == 0 and result.schedule == []
