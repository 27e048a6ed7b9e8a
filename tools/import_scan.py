"""Who imports whom among the repository's folders: the rules ``tests/test_tests_in_order.py``
enforces (no test imports another test module or a bench script, no bench script imports
another) and ``bench/bench_structure.py --layout`` counts, before and after.

Imports are read with :mod:`ast`, at module level and inside functions."""

from __future__ import annotations

import ast
from collections.abc import Callable, Iterable
from pathlib import Path


def imported_modules(source: str, package: str = "tests") -> set[str]:
    """Every module an import statement names (relative imports made absolute within
    ``package``; ``from a import b`` names ``a`` and ``a.b``)."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = f"{package}.{node.module or ''}".rstrip(".") if node.level else node.module
            if base:
                names.add(base)
                names.update(f"{base}.{alias.name}" for alias in node.names)
    return names


def module_names_of_tests(names: set[str]) -> set[str]:
    """The test modules among ``names`` (a part named ``test_*``)."""
    return {n for n in names if any(p.startswith("test_") for p in n.split("."))}


def bench_module_names(names: set[str]) -> set[str]:
    """The modules of the ``bench`` package among ``names``."""
    return {n for n in names if n == "bench" or n.startswith("bench.")}


def bench_script_names(bench: Path) -> Callable[[set[str]], set[str]]:
    """A rule picking the bench scripts among names: ``bench``, ``bench.<x>``, or
    ``<x>`` for a script ``bench/<x>.py`` (imported by name once ``bench/`` is on the path)."""
    scripts = {p.stem for p in bench.glob("*.py")}

    def rule(names: set[str]) -> set[str]:
        return bench_module_names(names) | {n for n in names if n.split(".")[0] in scripts}

    return rule


def offenders(
    paths: Iterable[Path], rule: Callable[[set[str]], set[str]], package: str, root: Path
) -> dict[str, list[str]]:
    """Each file among ``paths`` (named relative to ``root``) whose imports ``rule``
    picks, with what it picks."""
    found = {}
    for path in paths:
        names = rule(imported_modules(path.read_text(), package))
        if names:
            found[path.relative_to(root).as_posix()] = sorted(names)
    return found


def bench_importers_among_tests(root: Path) -> dict[str, list[str]]:
    """The test files of the repository at ``root`` that import a bench module."""
    return offenders(sorted((root / "tests").rglob("*.py")), bench_module_names, "tests", root)


def bench_scripts_importing_another(root: Path) -> dict[str, list[str]]:
    """The bench scripts of the repository at ``root`` that import another bench script
    (its own ``__init__`` aside)."""
    bench = root / "bench"
    scripts = sorted(p for p in bench.glob("*.py") if p.name != "__init__.py")
    return offenders(scripts, bench_script_names(bench), "bench", root)
