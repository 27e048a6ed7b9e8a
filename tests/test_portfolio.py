"""twostep.methods.portfolio: several decompositions through TwoStep, the shortest schedule kept.

Lengths are derived by hand on blocksworld tasks small enough for that, and on a tiny bar
(:data:`CUPS_DOMAIN`) whose planner calls are scripted (no Fast Downward: each plan is
written by hand); every returned schedule is re-validated by ``check_run`` and by
unified-planning on the sequentialised N-agent schedule
(:func:`tests.test_plan_split.up_validate_run`).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import blocks_problem
from tests.examples import (
    BW,
    CUPS,
    CUPS_SA_PLAN,
    TALL_TOWER,
    TALL_TOWER_PLAN,
    TWO_TOWERS,
)
from tests.support.plans import FAST, blocks_task, check_valid_run, cups_task, sa_result
from twostep.decomposers.base import DecompositionRequest, SubgoalProposal
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.methods import MethodRequest
from twostep.methods.portfolio import Portfolio, run_portfolio
from twostep.methods.steps import Steps
from twostep.pddl import Problem
from twostep.planner import PlannerSettings, PlanResult, Status
from twostep.tasks.benchmark import load_task


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
    task = blocks_task(tmp_path, TWO_TOWERS)
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
    check_valid_run(task.problem, run, BW)
    assert run.to_dict()["candidates"] == rows  # result.json lists them


def test_portfolio_finds_partial_progress_and_fewer_agents(tmp_path: Path) -> None:
    # The tall tower with the hand-written SA plan of test_plan_split (10 actions):
    # goal-split sees one component (no helper: the SA plan), plan-split lets a helper
    # clear b (the same subgoal for 3 agents as for 2). The candidates are the members with
    # 3 agents, then with 2; the repeats are recognised, not planned again.
    task = blocks_task(tmp_path, TALL_TOWER)
    sa = sa_result(TALL_TOWER_PLAN)
    run = run_portfolio(MethodRequest(task, 3, FAST, BW, sa_plan=sa), Portfolio())
    rows = run.extra["candidates"]
    members = ["plan-split", "plan-split-holding", "plan-split-holding-goal", "goal-split"]
    members += [f"{m}-chunks" for m in members[:3]]
    assert [(r["decomposer"], r["agents"]) for r in rows[:15]] == [
        (m, n) for n in (3, 2) for m in members
    ] + [("plan-deal", 3)]
    assert rows[0]["accepted"] == 1 and rows[0]["exec_length"] < 10
    assert rows[1]["same_as"] == 0  # blocksworld: the same pieces either way
    # goal literals only: clearing b achieves none, so no helper and the SA plan
    assert rows[2]["fallback"] == "no helper subgoal proposed" and rows[2]["exec_length"] == 10
    assert rows[3]["same_as"] == 2  # goal-split: one component, no helper either
    assert [r.get("same_as") for r in rows[7:11]] == [0, 0, 2, 2]  # 2 agents: as with 3
    # then each joint run's plans (a helper accepted, no fallback), one after the other,
    # dealt to 3 agents. None can beat 5 steps: unstack d b, putdown d, stack c d, stack b
    # c, stack a b follow one another in any schedule; a tie keeps the earlier candidate.
    joint = [k for k, r in enumerate(rows[:14]) if r.get("accepted") and r["fallback"] is None]
    assert [r["dealt_from"] for r in rows[15:]] == joint and joint
    assert all(r["agents"] == 3 and r["exec_length"] >= rows[14]["exec_length"] for r in rows[15:])
    assert (
        run.extra["candidate"]
        == min((r["exec_length"], k) for k, r in enumerate(rows) if "same_as" not in r)[1]
    )
    assert run.exec_length == min(r["exec_length"] for r in rows)
    assert run.success and run.exec_length < 10
    check_valid_run(task.problem, run, BW)


def test_portfolio_falls_back_to_sa_when_every_candidate_is_longer(tmp_path: Path) -> None:
    # One tower a-b-c (SA: 4 actions, nothing to share); the only candidate asks a helper
    # to put c on a, which the main agent has to undo.
    task = blocks_task(
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
    check_valid_run(task.problem, run, BW)
    kept = run_portfolio(MethodRequest(task, 2, FAST, BW, fallback_if_longer=False), portfolio)
    assert kept.exec_length == row["exec_length"] and kept.fallback is None
    check_valid_run(task.problem, kept, BW)
    one = run_portfolio(MethodRequest(task, 1, FAST, BW), portfolio)
    assert one.extra["candidates"] == [] and one.exec_length == 4
    assert one.fallback == "no candidate (one agent)"


# After the helper served g1 from c1, the main agent takes the clean cups c2 and c3
CUPS_MAIN_PLAN = (
    "(take c2)", "(fill c2)", "(serve c2 g2)", "(put c2)",
    "(take c3)", "(fill c3)", "(serve c3 g3)",
)  # fmt: skip


def scripted_planner(helper: tuple[str, ...]) -> Steps:
    """Steps whose planner returns ``helper`` for the helper's subgoal (served g1) and
    :data:`CUPS_MAIN_PLAN` for the whole goal (every plan written by hand)."""

    def plan(problem: Problem, settings: PlannerSettings, call: object = None) -> PlanResult:
        whole = "g3" in problem.goal.to_pddl()
        return PlanResult(Status.SOLVED, CUPS_MAIN_PLAN if whole else helper, 0.0, 0.0)

    return Steps(plan=plan)


def test_portfolio_deals_the_twostep_plans_again(tmp_path: Path) -> None:
    # N = 3, one helper asked to serve g1. The SA plan is one chain on c1 (each action
    # needs the cup as the one before left it; no action can go: without a wash the next
    # fill does not apply), so plan-deal has only the cleaned SA plan: 9 steps. TwoStep:
    # the helper takes c1, fills it, serves g1, puts it back (4), the main agent runs its
    # 7 actions with its one hand meanwhile: 7 steps. Concatenated (11 actions, valid: the
    # helper's hand is free again) the three cups are three pieces take-fill-serve(-put),
    # one per agent; the puts do not serve the goal: 3 steps.
    task = cups_task(tmp_path)
    helper = ("(take c1)", "(fill c1)", "(serve c1 g1)", "(put c1)")
    scripted = Scripted("serve-g1", "(served g1)")
    request = MethodRequest(
        task, 3, FAST, CUPS, steps=scripted_planner(helper), sa_plan=sa_result(CUPS_SA_PLAN)
    )
    # plan-deal without rebinding: rebinding spreads the chain over the three cups itself
    # (tests/test_rebind.py), and this test is about the re-deal
    run = run_portfolio(request, Portfolio(members=[scripted], rebind=False))
    rows = run.extra["candidates"]
    assert [(r["decomposer"], r["agents"]) for r in rows] == [
        ("serve-g1", 3), ("serve-g1", 2), ("plan-deal", 3), ("plan-deal<serve-g1>", 3)
    ]  # fmt: skip
    assert rows[0]["exec_length"] == 7 and rows[1]["same_as"] == 0
    assert rows[2]["exec_length"] == 9
    assert rows[3]["dealt_from"] == 0 and rows[3]["exec_length"] == 3
    assert run.exec_length == 3 and run.fallback is None and run.extra["dealt_from"] == 0
    assert run.extra["agents_used"] == 3 and run.sa_length == 9
    served = {a.split()[2].rstrip(")") for p in run.plans.values() for a in p if "serve" in a}
    assert served == {"g1", "g2", "g3"} and sorted(map(len, run.plans.values())) == [3, 3, 3]
    # the plans came from the helper's and the main agent's planner calls
    assert [c.role for c in run.planner_calls] == ["helper", "main"]
    assert "deal" not in run.extra and run.extra["redeal"][0]["cleaned_sa_length"] == 11
    check_valid_run(task.problem, run, CUPS)
    # without the re-deal the TwoStep run wins
    alone = run_portfolio(request, Portfolio(members=[scripted], redeal=False, rebind=False))
    assert alone.exec_length == 7 and len(alone.extra["candidates"]) == 3
    check_valid_run(task.problem, alone, CUPS)


def test_portfolio_skips_a_concatenation_that_does_not_apply(tmp_path: Path) -> None:
    # The helper keeps c1 in its hand after serving g1; the joint run is valid (the main
    # agent has its own hand: 7 steps), but one agent running both plans cannot take c2
    # with c1 in hand, and no walk frees a hand (putting a cup back is no walk: it changes
    # the shelf): that re-deal is skipped with the reason, the TwoStep run wins.
    task = cups_task(tmp_path)
    helper = ("(take c1)", "(fill c1)", "(serve c1 g1)")
    scripted = Scripted("serve-g1", "(served g1)")
    request = MethodRequest(
        task, 3, FAST, CUPS, steps=scripted_planner(helper), sa_plan=sa_result(CUPS_SA_PLAN)
    )
    run = run_portfolio(request, Portfolio(members=[scripted], rebind=False))  # as above
    rows = run.extra["candidates"]
    assert [r["decomposer"] for r in rows] == ["serve-g1", "serve-g1", "plan-deal",
                                               "plan-deal<serve-g1>"]  # fmt: skip
    skipped = rows[3]
    assert skipped["dealt_from"] == 0 and skipped["exec_length"] is None
    assert "no walk to where (take c2) applies" in skipped["skipped"]
    # every row carries its own time (the skipped one: its stitching); with the SA plan's,
    # they make the run's planning time
    own = sum(r.get("planning_time_s", 0.0) for r in rows)
    assert "planning_time_s" in skipped
    assert run.planning_time_s == pytest.approx(own + (run.sa_time_included_s or 0.0), abs=1e-3)
    assert rows[0]["exec_length"] == 7 and rows[2]["exec_length"] == 9
    assert run.exec_length == 7 and run.extra["candidate"] == 0 and run.fallback is None
    check_valid_run(task.problem, run, CUPS)


def test_portfolio_lite_runs_two_members_with_n_agents_beside_plan_deal(data_root: Path) -> None:
    # barman p01 (one shot glass carries every ingredient in the SA plan): portfolio-lite's
    # candidates are plan-split cut by holding and goal-split, with N = 3 agents only, then
    # plan-deal, then the two TwoStep candidates' plans dealt again. Its schedule is the
    # shortest candidate's, never longer than plan-deal's own run (a candidate), and here
    # shorter: the re-planned glasses deal into more than one chain. Checked by check_run,
    # unified-planning, and the independent validator on the original files.
    from checkers import IndependentValidator
    from twostep.methods import run_single_agent
    from twostep.methods.plan_deal import run_plan_deal
    from twostep.methods.registry import method_for

    preds = ["handempty", "holding"]
    task = load_task("barman", 1, data_root)
    sa_plan = run_single_agent(MethodRequest(task, planner=FAST)).planner_calls[0].result
    request = MethodRequest(task, 3, FAST, preds, sa_plan=sa_plan)
    run = method_for("twostep", "portfolio-lite")(request)
    names = [(row["decomposer"], row["agents"]) for row in run.extra["candidates"]]
    assert names == [
        ("plan-split-holding", 3), ("goal-split", 3), ("plan-deal", 3),
        ("plan-deal<plan-split-holding>", 3), ("plan-deal<goal-split>", 3),
    ]  # fmt: skip
    assert run.decomposer == "portfolio-lite" and run.agents == 3
    lengths = [row["exec_length"] for row in run.extra["candidates"] if row["exec_length"]]
    assert run.exec_length == min(lengths)
    deal = run_plan_deal(request)
    assert deal.exec_length is not None and run.exec_length is not None
    assert run.exec_length < deal.exec_length
    check_valid_run(task.problem, run, preds)
    verdict = IndependentValidator(task.domain_path, task.problem_path).check_schedule(
        run.agent_order, run.plans, run.schedule, preds
    )
    assert verdict.valid, verdict
