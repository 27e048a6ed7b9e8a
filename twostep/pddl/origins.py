"""Plans in the task's own terms and in the compiled domain's, and the way between them.

A domain beyond STRIPS is compiled by :mod:`twostep.pddl.adl` into variants of its actions
(``toggleobject-v1``, ``toggleobject-v2``) that may carry extra parameters (the witnesses
of ``exists``). Planning, progression and scoring work on the compiled actions; results
and users speak the task's own language. :func:`original_plan` drops the variant suffix
and the extra arguments (and the goal actions the compilation added);
:func:`compiled_plan` goes back by simulation: at each step it takes the variant, and
the witnesses, that are applicable in the state reached so far.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping, Sequence

from twostep.pddl.model import ActionOrigin, Fact, Problem
from twostep.strips import GroundAction, Grounder, PlanError, parse_action


def original_action(origins: Mapping[str, ActionOrigin], action: str) -> str | None:
    """A compiled plan step in the task's own terms; None for a goal action.

    ``(toggleobject-v2 a1 lamp t1 l1)`` -> ``(toggleobject a1 lamp t1)`` when
    ``toggleobject`` takes three parameters (``l1`` witnessed an ``exists``).
    """
    name, args = parse_action(action)
    origin = origins.get(name)
    if origin is None:
        return "(" + " ".join((name, *args)) + ")"
    if origin.name is None:
        return None
    return "(" + " ".join((origin.name, *args[: origin.arity])) + ")"


def original_plan(origins: Mapping[str, ActionOrigin], plan: Iterable[str]) -> list[str]:
    """A compiled plan in the task's own terms (goal actions left out)."""
    steps = (original_action(origins, step) for step in plan)
    return [step for step in steps if step is not None]


def _objects_of(problem: Problem, type_name: str) -> list[str]:
    types = problem.domain.types

    def is_a(name: str | None) -> bool:
        seen: set[str] = set()
        while name is not None and name not in seen:
            if name == type_name:
                return True
            seen.add(name)
            name = types.get(name)
        return type_name == "object"

    return sorted(o for o, t in problem.all_objects.items() if is_a(t))


def compiled_plan(
    problem: Problem, plan: Sequence[str], state: Iterable[Fact] | None = None
) -> list[str]:
    """A plan in the task's own terms, as compiled actions applicable from ``state``.

    ``state`` defaults to the initial state. Raises :class:`~twostep.strips.PlanError`
    at the first step for which no variant (with any witnesses) is applicable.
    """
    domain = problem.domain
    variants: dict[str, list[str]] = {}
    for name, origin in domain.origins.items():
        if origin.name is not None:
            variants.setdefault(origin.name, []).append(name)
    grounder = Grounder(problem)
    current = frozenset(problem.init if state is None else state)
    result: list[str] = []
    for step, text in enumerate(plan, start=1):
        name, args = parse_action(text)
        chosen: GroundAction | None = None
        for candidate in variants.get(name, [name]):
            schema = domain.actions.get(candidate)
            if schema is None or len(schema.parameters) < len(args):
                continue
            known = domain.origins.get(candidate)
            if known is not None and known.arity != len(args):
                continue
            extra = schema.parameters[len(args) :]
            for witnesses in itertools.product(*(_objects_of(problem, t) for _, t in extra)):
                try:
                    ground = grounder.ground("(" + " ".join((candidate, *args, *witnesses)) + ")")
                except PlanError:
                    continue
                if ground.applicable(current):
                    chosen = ground
                    break
            if chosen is not None:
                break
        if chosen is None:
            raise PlanError(f"step {step} {text}: no compiled action of it is applicable")
        current = chosen.apply(current)
        result.append(str(chosen))
    return result
