"""Repairs of real-world PDDL quirks, made on s-expressions before unified-planning reads them.

The LLM+P tyreworld domain uses objects that only its problems declare; they become domain
constants (the other quirk, actions named like predicates, is an environment setting in
:mod:`twostep.pddl.unified`).
"""

from __future__ import annotations

from twostep.pddl.errors import PDDLError
from twostep.pddl.sexp import SExp, define_body, section, typed_names, write_sexp


def _undeclared_constants(domain_body: list[SExp]) -> set[str]:
    """Names that domain actions use as objects without declaring them as constants."""
    predicates = {
        p[0] for p in (section(domain_body, ":predicates") or [])[1:] if isinstance(p, list) and p
    }
    constants = {n for n, _ in typed_names((section(domain_body, ":constants") or [":c"])[1:])}
    found: set[str] = set()

    def visit(expr: SExp) -> None:
        if not isinstance(expr, list) or not expr:
            return
        head = expr[0]
        if isinstance(head, str) and (head in predicates or head == "="):
            for term in expr[1:]:
                if isinstance(term, str) and not term.startswith("?") and term not in constants:
                    found.add(term)
        for sub in expr[1:]:
            visit(sub)

    for item in domain_body:
        if isinstance(item, list) and item and item[0] == ":action":
            for key, value in zip(item[2::2], item[3::2], strict=False):
                if key in (":precondition", ":effect"):
                    visit(value)
    return found


def repair_undeclared_constants(
    domain_text: str, problem_text: str, domain_source: str | None, problem_source: str | None
) -> tuple[str, str]:
    """Move objects that the domain uses but only the problem declares into domain constants.

    The LLM+P tyreworld domain mentions ``wrench``, ``jack`` and ``pump`` in its actions
    while only its problems declare them; both unified-planning and Fast Downward reject
    that. Declaring them as typed constants of the domain keeps the meaning.
    """
    domain_body = define_body(domain_text, "domain", domain_source)
    missing = _undeclared_constants(domain_body)
    if not missing:
        return domain_text, problem_text
    problem_body = define_body(problem_text, "problem", problem_source)
    objects_section = section(problem_body, ":objects") or [":objects"]
    declared = dict(typed_names(objects_section[1:]))
    unknown = sorted(missing - declared.keys())
    if unknown:
        raise PDDLError(
            f"the domain's actions use undeclared object(s) {', '.join(unknown)} "
            "that neither its constants nor the problem's objects declare",
            domain_source,
        )
    constants_section = section(domain_body, ":constants")
    new_constants: list[SExp] = [":constants"]
    if constants_section is not None:
        new_constants += constants_section[1:]
    for name in sorted(missing):
        new_constants += [name, "-", declared[name]] if _domain_body_typed(domain_body) else [name]
    rebuilt: list[SExp] = []
    inserted = False
    for item in domain_body:
        if item is constants_section:
            continue
        if not inserted and isinstance(item, list) and item and item[0] == ":predicates":
            rebuilt.append(new_constants)
            inserted = True
        rebuilt.append(item)
    if not inserted:
        rebuilt.insert(2, new_constants)
    kept: list[SExp] = [":objects"]
    for name, type_name in typed_names(objects_section[1:]):
        if name not in missing:
            kept += [name, "-", type_name]
    problem_rebuilt = [kept if item is objects_section else item for item in problem_body]
    return _pretty(rebuilt), _pretty(problem_rebuilt)


def _domain_body_typed(domain_body: list[SExp]) -> bool:
    return section(domain_body, ":types") is not None


def _pretty(body: list[SExp]) -> str:
    return "(" + "\n ".join(write_sexp(item) for item in body) + ")\n"
