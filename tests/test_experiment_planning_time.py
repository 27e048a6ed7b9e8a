"""experiment=planning_time (the paper's planning-time claim) and the report view that answers it.

Three independent checks: the experiment composes to the grid and settings the issue asks
for (Hydra's compose API, no planner); TwoStep's planning time holds no SA planner time
unless it returns the SA plan (real pipeline runs, lama-first on tiny blocksworld tasks,
with an SA result whose planner time is made huge so that any inclusion shows); and the
report view's numbers, derived by hand from a made-up run table.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from hydra import compose, initialize_config_dir
from omegaconf import DictConfig

from flows.build import open_decomposer
from flows.config import register
from flows.sweep_state import count_jobs
from tests.conftest import blocks_problem
from tests.examples import BW
from tests.support.plans import FAST, blocks_task
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.methods import MethodRequest, run_single_agent, run_twostep
from twostep.report import build_report, render_markdown
from twostep.report.planning_time import planning_time_view, view_rows

CONF = Path(__file__).resolve().parent.parent / "conf"
PLACES = ["output.root=/tmp/twostep-out", "data.root=/tmp/twostep-data"]


@pytest.fixture(scope="module")
def hydra_conf() -> Iterator[None]:
    register()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        yield


def make(*overrides: str) -> DictConfig:
    return compose(
        "config", overrides=[*PLACES, "experiment=planning_time", *overrides],
        return_hydra_config=True,
    )  # fmt: skip


# ------------------------------------------------------------------ the experiment


def test_experiment_composes_to_the_issue_grid(hydra_conf: None) -> None:
    cfg = make()
    assert cfg.planner.alias == "lama"  # anytime LAMA, the paper's alias
    assert cfg.planner.time_limit_s == 20
    assert cfg.method.fallback_if_longer is False  # paper-faithful TwoStep
    assert cfg.decomposer.name == "goal-split"
    params = cfg.hydra.sweeper.params
    assert params.domain.split(",") == ["barman", "blocksworld", "termes", "tyreworld", "grippers"]
    assert [int(t) for t in params.task.split(",")] == [1, 6, 11, 16]
    assert [int(n) for n in params.agents.split(",")] == [2, 3, 4]
    assert params.method.split(",") == ["sa", "ma", "twostep"]
    assert str(params.seed) == "0"
    assert count_jobs(cfg) == 5 * 4 * 3 * 3
    launcher = cfg.hydra.launcher  # one worker: the basic launcher, or ours with one job
    assert launcher._target_.endswith("BasicLauncher") or launcher.n_jobs == 1


def test_every_method_of_the_grid_composes(hydra_conf: None) -> None:
    for method in ("sa", "ma", "twostep"):
        cfg = make(f"method={method}", "agents=3", "domain=termes", "task=16")
        assert cfg.method.name == method and cfg.planner.time_limit_s == 20


def test_the_decomposer_does_not_read_the_sa_plan(hydra_conf: None) -> None:
    """TwoStep's subgoals come from the task alone, as the paper's LLM's do."""
    with open_decomposer(make()) as decomposer:
        assert decomposer.name == "goal-split"
        assert not getattr(decomposer, "needs_sa_plan", False)


# ------------------------------------------------------------------ what TwoStep's time counts

HUGE = 1000.0  # an SA planner time no real call here comes near


def _sa_with_huge_time(task: Any) -> Any:
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    return dataclasses.replace(sa.planner_calls[0].result, planner_time_s=HUGE)


def test_twostep_with_helpers_does_not_count_the_sa_plan(tmp_path: Path) -> None:
    task = blocks_task(tmp_path)  # two towers: goal-split gives the helper one of them
    sa_plan = _sa_with_huge_time(task)
    run = run_twostep(
        MethodRequest(
            task, 2, FAST, BW, GoalSplitDecomposer(BW), sa_plan=sa_plan, fallback_if_longer=False
        )
    )
    assert run.success and run.fallback is None
    assert [c.role for c in run.planner_calls] == ["helper", "main"]
    assert run.sa_time_included_s is None
    own = sum(c.result.planner_time_s for c in run.planner_calls)
    assert own <= run.planning_time_s < HUGE
    assert run.planning_time_s == pytest.approx(own + run.state_editing_time_s, abs=1e-6)


def test_twostep_without_a_helper_counts_the_sa_plan_it_returns(tmp_path: Path) -> None:
    one_tower = blocks_problem(
        " ".join(f"(on-table {b}) (clear {b})" for b in "abc") + " (arm-empty)",
        "(on a b) (on b c)",
        "a b c",
    )
    task = blocks_task(tmp_path, one_tower)  # one component: goal-split proposes no helper
    sa_plan = _sa_with_huge_time(task)
    run = run_twostep(
        MethodRequest(
            task, 2, FAST, BW, GoalSplitDecomposer(BW), sa_plan=sa_plan, fallback_if_longer=False
        )
    )
    assert run.success and run.fallback is not None
    assert run.sa_time_included_s == HUGE
    assert run.planning_time_s >= HUGE


# ------------------------------------------------------------------ the report view


