"""Independent plan validation with unified-planning's sequential plan validator.

Our own simulator (:mod:`twostep.plans.simulate`) is what the pipeline runs; this module checks a
plan a second way, against the problem as unified-planning reads it from our PDDL text,
so a bug in our grounding cannot silently accept a wrong plan.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from twostep.pddl import Problem, planner_input
from twostep.plans.simulate import parse_action
from twostep.tasks.multiagent import compile_multi_agent_problem


@dataclass(frozen=True)
class Validation:
    valid: bool
    message: str = ""


def to_up_problem(problem: Problem) -> Any:
    """The unified-planning problem for ``problem`` (read back from our PDDL text)."""
    from unified_planning.io import PDDLReader

    from twostep.verify.up_environment import up_environment

    up_environment()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return PDDLReader().parse_problem_string(*planner_input(problem))


def validate_plan(problem: Problem, plan: Sequence[str], up_problem: Any = None) -> Validation:
    """Check with unified-planning that ``plan`` is applicable and reaches the goal."""
    from unified_planning.engines import ValidationResultStatus
    from unified_planning.plans import ActionInstance, SequentialPlan
    from unified_planning.shortcuts import PlanValidator

    up_problem = up_problem if up_problem is not None else to_up_problem(problem)
    instances = []
    for step, text in enumerate(plan, start=1):
        name, args = parse_action(text)
        try:
            action = up_problem.action(name)
            objects = [up_problem.object(a) for a in args]
        except Exception:
            return Validation(False, f"step {step} {text}: unknown action or object")
        instances.append(ActionInstance(action, objects))
    with PlanValidator(name="sequential_plan_validator") as validator:
        result = validator.validate(up_problem, SequentialPlan(instances))
    if result.status == ValidationResultStatus.VALID:
        return Validation(True)
    reason = getattr(result, "reason", None)
    detail = str(getattr(result, "inapplicable_action", "") or "")
    message = " ".join(str(x) for x in (reason, detail) if x) or "invalid plan"
    return Validation(False, message)


def validate_schedule(
    problem: Problem,
    agent_order: Sequence[str],
    schedule: Sequence[Sequence[tuple[str, str]]],
    agent_predicates: Sequence[str],
) -> Validation:
    """unified-planning's verdict on a joint schedule: its steps laid out one after the
    other in the N-agent compilation, where every action names its agent (actions of one
    time step do not interfere, so any order of them is a valid sequential plan)."""
    compiled, names = compile_multi_agent_problem(problem, len(agent_order), agent_predicates)
    index = {agent: i for i, agent in enumerate(agent_order)}
    sequential = []
    for step in schedule:
        for agent, action in step:
            name, args = parse_action(action)
            sequential.append("(" + " ".join((name, names[index[agent]], *args)) + ")")
    return validate_plan(compiled, sequential)
