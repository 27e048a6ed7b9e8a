"""Objects a domain uses but only the problem declares, moved to the domain's ``:constants``.

Fast Downward and unified-planning reject a domain whose actions name an object that only
the problem declares (the LLM+P tyreworld, AlfWorld's alfred.pddl). The task the authors
meant is the same with those objects declared as typed domain constants; this writes that
pair of files so the independent checkers can read it. A small s-expression reader of its
own (comments dropped, names kept as written).
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path

SExpr = str | list["SExpr"]


def read_sexp(text: str) -> SExpr:
    text = re.sub(r";[^\n]*", " ", text)
    tokens = re.findall(r"\(|\)|[^\s()]+", text)
    stack: list[list[SExpr]] = [[]]
    for token in tokens:
        if token == "(":
            stack.append([])
        elif token == ")":
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(token)
    if len(stack) != 1 or len(stack[0]) != 1:
        raise ValueError("unbalanced parentheses")
    return stack[0][0]


def write_sexp(expr: SExpr) -> str:
    if isinstance(expr, str):
        return expr
    return "(" + " ".join(write_sexp(e) for e in expr) + ")"


def _section(expr: SExpr, keyword: str) -> list[SExpr] | None:
    assert isinstance(expr, list)
    for part in expr:
        if isinstance(part, list) and part and str(part[0]).lower() == keyword:
            return part
    return None


def move_constants(
    domain: Path, problem: Path, names: Iterable[str], out_dir: Path
) -> tuple[Path, Path]:
    """Write ``out_dir/domain.pddl`` and ``out_dir/problem.pddl``: ``names`` taken out of
    the problem's ``:objects`` (with their types) and declared as the domain's constants."""
    wanted = {n.lower() for n in names}
    domain_expr, problem_expr = read_sexp(domain.read_text()), read_sexp(problem.read_text())
    objects = _section(problem_expr, ":objects")
    if objects is None:
        raise ValueError(f"{problem}: no :objects section")
    kept: list[SExpr] = [":objects"]
    moved: list[SExpr] = []
    pending: list[SExpr] = []
    items = objects[1:]
    index = 0
    while index < len(items):
        item = items[index]
        if item == "-" and index + 1 < len(items):
            kind = items[index + 1]
            staying = [n for n in pending if str(n).lower() not in wanted]
            if staying:
                kept += [*staying, "-", kind]
            chosen = [n for n in pending if str(n).lower() in wanted]
            if chosen:
                moved += [*chosen, "-", kind]
            pending = []
            index += 2
            continue
        pending.append(item)
        index += 1
    kept += [n for n in pending if str(n).lower() not in wanted]
    moved += [n for n in pending if str(n).lower() in wanted]
    objects[:] = kept
    assert isinstance(domain_expr, list)
    constants = _section(domain_expr, ":constants")
    if constants is None:
        position = next(
            i
            for i, part in enumerate(domain_expr)
            if isinstance(part, list) and str(part[0]).lower() == ":predicates"
        )
        domain_expr.insert(position, [":constants", *moved])
    else:
        constants.extend(moved)
    out_dir.mkdir(parents=True, exist_ok=True)
    new_domain, new_problem = out_dir / "domain.pddl", out_dir / "problem.pddl"
    new_domain.write_text(write_sexp(domain_expr) + "\n")
    new_problem.write_text(write_sexp(problem_expr) + "\n")
    return new_domain, new_problem