def _run(domain: str, task: int, method: str, agents: int, time: float, length: float,
         limit_hits: int = 0, accepted: int | None = None, status: str = "success") -> dict[str, Any]:  # fmt: skip
    row: dict[str, Any] = {
        "domain": domain, "task": task, "method": method, "agents": agents, "seed": 0,
        "decomposer": "goal-split" if method == "twostep" else "", "status": status,
        "planning_time_s": time, "exec_length": length, "planner_timeouts": float(limit_hits),
    }  # fmt: skip
    if accepted is not None:
        row["subgoals_accepted"] = float(accepted)
    return row


def hand_made_runs() -> pd.DataFrame:
    rows = [
        # domain A: SA 3 s / 15 steps; MA(2) 15 s / 10, one of two at its limit;
        # TwoStep(2) 4.5 s / 14.5, one of two without a helper (a failed run aside)
        _run("A", 1, "sa", 1, 2.0, 10.0), _run("A", 2, "sa", 1, 4.0, 20.0),
        _run("A", 1, "ma", 2, 20.0, 8.0, limit_hits=1), _run("A", 2, "ma", 2, 10.0, 12.0),
        _run("A", 1, "twostep", 2, 3.0, 9.0, accepted=1),
        _run("A", 2, "twostep", 2, 6.0, 20.0, accepted=0),
        _run("A", 3, "twostep", 2, 99.0, 99.0, accepted=1, status="failed"),
        _run("A", 1, "ma", 3, 8.0, 7.0, limit_hits=1), _run("A", 2, "ma", 3, 8.0, 9.0),
        _run("A", 1, "twostep", 3, 2.0, 8.0, accepted=2),
        _run("A", 2, "twostep", 3, 2.0, 8.0, accepted=2),
        # domain B: SA 1 s / 6; MA(2) 5 s / 4, both at the limit; TwoStep(2) 6 s / 5;
        # TwoStep(3) without an MA(3) to compare with
        _run("B", 1, "sa", 1, 1.0, 5.0), _run("B", 2, "sa", 1, 1.0, 7.0),
        _run("B", 1, "ma", 2, 4.0, 4.0, limit_hits=1),
        _run("B", 2, "ma", 2, 6.0, 4.0, limit_hits=1),
        _run("B", 1, "twostep", 2, 5.0, 5.0, accepted=1),
        _run("B", 2, "twostep", 2, 7.0, 5.0, accepted=2),
        _run("B", 1, "twostep", 3, 1.0, 4.0, accepted=2),
    ]  # fmt: skip
    return pd.DataFrame.from_records(rows)


def test_view_numbers_are_the_hand_derived_ones() -> None:
    report = build_report(hand_made_runs())
    view = planning_time_view(report.summary, report.runs)
    cells = {(r["domain"], r["agents"]): r for r in view.to_dict("records")}
    assert set(cells) == {("A", 2), ("B", 2), ("all", 2), ("A", 3), ("all", 3)}
    a2, b2, all2 = cells["A", 2], cells["B", 2], cells["all", 2]
    assert (a2["sa_time_s"], a2["ma_time_s"], a2["twostep_time_s"]) == (3.0, 15.0, 4.5)
    assert a2["change_pct"] == pytest.approx(-70.0)  # (4.5 - 15) / 15
    assert (a2["sa_exec"], a2["ma_exec"], a2["twostep_exec"]) == (15.0, 10.0, 14.5)
    assert (a2["ma_at_limit"], a2["twostep_no_helper"]) == (0.5, 0.5)  # failed run left out
    assert b2["change_pct"] == pytest.approx(20.0)  # (6 - 5) / 5
    assert (b2["ma_at_limit"], b2["twostep_no_helper"]) == (1.0, 0.0)
    # all: the mean over domains of each mean, and the change of those means
    assert (all2["sa_time_s"], all2["ma_time_s"], all2["twostep_time_s"]) == (2.0, 10.0, 5.25)
    assert all2["change_pct"] == pytest.approx(-47.5)
    assert all2["ma_at_limit"] == pytest.approx(0.75)
    assert all2["paper_change_pct"] == pytest.approx(-50.1)
    assert cells["all", 3]["change_pct"] == pytest.approx(-75.0)  # A only: (2 - 8) / 8
    assert cells["all", 3]["paper_change_pct"] == pytest.approx(-60.3)
    assert set(view["twostep_series"]) == {"TwoStep (goal-split)"}
    assert set(view["ma_series"]) == {"MA"}


def test_view_is_rendered_in_the_report() -> None:
    report = build_report(hand_made_runs())
    headers, rows = view_rows(planning_time_view(report.summary, report.runs))
    assert headers[0] == "N" and len(rows) == 5
    text = render_markdown(report, "t", "s")
    assert "## TwoStep against MA: planning time per domain" in text
    assert "| 2 | A | 3.00 | 15.00 | 4.50 | -70.0 % |  | 15.0 / 10.0 / 14.5 | 50 % | 50 % |" in text
    assert "| 2 | **all** | 2.00 | 10.00 | 5.25 | -47.5 % | -50.1 % |" in text


def test_no_ma_runs_no_view() -> None:
    runs = hand_made_runs()
    report = build_report(runs[runs["method"] != "ma"])
    assert planning_time_view(report.summary, report.runs).empty
    assert "TwoStep against MA" not in render_markdown(report, "t", "s")
