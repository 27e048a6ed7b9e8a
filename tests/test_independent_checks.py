"""Checks that do not trust the project's own simulator.

* unified-planning's validator is given invalid plans and must reject them (a validator
  that always said "valid" would otherwise pass every other test);
* every MA and TwoStep joint schedule of small real tasks is sequentialised into the
  compiled N-agent task (each agent with its own agent-specific facts, as the scorer
  assumes) and validated there by unified-planning;
* the exact scorer is compared with a brute-force breadth-first search over every subset
  of agents on random small STRIPS tasks (hypothesis), with several agent-predicate sets.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

import pytest
from hypothesis import HealthCheck, given, settings

from tests.support.brute_force import brute_force, cases
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.makespan import ScheduleError, parallel_length
from twostep.methods import (
    MethodRequest,
    RunResult,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import load_task
from twostep.tasks.multiagent import compile_multi_agent_problem
from twostep.verify.validation import to_up_problem, validate_plan

FAST = PlannerSettings("lama-first", 20)
AGENT_FACTS = {
    "blocksworld": ["arm-empty", "holding"],
    "grippers": ["at-robby", "free", "carry"],
    "tyreworld": [],
}


# --------------------------------------------------- the validator rejects bad plans


def test_validator_rejects_invalid_plans(data_root) -> None:
    task = load_task("blocksworld", 2, data_root)
    plan = run_single_agent(MethodRequest(task, planner=FAST)).plans["agent0"]
    assert len(plan) >= 2
    up_problem = to_up_problem(task.problem)
    assert validate_plan(task.problem, plan, up_problem).valid
    # Each mutation breaks the plan in a different way; each must be caught.
    truncated = plan[:-1]  # applicable but the goal is not reached
    swapped = [plan[1], plan[0], *plan[2:]]  # the first action's effect is needed first
    repeated = [plan[0], *plan]  # an action applied twice in a row
    unknown = ["(teleport b1)", *plan]
    for bad in (truncated, swapped, repeated, unknown):
        assert not validate_plan(task.problem, bad, up_problem).valid, bad


# ------------------------------------- MA and TwoStep schedules, validated by UP


def _sequentialise(run: RunResult, names: Sequence[str]) -> list[str]:
    """The joint schedule as one plan of the compiled N-agent task.

    Actions in one time step do not interfere, so any order within a step is valid;
    agents are mapped to the compiled task's agent objects in the run's agent order.
    """
    agent_object = {agent: names[i] for i, agent in enumerate(sorted(run.agent_order))}
    plan = []
    for step in run.schedule:
        for agent, action in step:
            name, *args = action.strip("()").split()
            plan.append("(" + " ".join((name, agent_object[agent], *args)) + ")")
    return plan


def _validate_joint(task, run: RunResult, agent_facts: Collection[str]) -> None:
    assert run.success, run.message
    agents = len(run.agent_order)
    compiled, names = compile_multi_agent_problem(task.problem, agents, agent_facts)
    plan = _sequentialise(run, names)
    assert len(plan) == sum(len(p) for p in run.plans.values())
    verdict = validate_plan(compiled, plan)
    assert verdict.valid, verdict.message


@pytest.mark.parametrize(
    ("domain", "task_id", "agents"),
    [("blocksworld", 3, 2), ("grippers", 2, 2), ("grippers", 4, 3), ("tyreworld", 1, 2)],
)
def test_twostep_and_ma_schedules_validate_in_the_compiled_task(
    data_root, domain: str, task_id: int, agents: int
) -> None:
    task = load_task(domain, task_id, data_root)
    facts = AGENT_FACTS[domain]
    twostep = run_twostep(MethodRequest(task, agents, FAST, facts, GoalSplitDecomposer(facts)))
    _validate_joint(task, twostep, facts)
    ma = run_multi_agent(MethodRequest(task, agents, FAST, facts))
    _validate_joint(task, ma, facts)


def test_sequentialised_schedule_with_a_wrong_order_is_rejected(data_root) -> None:
    """The check above can fail: swapping two dependent steps makes UP say invalid."""
    task = load_task("grippers", 2, data_root)
    facts = AGENT_FACTS["grippers"]
    run = run_twostep(MethodRequest(task, 2, FAST, facts, GoalSplitDecomposer(facts)))
    compiled, names = compile_multi_agent_problem(task.problem, 2, facts)
    plan = _sequentialise(run, names)
    assert validate_plan(compiled, plan).valid
    assert not validate_plan(compiled, plan[::-1]).valid


# ------------------------------------------- exact scorer vs brute force (hypothesis)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_exact_scorer_matches_brute_force(case) -> None:
    plans, init, goal, predicates = case
    expected = brute_force(plans, init, goal, predicates)
    try:
        found = parallel_length(plans, init, goal, predicates, mode="exact")
    except ScheduleError:
        assert expected is None
        return
    assert expected is not None
    assert found.length == expected
