"""Bare status words in code: the comparisons ``tests/test_outcome.py`` forbids outside
the outcome vocabulary (``twostep/util/outcome.py``) and ``bench/bench_structure.py``
counts."""

from __future__ import annotations

import ast


def _literals(node: ast.expr) -> list[object]:
    if isinstance(node, ast.Constant):
        return [node.value]
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return [e.value for e in node.elts if isinstance(e, ast.Constant)]
    return []


def bare_status_comparisons(code: str | ast.AST, words: set[str]) -> list[tuple[int, str]]:
    """(line, word) of every comparison of a value with a bare status word in ``code``
    (source or a parsed tree): ``==``, ``!=``, ``is`` with a word; ``in`` a literal tuple,
    list or set holding one (``"error" in result`` asks for a key and is not one);
    ``.isin([...])`` and ``.count(...)`` of one."""
    found = []
    for node in ast.walk(ast.parse(code) if isinstance(code, str) else code):
        hits: list[object] = []
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            for op, left, right in zip(node.ops, operands, operands[1:], strict=False):
                if isinstance(op, ast.Eq | ast.NotEq | ast.Is | ast.IsNot):
                    hits += [x.value for x in (left, right) if isinstance(x, ast.Constant)]
                elif isinstance(op, ast.In | ast.NotIn) and not isinstance(right, ast.Constant):
                    hits += _literals(right)
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in ("isin", "count")
        ):
            hits += [v for arg in node.args for v in _literals(arg)]
        found += [
            (getattr(node, "lineno", 0), str(h)) for h in hits if isinstance(h, str) and h in words
        ]
    return sorted(found)
