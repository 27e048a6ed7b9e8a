"""Writing the model as PDDL text that Fast Downward and unified-planning both read."""

from __future__ import annotations

from collections.abc import Iterable

from twostep.pddl.model import Domain, Problem, fact_to_pddl


def _requirements(domain: Domain, extra: Iterable[str] = ()) -> list[str]:
    reqs = set(domain.requirements) | set(extra) | {":strips"}
    if domain.typed:
        reqs.add(":typing")
    if any(a.pre_negative for a in domain.actions.values()):
        reqs.add(":negative-preconditions")
    if any(a.equal or a.not_equal for a in domain.actions.values()):
        reqs.add(":equality")
    if domain.action_costs:
        reqs.add(":action-costs")
    return sorted(reqs)


def _typed_list(pairs: Iterable[tuple[str, str]], typed: bool) -> str:
    if not typed:
        return " ".join(name for name, _ in pairs)
    return " ".join(f"{name} - {type_name}" for name, type_name in pairs)


def _conjunction(parts: list[str]) -> str:
    if len(parts) == 1:
        return parts[0]
    return "(and " + " ".join(parts) + ")"


def domain_to_pddl(domain: Domain, extra_requirements: Iterable[str] = ()) -> str:
    """Write ``domain`` as PDDL text that Fast Downward and unified-planning both read."""
    typed = domain.typed
    lines = [f"(define (domain {domain.name})"]
    lines.append(" (:requirements " + " ".join(_requirements(domain, extra_requirements)) + ")")
    if typed:
        entries = [
            f"{t} - {parent or 'object'}" for t, parent in domain.types.items() if t != "object"
        ]
        lines.append(" (:types " + " ".join(entries) + ")")
    if domain.constants:
        lines.append(" (:constants " + _typed_list(domain.constants.items(), typed) + ")")
    preds = []
    for name, arg_types in domain.predicates.items():
        params = _typed_list(((f"?x{i}", t) for i, t in enumerate(arg_types)), typed)
        preds.append(f"({name}{' ' + params if params else ''})")
    lines.append(" (:predicates " + " ".join(preds) + ")")
    if domain.action_costs:  # so that Fast Downward minimises them
        lines.append(" (:functions (total-cost) - number)")
    for action in domain.actions.values():
        pre = [str(a) for a in action.pre_positive]
        pre += [f"(not {a})" for a in action.pre_negative]
        pre += [f"(= {x} {y})" for x, y in action.equal]
        pre += [f"(not (= {x} {y}))" for x, y in action.not_equal]
        eff = [str(a) for a in action.add] + [f"(not {a})" for a in action.delete]
        if domain.action_costs.get(action.name):
            eff.append(f"(increase (total-cost) {domain.action_costs[action.name]})")
        lines.append(f" (:action {action.name}")
        lines.append(f"  :parameters ({_typed_list(action.parameters, typed)})")
        if pre:
            lines.append(f"  :precondition {_conjunction(pre)}")
        lines.append(f"  :effect {_conjunction(eff) if eff else '(and)'})")
    lines.append(")")
    return "\n".join(lines) + "\n"


def problem_to_pddl(problem: Problem) -> str:
    """Write ``problem`` (objects, initial state, goal) as PDDL text."""
    typed = problem.domain.typed
    lines = [f"(define (problem {problem.name})", f" (:domain {problem.domain.name})"]
    lines.append(" (:objects " + _typed_list(sorted(problem.objects.items()), typed) + ")")
    lines.append(" (:init")
    lines += [f"  {fact_to_pddl(f)}" for f in sorted(problem.init)]
    if problem.domain.action_costs:
        lines.append("  (= (total-cost) 0)")
    lines.append(" )")
    lines.append(f" (:goal {problem.goal.to_pddl()})")
    if problem.domain.action_costs:
        lines.append(" (:metric minimize (total-cost))")
    lines.append(")")
    return "\n".join(lines) + "\n"
