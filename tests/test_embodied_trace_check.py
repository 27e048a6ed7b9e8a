"""Every embodied trace replayed by the independent checker (:mod:`checkers.trace_check`).

The checker is first shown to reject broken traces (a jump, a collision, furniture, an
interaction from a distance, a swapped pair of actions, a wrong length), so that its
"ok" on the real traces means something. Then: the issue's case (MA, task 1, N = 2, seeds
0 and 1: the egg was taken out of the fridge from 4 cells away after a backoff) and a
sweep over the four kitchen tasks, MA and TwoStep, N = 2 and 3 (seeds 0-1 here, 0-29
in the slow run), all with no interaction out of reach.
"""

from __future__ import annotations

import copy
from typing import Any

import pytest

from checkers.trace_check import check_trace, read_kitchen_file, read_sexpr
from tests.embodied_checks import DATA, KITCHEN, method_plans, run_and_check
from twostep.embodied import ExecutorSettings, FloorPlan, execute_plans, load_floor_plan
from twostep.embodied.run import TRACE_KEY, embodied_fields
from twostep.tasks.benchmark import load_task


@pytest.fixture(scope="module")
def kitchen() -> FloorPlan:
    return load_floor_plan(KITCHEN)


def test_sexpr_reader() -> None:
    assert read_sexpr("(a (B c) ; note\n d)") == [["a", ["b", "c"], "d"]]
    with pytest.raises(ValueError, match="unbalanced"):
        read_sexpr("(a (b)")


def _record(kitchen: FloorPlan) -> tuple[dict[str, Any], dict[str, list[str]], str, str]:
    task = load_task("alfworld", 1, DATA)
    plans = {a: list(p) for a, p in method_plans(1, "ma", 2)}
    result = execute_plans(task.problem, plans, list(plans), kitchen, ExecutorSettings(seed=3))
    assert result.success, result.message
    record = embodied_fields(result, kitchen)[TRACE_KEY]
    return record, plans, task.domain_path.read_text(), task.problem_path.read_text()


def test_the_checker_rejects_broken_traces(kitchen: FloorPlan) -> None:
    record, plans, domain, problem = _record(kitchen)
    floor = read_kitchen_file(KITCHEN)
    clean = check_trace(record, plans, domain, problem, floor)
    assert clean.ok, clean.violations
    assert clean.steps == record["embodied_length"]
    assert clean.interactions + clean.navigations == sum(len(p) for p in plans.values())
    trace = record["trace"]

    def broken(edit: Any) -> dict[str, int]:
        bad = copy.deepcopy(record)
        edit(bad)
        return dict(check_trace(bad, plans, domain, problem, floor).kinds)

    first_move = next(i for i, t in enumerate(trace) if t["primitive"] == "move")
    interaction = next(i for i, t in enumerate(trace) if t["primitive"] == "interact")
    applied = [i for i, t in enumerate(trace) if t.get("applied")]

    def jump(bad: dict[str, Any]) -> None:
        x, y = bad["start_positions"][trace[first_move]["agent"]]
        bad["trace"][first_move]["position"] = [x + 1, y + 1]

    def onto_furniture(bad: dict[str, Any]) -> None:
        bad["start_positions"][trace[0]["agent"]] = [6, 5]  # the dining table

    def collide(bad: dict[str, Any]) -> None:
        agents = list(bad["start_positions"])
        bad["start_positions"][agents[1]] = bad["start_positions"][agents[0]]

    def from_a_distance(bad: dict[str, Any]) -> None:
        agent, step = trace[interaction]["agent"], trace[interaction]["step"]
        x, y = trace[interaction]["position"]
        for entry in bad["trace"]:  # the whole stay at that cell shifted one cell down
            if entry["agent"] == agent and entry["step"] >= step and entry["position"] == [x, y]:
                entry["position"] = [x, y + 1]

    def swap(bad: dict[str, Any]) -> None:
        i, j = applied[0], applied[1]
        for key in ("action", "applied"):
            bad["trace"][i][key], bad["trace"][j][key] = trace[j][key], trace[i][key]

    def longer(bad: dict[str, Any]) -> None:
        bad["embodied_length"] += 1

    assert broken(jump).get("move", 0) >= 1
    assert broken(onto_furniture).get("blocked", 0) >= 1
    assert broken(collide).get("collision", 0) >= 1
    assert broken(from_a_distance).get("reach", 0) >= 1
    assert broken(swap).get("pddl", 0) + broken(swap).get("plan", 0) >= 1
    assert broken(longer) == {"length": 1}


@pytest.mark.parametrize("seed", [0, 1])
def test_the_issue_case_interacts_only_from_access_cells(seed: int, kitchen: FloorPlan) -> None:
    """MA, task 1, N = 2: a backoff moves agent0 off loc-fridge1's cell before it takes the
    egg; it must walk back first (before the fix it took the egg from 4 cells away)."""
    result, report = run_and_check(1, "ma", 2, seed, kitchen)
    assert result.success, result.message
    assert report.ok, report.violations
    assert report.out_of_reach == 0 and report.interactions > 0
    assert result.backoffs > 0  # the situation of the issue does arise
    # after every backoff, the next thing that agent applies comes after a walk back
    for index, entry in enumerate(result.trace):
        if entry.primitive != "backoff":
            continue
        later = [t for t in result.trace[index + 1 :] if t.agent == entry.agent]
        first_applied = next((t for t in later if t.applied is not None), None)
        if first_applied is not None and first_applied.primitive == "interact":
            assert any(t.primitive == "move" for t in later[: later.index(first_applied)])


SWEEP = [
    (task_id, method, agents)
    for task_id in (1, 2, 3, 4)
    for method in ("ma", "twostep")
    for agents in (2, 3)
]


def _sweep(seeds: range, kitchen: FloorPlan) -> tuple[int, int, list[str]]:
    traces = out_of_reach = 0
    problems: list[str] = []
    for task_id, method, agents in SWEEP:
        for seed in seeds:
            result, report = run_and_check(task_id, method, agents, seed, kitchen)
            traces += 1
            out_of_reach += report.out_of_reach
            label = f"p{task_id} {method} N={agents} seed {seed}"
            if not result.success:
                problems.append(f"{label}: {result.message}")
            problems += [f"{label}: {v}" for v in report.violations]
    return traces, out_of_reach, problems


def test_every_trace_of_a_sweep_replays(kitchen: FloorPlan) -> None:
    traces, out_of_reach, problems = _sweep(range(2), kitchen)
    assert traces == 32
    assert (out_of_reach, problems) == (0, [])


@pytest.mark.slow  # 480 executions and replays, 16 plannings: about 2 minutes
def test_every_trace_of_thirty_seeds_replays(kitchen: FloorPlan) -> None:
    traces, out_of_reach, problems = _sweep(range(30), kitchen)
    assert traces == 480
    assert (out_of_reach, problems) == (0, [])
