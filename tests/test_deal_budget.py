"""plan-deal is bounded for any N (issue 39, finding 3): no deal to more agents than the
SA plan has pieces (an agent beyond them would stay idle), and a work budget that grows
with N and stops with the best deal so far, said so in result.json.

Before: blocksworld task 1 (8 actions, 4 pieces) took 11 s of planning at ``agents=100``,
65 s at 200, and ``agents=1000`` was silent for more than 400 s; every result used 2
agents and had length 5.

Every schedule here is re-validated by our simulator and by unified-planning's validator
on the original files (``tests/test_plan_split._check``).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import twostep.methods.plan_deal as plan_deal
from tests.conftest import DATA
from tests.support.plans import agent_predicates_of, check_valid_run
from twostep.dealing import Dealer
from twostep.methods import MethodRequest, RunResult, run_single_agent
from twostep.methods.plan_deal import deal_budget, run_plan_deal
from twostep.planner.results import PlanResult, Status
from twostep.tasks.benchmark import load_task

REPO = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent


def dealt(
    domain: str, task_id: int, agents: int, sa: PlanResult | None = None
) -> tuple[RunResult, PlanResult]:
    task = load_task(domain, task_id, DATA)
    if sa is None:
        sa = run_single_agent(MethodRequest(task)).planner_calls[0].result
    run = run_plan_deal(
        MethodRequest(task, agents, agent_predicates=agent_predicates_of(domain), sa_plan=sa)
    )
    check_valid_run(task.problem, run, agent_predicates_of(domain))
    return run, sa


def test_a_thousand_agents_get_the_deal_of_as_many_as_there_are_pieces() -> None:
    run, sa = dealt("blocksworld", 1, 1000)
    pieces = max(row.get("pieces", 0) for row in run.extra["deal"])
    assert run.extra["deal_agents"] == pieces == 4  # the probe's 4 pieces
    assert max(row["agents"] for row in run.extra["deal"]) == pieces
    at_pieces, _ = dealt("blocksworld", 1, pieces, sa)
    assert (run.exec_length, run.plans) == (at_pieces.exec_length, at_pieces.plans)
    assert run.exec_length is not None and sa.plan is not None
    assert run.exec_length <= len(sa.plan)


@pytest.mark.parametrize(("domain", "task_id"), [("blocksworld", 2), ("grippers", 1),
                                                 ("grippers", 6), ("blocksworld", 7)])  # fmt: skip
def test_agents_beyond_the_pieces_change_nothing(
    domain: str, task_id: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Dealt to every number up to pieces + 2 (the cap turned off) and to the pieces only:
    the same outcome."""
    capped, sa = dealt(domain, task_id, 6)
    pieces = capped.extra.get("deal_agents")
    assert pieces is not None and pieces < 6
    monkeypatch.setattr(Dealer, "most_pieces", lambda self, cuts: 10**6)
    uncapped, _ = dealt(domain, task_id, pieces + 2, sa)
    assert max(row["agents"] for row in uncapped.extra["deal"]) == pieces + 2
    assert (capped.exec_length, capped.plans, capped.schedule) == (
        uncapped.exec_length,
        uncapped.plans,
        uncapped.schedule,
    )


def test_the_budget_grows_with_n_up_to_its_most() -> None:
    budgets = [deal_budget(n) for n in range(1, 12)]
    assert budgets[:5] == [2_000_000, 2_000_000, 8_000_000, 18_000_000, 20_000_000]
    assert budgets == sorted(budgets) and deal_budget(1000) == plan_deal.DEAL_WORK_MAX


def test_a_spent_budget_keeps_the_best_deal_so_far(monkeypatch: pytest.MonkeyPatch) -> None:
    """A budget far too small for termes task 1 at N = 4: dealing stops early, and the
    outcome is the best deal found by then, valid and no longer than the SA plan."""
    full, sa = dealt("termes", 1, 4)
    assert "deal_budget" not in full.extra
    monkeypatch.setattr(plan_deal, "DEAL_WORK", 1_000)
    monkeypatch.setattr(plan_deal, "DEAL_WORK_MAX", 1_000_000)
    cut, _ = dealt("termes", 1, 4, sa)
    stopped = cut.extra["deal_budget"]
    assert stopped["work"] == 9_000 and stopped["spent"] >= stopped["work"]
    assert 2 <= stopped["agents"] <= 4
    assert "work budget" in cut.message and "the best deal so far" in cut.message
    assert cut.success and sa.plan is not None
    assert cut.exec_length is not None and cut.exec_length <= len(sa.plan)
    assert full.exec_length is not None and full.exec_length <= cut.exec_length


def test_twostep_with_a_thousand_agents_answers(tmp_path: Path) -> None:
    """The probe's command (a timeout turns a hang into a failure)."""
    done = subprocess.run(
        [str(BIN / "twostep"), "agents=1000", "task=1", f"output.root={tmp_path}/out",
         "mlflow.enabled=false", "orchestration.prefect=false"],
        capture_output=True, text=True, timeout=240, cwd=REPO,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    (path,) = (tmp_path / "out").glob("runs/*/*/result.json")
    result = json.loads(path.read_text())
    assert result["success"] and result["exec_length"] == 5 and result["deal_agents"] == 4


@pytest.mark.slow
@pytest.mark.timeout(3600)
def test_the_budget_never_binds_on_the_stored_runs() -> None:
    """The 120 SA plans of ``docs/bench/methods_deal.json`` (the 100 tasks, the stress and
    large sets) dealt again to 2, 3 and 4 agents: each length as stored, no budget hit."""
    rows = json.loads((REPO / "docs" / "bench" / "methods_deal.json").read_text())
    stored = {(r["data"], r["domain"], r["task"], r["agents"]): r["exec_length"]
              for r in rows if r["method"] == "plan-deal"}  # fmt: skip
    checked = 0
    for row in (r for r in rows if r["method"] == "sa"):
        task = load_task(row["domain"], row["task"], REPO / row["data"])
        sa = PlanResult(Status.SOLVED, tuple(row["plan"]), 0.0, 0.0)
        for agents in (2, 3, 4):
            request = MethodRequest(
                task, agents, agent_predicates=agent_predicates_of(row["domain"]), sa_plan=sa
            )
            run = run_plan_deal(request)
            key = (row["data"], row["domain"], row["task"], agents)
            assert run.exec_length == stored[key], key
            assert "deal_budget" not in run.extra, key
            checked += 1
    assert checked == 360
