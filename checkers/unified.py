"""unified-planning's reader and sequential plan validator on the original files.

Also builds an N-agent formulation in unified-planning itself: each agent-specific fluent is
copied once per agent, each action once per agent acting on its own copies (so agents share
the environment, each keeps its own agent facts, and every goal that reads an agent fluent
must hold for every agent). A joint schedule, sequentialised, is validated there.

Nothing here uses twostep: every problem comes from unified-planning's own PDDL reader
(with its name check relaxed as far as real files need: an action may share a predicate's
name). unified-planning's grounder works in its global environment, so every problem does.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .sas import step_name


class ReaderRejected(Exception):
    """unified-planning's PDDL reader does not accept the files."""


@dataclass(frozen=True)
class UPCheck:
    valid: bool
    reason: str = ""


def read_problem(domain: Path, problem: Path) -> Any:
    """The unified-planning problem of the files."""
    from unified_planning.environment import get_environment
    from unified_planning.io import PDDLReader

    env = get_environment()
    env.error_used_name = False
    env.credits_stream = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            up_problem = PDDLReader(environment=env).parse_problem(str(domain), str(problem))
    except Exception as error:
        text = " ".join(str(error).split())[:200]
        raise ReaderRejected(f"{type(error).__name__}: {text}") from None
    _total_cost_starts_at_zero(up_problem)
    return up_problem


def _total_cost_starts_at_zero(up_problem: Any) -> None:
    """A problem that does not set ``(total-cost)`` starts it at 0 (PDDL's action costs;
    Fast Downward reads it so); unified-planning's validator needs the value to evaluate
    the metric, and stops with an error without it."""
    if not up_problem.has_fluent("total-cost"):
        return
    cost = up_problem.fluent("total-cost")
    if cost.arity == 0 and cost() not in up_problem.explicit_initial_values:
        up_problem.set_initial_value(cost(), 0)


def _lookup(items: Iterable[Any]) -> dict[str, Any]:
    return {item.name.lower(): item for item in items}


def _instances(up_problem: Any, steps: Sequence[tuple[str, str]]) -> list[Any] | str:
    """ActionInstances for ``(action name suffix, "(name arg ...)")`` steps, or why not."""
    from unified_planning.plans import ActionInstance

    actions, objects = _lookup(up_problem.actions), _lookup(up_problem.all_objects)
    result = []
    for number, (suffix, text) in enumerate(steps, start=1):
        name, *args = step_name(text).split()
        action = actions.get(name + suffix)
        if action is None or any(a not in objects for a in args):
            return f"step {number} {text}: unknown action or object"
        if len(args) != len(action.parameters):
            return f"step {number} {text}: {len(args)} arguments, the action takes {len(action.parameters)}"
        try:
            result.append(ActionInstance(action, [objects[a] for a in args]))
        except Exception as error:  # unified-planning checks the arguments' types here
            return f"step {number} {text}: {' '.join(str(error).split())[:150]}"
    return result


def _validate(up_problem: Any, instances: list[Any]) -> UPCheck:
    from unified_planning.engines import ValidationResultStatus
    from unified_planning.plans import SequentialPlan

    env = up_problem.environment
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with env.factory.PlanValidator(name="sequential_plan_validator") as validator:
            result = validator.validate(up_problem, SequentialPlan(instances, environment=env))
    if result.status == ValidationResultStatus.VALID:
        return UPCheck(True)
    reason = " ".join(str(x) for x in (result.reason, result.inapplicable_action) if x)
    return UPCheck(False, reason or "invalid plan")


def validate_plan(up_problem: Any, plan: Sequence[str]) -> UPCheck:
    """unified-planning's verdict on a sequential plan of the task's own actions."""
    instances = _instances(up_problem, [("", step) for step in plan])
    if isinstance(instances, str):
        return UPCheck(False, instances)
    return _validate(up_problem, instances)


# ------------------------------------------------------------ the N-agent formulation


def agent_suffix(agent: int) -> str:
    return f"__agent{agent}"


def multi_agent_problem(up_problem: Any, agent_predicates: Iterable[str], agents: int) -> Any:
    """The N-agent formulation described in the module docstring (actions ``name__agentI``)."""
    from unified_planning.model import Fluent, InstantaneousAction, Problem
    from unified_planning.model.walkers.identitydag import IdentityDagWalker

    env = up_problem.environment
    wanted = {p.lower() for p in agent_predicates}
    own = [f for f in up_problem.fluents if f.name.lower() in wanted]
    copies = [
        {f: Fluent(f.name + agent_suffix(i), f.type, f.signature, env) for f in own}
        for i in range(agents)
    ]

    class Renamer(IdentityDagWalker):  # type: ignore[misc]
        def __init__(self, mapping: dict[Any, Any]) -> None:
            super().__init__(env)
            self.mapping = mapping

        def walk_fluent_exp(self, expression: Any, args: list[Any], **kwargs: Any) -> Any:
            fluent = self.mapping.get(expression.fluent(), expression.fluent())
            return self.manager.FluentExp(fluent, tuple(args))

    renamers = [Renamer(copy) for copy in copies]
    result = Problem(up_problem.name + "-agents", env)
    result.add_objects(up_problem.all_objects)
    defaults = up_problem.fluents_defaults
    for fluent in up_problem.fluents:
        for new in [c[fluent] for c in copies] if fluent in own else [fluent]:
            result.add_fluent(new, default_initial_value=defaults.get(fluent))
    for key, value in up_problem.explicit_initial_values.items():
        if key.fluent() in own:
            for renamer in renamers:
                result.set_initial_value(renamer.walk(key), value)
        else:
            result.set_initial_value(key, value)
    for agent, renamer in enumerate(renamers):
        for action in up_problem.actions:
            params = {p.name: p.type for p in action.parameters}
            copy = InstantaneousAction(action.name + agent_suffix(agent), params, env)
            for pre in action.preconditions:
                copy.add_precondition(renamer.walk(pre))
            for effect in action.effects:
                args = (
                    renamer.walk(effect.fluent),
                    renamer.walk(effect.value),
                    renamer.walk(effect.condition),
                    effect.forall,
                )
                if effect.is_increase():
                    copy.add_increase_effect(*args)
                elif effect.is_decrease():
                    copy.add_decrease_effect(*args)
                else:
                    copy.add_effect(*args)
            result.add_action(copy)
    goals: list[Any] = []
    for goal in up_problem.goals:
        for renamer in renamers:
            renamed = renamer.walk(goal)
            if renamed not in goals:
                goals.append(renamed)
    for goal in goals:
        result.add_goal(goal)
    return result


def validate_schedule(
    ma_problem: Any, agent_order: Sequence[str], schedule: Sequence[Sequence[Sequence[str]]]
) -> UPCheck:
    """unified-planning's verdict on a joint schedule, each step's actions one after the
    other in the listed order, in :func:`multi_agent_problem`'s formulation."""
    index = {name: i for i, name in enumerate(agent_order)}
    steps = [(agent_suffix(index[agent]), action) for step in schedule for agent, action in step]
    instances = _instances(ma_problem, steps)
    if isinstance(instances, str):
        return UPCheck(False, instances)
    return _validate(ma_problem, instances)
