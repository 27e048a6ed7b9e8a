"""The tests in order: no test module imports another test module (shared helpers live in
tests/examples.py, tests/support/ or conftest.py), no test imports a bench script (what a
test needs lives in the library, checkers/, evaluation/, tools/ or tests/support/, and the
bench imports it from there), and no bench script imports another one.

Imports are read with :mod:`ast` (module level and inside functions); each rule is shown
to catch a planted import."""

from __future__ import annotations

from pathlib import Path

from tools.import_scan import (
    bench_importers_among_tests,
    bench_module_names,
    bench_script_names,
    bench_scripts_importing_another,
    imported_modules,
    module_names_of_tests,
    offenders,
)

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent
BENCH = REPO / "bench"


def test_no_test_module_imports_another() -> None:
    found = offenders(sorted(TESTS.rglob("*.py")), module_names_of_tests, "tests", REPO)
    assert not found, found


def test_no_test_imports_a_bench_script() -> None:
    assert not bench_importers_among_tests(REPO)


def test_no_bench_script_imports_another() -> None:
    assert not bench_scripts_importing_another(REPO)


def test_the_repository_code_beside_the_benches_imports_none() -> None:
    """evaluation/, tools/ and checkers/ serve the benches and the tests: none imports a
    bench script (a results page's renderer included: :data:`tools.results.PAGES` names
    its module)."""
    from tools.results import PAGES

    for folder in ("evaluation", "tools", "checkers"):
        found = offenders(sorted((REPO / folder).rglob("*.py")), bench_module_names, folder, REPO)
        assert not found, found
    assert not bench_module_names({page.render.partition(":")[0] for page in PAGES})


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
    in_bench = (
        "from bench_execution import CASES\n"
        "from bench import record\n"
        "from .bench_sweep import targets\n"
        "def f():\n"
        "    import bench.bench_load\n"
        "from evaluation.tracks import build\n"
        "from tools import record\n"
    )
    assert bench_script_names(BENCH)(imported_modules(in_bench, package="bench")) == {
        "bench_execution", "bench_execution.CASES", "bench", "bench.record",
        "bench.bench_sweep", "bench.bench_sweep.targets", "bench.bench_load",
    }  # fmt: skip
