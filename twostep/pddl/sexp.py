"""The s-expression layer: PDDL text as nested lists, with file-and-line errors.

Reading reports unbalanced parentheses before unified-planning sees a file (its own
messages do not say where); the section helpers serve the repairs and the reader.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from twostep.pddl.errors import PDDLError

SExp = str | list["SExp"]


# A "?" starts a variable even inside a word: Fast Downward reads "(aircraft?a)" (IPC
# zenotravel) as "(aircraft ?a)".
_TOKEN = re.compile(r"\(|\)|\??[^\s()?]+|\?")
# Sections that open directly inside (define ...): seeing one deeper means a ')' is missing.
_SECTIONS = frozenset(
    {":domain", ":requirements", ":types", ":constants", ":predicates", ":functions",
     ":action", ":durative-action", ":derived", ":objects", ":init", ":goal", ":metric"}
)  # fmt: skip


def read_sexp(text: str, source: str | None = None, single: bool = False) -> list[SExp]:
    """Read all top-level s-expressions of ``text``; PDDL comments (``;``) are skipped.

    With ``single``, anything after the first complete expression is an error (a ``)``
    too many closes a PDDL file's ``define`` early).
    """
    stack: list[list[SExp]] = [[]]
    opened: list[int] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        line = line.split(";", 1)[0]
        for token in _TOKEN.findall(line):
            if single and len(stack) == 1 and stack[0]:
                raise PDDLError(
                    f"unexpected '{token}' after the end of the define: a ')' too many before it?",
                    source,
                    lineno,
                )
            if token == "(":
                stack.append([])
                opened.append(lineno)
            elif token.lower() in _SECTIONS and len(stack) > 3 and not stack[-1]:
                raise PDDLError(
                    f"'({token.lower()}' on line {lineno} opens inside an expression that is "
                    "never closed: a ')' is missing",
                    source,
                    opened[-2],
                )
            elif token == ")":
                if len(stack) == 1:
                    raise PDDLError("unexpected ')' with no matching '('", source, lineno)
                done = stack.pop()
                opened.pop()
                stack[-1].append(done)
            else:
                stack[-1].append(token.lower())
    if len(stack) > 1:
        raise PDDLError("'(' is never closed", source, opened[-1])
    return stack[0]


def write_sexp(expr: SExp) -> str:
    if isinstance(expr, str):
        return expr
    return "(" + " ".join(write_sexp(e) for e in expr) + ")"


def define_body(text: str, kind: str, source: str | None) -> list[SExp]:
    exprs = read_sexp(text, source)
    if not exprs or not isinstance(exprs[0], list) or not exprs[0] or exprs[0][0] != "define":
        raise PDDLError(f"expected '(define ({kind} ...) ...)'", source, 1)
    return exprs[0]


def section(body: list[SExp], key: str) -> list[SExp] | None:
    for item in body:
        if isinstance(item, list) and item and item[0] == key:
            return item
    return None


TypeSpec = str | tuple[str, ...]
"""A declared type: one name, or the members of ``(either t1 t2 ...)``."""


def _clean(token: SExp) -> SExp:
    # AlfWorld writes "(?l - location, ?r - receptacle)": the comma is a separator.
    return token.rstrip(",") if isinstance(token, str) else token


def typed_list(items: Sequence[SExp]) -> list[tuple[str, TypeSpec]]:
    """A PDDL typed list, ``(either ...)`` types and comma separators included."""
    tokens = [_clean(t) for t in items]
    tokens = [t for t in tokens if t != ""]
    result: list[tuple[str, TypeSpec]] = []
    pending: list[str] = []
    i = 0
    while i < len(tokens):
        token = tokens[i]
        if token == "-" and i + 1 < len(tokens):
            spec = tokens[i + 1]
            type_spec: TypeSpec
            if isinstance(spec, list) and spec[:1] == ["either"]:
                type_spec = tuple(str(_clean(t)) for t in spec[1:] if _clean(t))
            else:
                type_spec = str(spec)
            result += [(name, type_spec) for name in pending]
            pending = []
            i += 2
            continue
        if isinstance(token, str):
            pending.append(token)
        i += 1
    result += [(name, "object") for name in pending]
    return result


def typed_names(items: list[SExp]) -> list[tuple[str, str]]:
    """Parse a PDDL typed list ``a b - t c`` into ``[(a, t), (b, t), (c, object)]``
    (an ``(either ...)`` type reads as ``object`` here; :func:`typed_list` keeps it)."""
    return [(name, spec if isinstance(spec, str) else "object") for name, spec in typed_list(items)]
