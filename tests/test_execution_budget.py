"""The scorer's search budget: time limit, the pipeline's score step, the config keys.

A budgeted answer is checked against the unbudgeted optimum (and the brute-force makespan
of tests/test_independent_checks.py on random cases): the schedule re-validates and the
optimum lies between its lower bound and its length.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator, Sequence
from pathlib import Path
from types import SimpleNamespace

import pytest
from hydra import compose, initialize_config_dir
from hypothesis import HealthCheck, given, settings

from flows.build import JobError, check_job, run_config, search_budget
from flows.config import register, typed
from tests.examples import STAGGERED, TRACKS, problem, two_hub_tracks, two_hub_tracks_text
from tests.support.brute_force import brute_force, cases
from twostep.makespan import (
    DEFAULT_SEARCH_BUDGET,
    ParallelExecution,
    SearchBudget,
    check_schedule,
    parallel_length,
)
from twostep.methods import MethodRequest, Steps
from twostep.methods.steps import score
from twostep.pddl import Problem

CONF = Path(__file__).resolve().parent.parent / "conf"


def test_time_budget_returns_a_valid_schedule_above_its_lower_bound() -> None:
    prob, plans = two_hub_tracks(STAGGERED, 14)
    full = parallel_length(
        plans, prob.init, prob.goal, ["ready"], max_nodes=None, time_limit_s=None
    )
    assert full.exact and full.length == full.lower_bound
    # A zero time limit stops before the search (no dive, no pair bounds, no expansion):
    # the greedy schedule comes back with the start node's bound, deterministically.
    cut = parallel_length(plans, prob.init, prob.goal, ["ready"], max_nodes=None, time_limit_s=0)
    check_schedule(cut.steps, plans, prob.init, prob.goal, ["ready"])
    assert cut.lower_bound <= full.length <= cut.length
    assert not cut.exact and cut.gap == cut.length - cut.lower_bound > 0


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_zero_time_budget_brackets_the_brute_force_optimum(case) -> None:
    plans, init, goal, predicates = case
    expected = brute_force(plans, init, goal, predicates)
    if expected is None:
        return  # nothing to bracket (ScheduleError; covered in test_execution_scaling)
    found = parallel_length(plans, init, goal, predicates, max_nodes=None, time_limit_s=0)
    check_schedule(found.steps, plans, init, goal, predicates)
    assert found.lower_bound <= expected <= found.length
    assert found.exact == (found.length == found.lower_bound)


def test_pipeline_score_passes_its_budget_to_the_search() -> None:
    text, plans = two_hub_tracks_text(STAGGERED, 14)
    prob = problem(TRACKS, text)
    budgeted = score(prob, plans, ["ready"], "exact", SearchBudget(0, None))
    unlimited = score(prob, plans, ["ready"], "exact", SearchBudget(None, None))
    # Stopped before any expansion, the greedy schedule is not proven: a gap of one.
    assert (budgeted.exact, unlimited.exact) == (False, True)
    assert budgeted.lower_bound < unlimited.length <= budgeted.length
    request = MethodRequest(
        SimpleNamespace(problem=prob),  # type: ignore[arg-type]  # the request reads .problem
        agent_predicates=["ready"],
        search_budget=SearchBudget(0, None),
    )
    assert request.score(plans) == budgeted


# ------------------------------------------------------------------- config keys


@pytest.fixture(scope="module")
def hydra_conf() -> Iterator[None]:
    register()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        yield


def make(tmp: Path, *overrides: str):
    data = Path(__file__).resolve().parent.parent / "data"
    places = [f"output.root={tmp}", f"data.root={data}", "mlflow.enabled=false"]
    return typed(compose("config", overrides=[*places, *overrides]))


def test_config_keys_map_to_the_search_budget(hydra_conf: None, tmp_path: Path) -> None:
    assert search_budget(make(tmp_path)) == DEFAULT_SEARCH_BUDGET
    cfg = make(tmp_path, "score_max_nodes=0", "score_time_limit_s=3.5")
    assert search_budget(cfg) == SearchBudget(max_nodes=0, time_limit_s=3.5)
    cfg = make(tmp_path, "score_max_nodes=null", "score_time_limit_s=null")
    assert search_budget(cfg) == SearchBudget(max_nodes=None, time_limit_s=None)
    for bad, message in (
        ("score_max_nodes=-1", "score_max_nodes=-1 must be >= 0"),
        ("score_time_limit_s=0", "score_time_limit_s=0.0 must be > 0"),
    ):
        with pytest.raises(JobError, match=message):
            check_job(make(tmp_path, bad))


def test_config_budget_reaches_the_score_step(
    hydra_conf: None, tmp_path: Path, data_root: Path
) -> None:
    seen: list[SearchBudget] = []

    def recording_score(
        problem: Problem,
        plans: Sequence[Sequence[str]],
        agent_predicates: Collection[str],
        mode: str = "exact",
        budget: SearchBudget = DEFAULT_SEARCH_BUDGET,
    ) -> ParallelExecution:
        seen.append(budget)
        return score(problem, plans, agent_predicates, mode, budget)

    cfg = make(
        tmp_path,
        "method=ma",
        "domain=grippers",
        "task=1",
        "compare_sa=false",
        "score_max_nodes=7",
        "score_time_limit_s=2.5",
    )
    result = run_config(cfg, steps=Steps(score=recording_score))
    assert result.success
    assert seen == [SearchBudget(max_nodes=7, time_limit_s=2.5)]
