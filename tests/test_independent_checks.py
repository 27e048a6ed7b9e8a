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

import itertools
from collections import deque
from collections.abc import Collection, Sequence

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.makespan import ScheduleError, parallel_length
from twostep.methods import (
    MethodRequest,
    RunResult,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)
from twostep.pddl import Fact, Goal
from twostep.planner import PlannerSettings
from twostep.plans.simulate import GroundAction
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

ENV = [("e", str(i)) for i in range(4)]  # environment facts
OWN = [("h", str(i)) for i in range(2)]  # candidate agent-specific facts


def _brute_force(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> int | None:
    """Minimum makespan by breadth-first search over every subset of agents per step.

    Written from the rules (SPEC section 5) without the scorer's bit sets, bounds or
    dominance: each agent keeps its own copy of the agent-specific facts; a set of agents
    may act together when each action is applicable in (environment + own copy) and no
    two interfere on environment facts.
    """

    def private(fact: Fact) -> bool:
        return fact[0] in agent_predicates

    def interfere(a: GroundAction, b: GroundAction) -> bool:
        for x, y in ((a, b), (b, a)):
            if any(not private(f) for f in x.delete & (y.pre_positive | y.add)):
                return True
            if any(not private(f) for f in x.add & y.pre_negative):
                return True
        return False

    env0 = frozenset(f for f in init if not private(f))
    own0 = frozenset(f for f in init if private(f))
    start = (tuple(0 for _ in plans), env0, tuple(own0 for _ in plans))
    seen = {start}
    queue = deque([(start, 0)])
    while queue:
        (indices, env, owns), depth = queue.popleft()
        if all(i == len(p) for i, p in zip(indices, plans, strict=True)):
            ok = all(
                (f in owns[k] if private(f) else f in env)
                for f in goal.positive
                for k in range(len(plans))
            ) and not any(
                (f in owns[k] if private(f) else f in env)
                for f in goal.negative
                for k in range(len(plans))
            )
            if ok:
                return depth
            continue
        ready = [k for k in range(len(plans)) if indices[k] < len(plans[k])]
        for size in range(1, len(ready) + 1):
            for chosen in itertools.combinations(ready, size):
                actions = [plans[k][indices[k]] for k in chosen]
                if not all(
                    a.applicable(env | owns[k]) for a, k in zip(actions, chosen, strict=True)
                ):
                    continue
                if any(interfere(a, b) for a, b in itertools.combinations(actions, 2)):
                    continue
                new_env = set(env)
                new_owns = list(owns)
                for a in actions:
                    new_env -= {f for f in a.delete if not private(f)}
                for a in actions:
                    new_env |= {f for f in a.add if not private(f)}
                for a, k in zip(actions, chosen, strict=True):
                    new_owns[k] = frozenset(
                        (owns[k] - {f for f in a.delete if private(f)})
                        | {f for f in a.add if private(f)}
                    )
                new_indices = tuple(i + (1 if k in chosen else 0) for k, i in enumerate(indices))
                node = (new_indices, frozenset(new_env), tuple(new_owns))
                if node not in seen:
                    seen.add(node)
                    queue.append((node, depth + 1))
    return None


facts = st.sampled_from(ENV + OWN)


def _subset(draw: st.DrawFn, pool: Collection[Fact], most: int) -> frozenset[Fact]:
    if not pool:
        return frozenset()
    return draw(st.frozensets(st.sampled_from(sorted(pool)), max_size=most))


@st.composite
def cases(draw: st.DrawFn):
    """Plans that run one after the other in hand-off order (preconditions drawn from what
    holds then), sometimes with a random precondition that may break every schedule."""
    predicates = draw(st.sampled_from([(), ("h",), ("e",), ("e", "h")]))
    init = draw(st.frozensets(facts, min_size=1))
    agents = draw(st.sampled_from([1, 2, 3, 3]))
    own0 = frozenset(f for f in init if f[0] in predicates)
    env = frozenset(f for f in init if f[0] not in predicates)
    plans, owns = [], []
    for agent in range(agents):
        own, plan = own0, []
        for step in range(draw(st.integers(0, 4))):
            state = env | own
            if draw(st.integers(0, 9)) == 0:
                positive = _subset(draw, ENV + OWN, 1)  # anything: may never hold
            else:
                positive = _subset(draw, state, 2)
            negative = _subset(draw, set(ENV + OWN) - state, 1)
            add = _subset(draw, ENV + OWN, 2)
            delete = _subset(draw, ENV + OWN, 2) - add
            action = GroundAction(f"a{agent}", (str(step),), positive, negative, add, delete)
            plan.append(action)
            after = action.apply(state)
            env = frozenset(f for f in after if f[0] not in predicates)
            own = frozenset(f for f in after if f[0] in predicates)
        plans.append(plan)
        owns.append(own)
    shared_private = frozenset.intersection(*owns)
    goal = Goal(
        _subset(draw, env | shared_private, 2),
        _subset(draw, set(ENV) - env, 1),
    )
    return plans, init, goal, predicates


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_exact_scorer_matches_brute_force(case) -> None:
    plans, init, goal, predicates = case
    expected = _brute_force(plans, init, goal, predicates)
    try:
        found = parallel_length(plans, init, goal, predicates, mode="exact")
    except ScheduleError:
        assert expected is None
        return
    assert expected is not None
    assert found.length == expected
