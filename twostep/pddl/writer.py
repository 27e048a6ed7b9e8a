"""The PDDL the planner receives: the user's own files, changed only where a task is.

A problem read from a file goes to the planner as that file (after the repairs real-world
files need, :mod:`twostep.pddl.repairs`), its domain likewise. A problem whose initial
state or goal changed (a hand-off problem, a helper's subgoal) is the original problem
with ``:objects``, ``:init`` and ``:goal`` written anew and everything else kept: the
requirements, the metric, the numeric initial values (``(= (road-length a b) 3)``).
Derived facts are never written (they are not initial facts). A domain or problem made in
code (the multi-agent compilation) is written from its s-expressions; a domain made in
code without them, from its STRIPS schemas.
"""

from __future__ import annotations

from collections.abc import Iterable

from twostep.pddl.model import Domain, Problem
from twostep.pddl.sexp import SExp, write_sexp


def planner_input(problem: Problem) -> tuple[str, str]:
    """The PDDL texts (domain, problem) the planner receives for ``problem``."""
    return domain_to_pddl(problem.domain), problem_to_pddl(problem)


def domain_to_pddl(domain: Domain) -> str:
    """``domain`` as PDDL text: its file's own text when there is one."""
    if domain.text is not None:
        return domain.text
    if domain.body:
        return pretty_define(domain.body)
    return _strips_domain(domain)


def problem_to_pddl(problem: Problem) -> str:
    """``problem`` as PDDL text (see the module docstring)."""
    if problem.text is not None:
        return problem.text
    typed = problem.domain.typed
    objects: list[SExp] = [":objects"]
    for name, type_name in sorted(problem.objects.items()):
        objects += [name, "-", type_name] if typed and not type_name.startswith("(") else [name]
    init: list[SExp] = [":init"]
    init += [list(f) for f in sorted(problem.init) if not problem.domain.is_derived(f)]
    init += list(problem.numeric_init)
    goal: list[SExp] = [":goal", _goal_sexp(problem)]
    header: list[SExp] = ["define", ["problem", problem.name], [":domain", problem.domain.name]]
    replaced = {":objects": objects, ":init": init, ":goal": goal}
    body: list[SExp] = list(header)
    seen: set[str] = set()
    for item in problem.body[3:] if problem.body else ():
        key = item[0] if isinstance(item, list) and item else None
        if isinstance(key, str) and key in replaced:
            body.append(replaced[key])
            seen.add(key)
        else:
            body.append(item)
    for key in (":objects", ":init", ":goal"):
        if key not in seen:
            index = next(
                (
                    i
                    for i, item in enumerate(body)
                    if isinstance(item, list) and item[:1] == [":metric"]
                ),
                len(body),
            )
            body.insert(index, replaced[key])
    if problem.domain.has_action_costs and not problem.body:
        body.append([":metric", "minimize", ["total-cost"]])
    return pretty_define(body)


def _goal_sexp(problem: Problem) -> SExp:
    goal = problem.goal
    if goal.formula is not None:
        return goal.formula
    literals: list[SExp] = [list(f) for f in sorted(goal.positive)]
    literals += [["not", list(f)] for f in sorted(goal.negative)]
    return ["and", *literals]


def pretty_define(body: list[SExp]) -> str:
    """A ``define`` written one section per line (``:init`` one fact per line)."""
    head = "(" + " ".join(write_sexp(item) for item in body[:2])
    lines = [head]
    for item in body[2:]:
        if isinstance(item, list) and item[:1] == [":init"]:
            lines.append(" (:init")
            lines += [f"  {write_sexp(fact)}" for fact in item[1:]]
            lines.append(" )")
        else:
            lines.append(" " + write_sexp(item))
    lines.append(")")
    return "\n".join(lines) + "\n"


def _typed_list(pairs: Iterable[tuple[str, str]], typed: bool) -> str:
    if not typed:
        return " ".join(name for name, _ in pairs)
    return " ".join(f"{name} - {type_name}" for name, type_name in pairs)


def _strips_domain(domain: Domain) -> str:
    typed = domain.typed
    requirements = {":strips", *domain.requirements}
    if typed:
        requirements.add(":typing")
    if any(a.pre_negative for a in domain.actions.values()):
        requirements.add(":negative-preconditions")
    if any(a.equal or a.not_equal for a in domain.actions.values()):
        requirements.add(":equality")
    lines = [
        f"(define (domain {domain.name})",
        f" (:requirements {' '.join(sorted(requirements))})",
    ]
    if typed:
        entries = [f"{t} - {p or 'object'}" for t, p in domain.types.items() if t != "object"]
        lines.append(" (:types " + " ".join(entries) + ")")
    if domain.constants:
        lines.append(" (:constants " + _typed_list(domain.constants.items(), typed) + ")")
    predicates = []
    for name, arg_types in domain.predicates.items():
        params = _typed_list(((f"?x{i}", t) for i, t in enumerate(arg_types)), typed)
        predicates.append(f"({name}{' ' + params if params else ''})")
    lines.append(" (:predicates " + " ".join(predicates) + ")")
    if domain.has_action_costs:
        lines.append(" (:functions (total-cost) - number)")
    for action in domain.actions.values():
        pre = [str(a) for a in action.pre_positive]
        pre += [f"(not {a})" for a in action.pre_negative]
        pre += [f"(= {x} {y})" for x, y in action.equal]
        pre += [f"(not (= {x} {y}))" for x, y in action.not_equal]
        eff = [str(a) for a in action.add] + [f"(not {a})" for a in action.delete]
        if domain.has_action_costs:
            eff.append(f"(increase (total-cost) {action.cost or 0})")
        lines.append(f" (:action {action.name}")
        lines.append(f"  :parameters ({_typed_list(action.parameters, typed)})")
        if pre:
            lines.append("  :precondition (and " + " ".join(pre) + ")")
        lines.append("  :effect (and " + " ".join(eff) + "))")
    lines.append(")")
    return "\n".join(lines) + "\n"
