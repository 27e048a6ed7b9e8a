"""The tests in order: no test module imports another test module (shared helpers live in
tests/examples.py, tests/support/ or conftest.py), and no test imports a bench script
(what a test needs lives in the library, checkers/ or tests/support/, and the bench
imports it from there).

Imports are read with :mod:`ast` (module level and inside functions); each rule is shown
to catch a planted import."""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent

# Test files that still import bench modules as libraries (what they test is the bench's
# own code: its tables, its records, the results pages); the list only shrinks.
STILL_IMPORT_BENCH = {
    "test_bench_heldout.py",
    "test_bench_methods.py",
    "test_bench_portfolio_members.py",
    "test_bench_record.py",
    "test_conformance.py",
    "test_docs_site.py",
    "test_paper_shaped.py",
    "test_readme.py",
}


def imported_modules(source: str, package: str = "tests") -> set[str]:
    """Every module an import statement names (relative imports made absolute within
    ``package``; ``from a import b`` names ``a`` and ``a.b``)."""
    names = set()
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
    return {n for n in names if any(p.startswith("test_") for p in n.split("."))}


def bench_module_names(names: set[str]) -> set[str]:
    return {n for n in names if n == "bench" or n.startswith("bench.")}


def _sources() -> dict[str, str]:
    return {p.relative_to(TESTS).as_posix(): p.read_text() for p in sorted(TESTS.rglob("*.py"))}


def test_no_test_module_imports_another() -> None:
    found = {
        name: sorted(module_names_of_tests(imported_modules(text)))
        for name, text in _sources().items()
        if module_names_of_tests(imported_modules(text))
    }
    assert not found, found


def test_no_test_imports_a_bench_script() -> None:
    importing = {n for n, text in _sources().items() if bench_module_names(imported_modules(text))}
    assert importing - STILL_IMPORT_BENCH == set()
    assert STILL_IMPORT_BENCH - importing == set(), "a file left the list: take it out"


def test_the_rules_catch_a_planted_import() -> None:
    planted = (
        "from tests.test_flows import make_data\n"
        "from .test_plan_split import FAST\n"
        "def f():\n"
        "    import tests.test_cli\n"
        "    from bench.bench_methods import summarise\n"
        "    from bench import results\n"
        "from tests.support.plans import sa_result\n"
        "from twostep.tests_like import x\n"
    )
    names = imported_modules(planted)
    assert module_names_of_tests(names) == {
        "tests.test_flows", "tests.test_flows.make_data", "tests.test_plan_split",
        "tests.test_plan_split.FAST", "tests.test_cli",
    }  # fmt: skip
    assert bench_module_names(names) == {
        "bench.bench_methods", "bench.bench_methods.summarise", "bench", "bench.results"
    }  # fmt: skip
