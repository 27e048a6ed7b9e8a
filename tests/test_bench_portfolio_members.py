"""bench/bench_portfolio_members.py: a smaller portfolio replayed from a portfolio's rows,
checked on hand-made rows whose answers are worked out here by hand."""

from __future__ import annotations

from typing import Any

import pytest

from evaluation.portfolio_members import evaluate, members, replay


def run(domain: str, agents: int, sa: int, candidates: list[dict[str, Any]]) -> dict[str, Any]:
    return {"method": "portfolio", "domain": domain, "agents": agents, "sa_length": sa,
            "candidates": candidates}  # fmt: skip


# N = 3: goal-split planned with 3 and 2 agents, plan-split with 3 (same subgoals as the
# goal-split run: not planned again), plan-deal, and the re-deals of rows 0 and 1.
ROW = run("barman", 3, 30, [
    {"decomposer": "goal-split", "agents": 3, "exec_length": 25, "planning_time_s": 0.5},
    {"decomposer": "goal-split", "agents": 2, "exec_length": 14, "planning_time_s": 0.4},
    {"decomposer": "plan-split", "agents": 3, "same_as": 0, "exec_length": 25},
    {"decomposer": "plan-deal", "agents": 3, "exec_length": 20, "planning_time_s": 0.01},
    {"decomposer": "plan-deal<goal-split>", "agents": 3, "dealt_from": 0, "exec_length": 16,
     "planning_time_s": 0.02},
    {"decomposer": "plan-deal<goal-split>", "agents": 3, "dealt_from": 1, "exec_length": 12,
     "planning_time_s": 0.03},
])  # fmt: skip


def test_members_are_the_twostep_sources_in_order() -> None:
    assert members([ROW]) == ["goal-split", "plan-split"]


def test_a_subset_keeps_plan_deal_and_its_n_agent_candidates_and_their_re_deals() -> None:
    # plan-deal alone: 20, nothing added
    assert replay(ROW, ()) == (20, 0.0)
    # goal-split with N = 3 only: its run (25) and its re-deal (16); the 2-agent run (14)
    # and its re-deal (12) are not in a portfolio of N agents only
    best, added = replay(ROW, ("goal-split",))
    assert best == 16 and added == pytest.approx(0.5 + 0.02)
    # plan-split had goal-split's subgoals: its length and re-deal are row 0's, at no cost
    # of its own but the re-deal's
    best, added = replay(ROW, ("plan-split",))
    assert best == 16 and added == pytest.approx(0.02)


def test_the_macro_is_the_mean_over_domains_of_the_per_task_mean() -> None:
    other = run("grippers", 3, 10, [
        {"decomposer": "goal-split", "agents": 3, "exec_length": 6, "planning_time_s": 0.2},
        {"decomposer": "plan-deal", "agents": 3, "exec_length": 8, "planning_time_s": 0.0},
    ])  # fmt: skip
    result = evaluate([ROW, other, {**other, "agents": 2}], 3, ("goal-split",))
    assert result["domains"] == {"barman": pytest.approx(16 / 30), "grippers": 0.6}
    assert result["macro"] == pytest.approx((16 / 30 + 0.6) / 2)
    assert result["added_s"] == pytest.approx(0.52)  # barman's median, the larger
