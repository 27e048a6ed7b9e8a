"""Conversion from unified-planning: its PDDLReader's problem into the model.

unified-planning is imported inside the functions: importing this module stays cheap.
The environment it reads in is :func:`twostep.pddl.environment.up_environment`.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterator
from typing import Any

from twostep.pddl.errors import PDDLError
from twostep.pddl.model import ActionSchema, Atom, Fact

_LINE_IN_MESSAGE = re.compile(r"line:? (\d+)", re.IGNORECASE)


def parse_with_up(
    domain_text: str, problem_text: str, domain_source: str | None, problem_source: str | None
) -> Any:
    from unified_planning.io import PDDLReader

    from twostep.pddl.environment import up_environment

    up_environment()
    reader = PDDLReader()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        try:
            return reader.parse_problem_string(domain_text, problem_text)
        except Exception as exc:
            problem_error = exc
        try:  # which file is wrong? the domain alone tells (only on failure: parsing is slow)
            reader.parse_problem_string(domain_text)
        except Exception as exc:
            raise _as_pddl_error(exc, domain_source) from None
        raise _as_pddl_error(problem_error, problem_source) from None


def _as_pddl_error(exc: Exception, source: str | None) -> PDDLError:
    line = getattr(exc, "lineno", None)
    message = str(getattr(exc, "msg", None) or exc)
    if line is None:
        match = _LINE_IN_MESSAGE.search(str(exc))
        line = int(match.group(1)) if match else None
    return PDDLError(message.split(". From line")[0].strip(), source, line)


def _terms(node: Any) -> tuple[str, ...]:
    terms: list[str] = []
    for arg in node.args:
        if arg.is_parameter_exp():
            terms.append("?" + arg.parameter().name)
        elif arg.is_object_exp():
            terms.append(arg.object().name)
        elif arg.is_variable_exp():
            terms.append("?" + arg.variable().name)
        else:
            raise PDDLError(f"unsupported term {arg}")
    return tuple(terms)


def literals(node: Any, where: str) -> Iterator[tuple[bool, str, tuple[str, ...]]]:
    """Flatten a conjunction into (positive, predicate-or-'=', terms)."""
    if node.is_true():
        return
    if node.is_and():
        for arg in node.args:
            yield from literals(arg, where)
        return
    positive = True
    if node.is_not():
        positive, node = False, node.arg(0)
    if node.is_fluent_exp():
        yield positive, node.fluent().name, _terms(node)
    elif node.is_equals():
        yield positive, "=", _terms(node)
    else:
        raise PDDLError(f"{where}: unsupported PDDL construct {node} (only STRIPS literals)")


def action_costs(up_problem: Any) -> dict[str, int] | None:
    """Each action's constant cost when the problem minimises action costs, else None.

    unified-planning reads ``(increase (total-cost) N)`` effects into its
    ``MinimizeActionCosts`` metric (not into the actions' effects); an action without
    one costs the metric's default (0 in PDDL).
    """
    for metric in up_problem.quality_metrics:
        if not metric.is_minimize_action_costs():
            continue
        default = metric.default
        costs: dict[str, int] = {}
        for action in up_problem.actions:
            value = metric.costs.get(action, default)
            if value is None:
                costs[action.name] = 0
            elif isinstance(value, int):
                costs[action.name] = value
            elif value.is_int_constant():
                costs[action.name] = int(value.constant_value())
            else:
                raise PDDLError(
                    f"action {action.name}: only constant integer action costs are "
                    f"supported, not {value}"
                )
        return costs
    return None


def schema_from_up(action: Any, cost: int | None = None) -> ActionSchema:
    where = f"action {action.name}"
    params = tuple(("?" + p.name, p.type.name) for p in action.parameters)
    pre_pos: list[Atom] = []
    pre_neg: list[Atom] = []
    equal: list[tuple[str, str]] = []
    not_equal: list[tuple[str, str]] = []
    for pre in action.preconditions:
        for positive, pred, terms in literals(pre, where):
            if pred == "=":
                (equal if positive else not_equal).append((terms[0], terms[1]))
            else:
                (pre_pos if positive else pre_neg).append(Atom(pred, terms))
    add: list[Atom] = []
    delete: list[Atom] = []
    for effect in action.effects:
        if effect.is_conditional() or effect.is_forall():
            raise PDDLError(f"{where}: conditional and universal effects are not supported")
        atom = Atom(effect.fluent.fluent().name, _terms(effect.fluent))
        (add if effect.value.is_true() else delete).append(atom)
    return ActionSchema(
        action.name,
        params,
        tuple(pre_pos),
        tuple(pre_neg),
        tuple(add),
        tuple(delete),
        tuple(equal),
        tuple(not_equal),
        cost,
    )


def fact_from_up(node: Any) -> Fact:
    return (node.fluent().name, *_terms(node))
