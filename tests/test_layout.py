"""The house's layout: nothing at the root of ``twostep/`` but ``__init__.py``, whose package
map names exactly the packages on disk (and the site's Layout the top-level folders); no import cycle among the
library's modules; the independent checkers import nothing from ``twostep``; the config
stays in ``flows/`` (no library module uses a config key, a Hydra group or ``.hydra``).

The import graph is read here with :mod:`ast` (every import: module level, under
``TYPE_CHECKING`` and inside functions), not with the bench's code."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import twostep
from tools.config_scan import config_leaks, library_leaks

ROOT = Path(__file__).resolve().parent.parent
LIBRARY = ROOT / "twostep"


def _packages() -> set[str]:
    return {p.parent.name for p in LIBRARY.glob("*/__init__.py")}


def test_nothing_at_the_root_of_the_library_but_its_init() -> None:
    assert sorted(p.name for p in LIBRARY.glob("*.py")) == ["__init__.py"]


def test_the_package_map_names_every_package_once() -> None:
    named = re.findall(r"^- :mod:`twostep\.(\w+)`", twostep.__doc__ or "", re.M)
    assert len(named) == len(set(named)), named
    assert set(named) == _packages()


def test_the_development_page_layout_names_every_top_level_folder() -> None:
    """The site's Layout (docs/development.md) names each folder at the top of the
    repository that git tracks, and no folder that is not there; the library's packages are
    listed by the package map above and the generated API reference."""
    page = (ROOT / "docs" / "development.md").read_text()
    layout = page[page.index("\n## Layout") :]
    block = layout[layout.index("```\n") + 4 :]
    block = block[: block.index("```")]
    named = {m.split("/")[0] for m in re.findall(r"^(\w[\w.-]*/)", block, re.M)}
    tracked = {p.name for p in ROOT.iterdir() if p.is_dir() and not p.name.startswith(".")}
    tracked &= {f.split("/")[0] for f in _git_files()}
    assert named - {"outputs"} == tracked, (named, tracked)


def _git_files() -> list[str]:
    import subprocess

    out = subprocess.run(
        ["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout
    return [line for line in out.splitlines() if "/" in line]


def _module_names(package: Path) -> dict[str, Path]:
    found = {}
    for path in package.rglob("*.py"):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join(parts)] = path
    return found


def _imported(module: str, path: Path, modules: set[str] | None = None) -> set[str]:
    """Every module name an import statement of the file names (``from a import b``:
    module ``a.b`` if it is one of ``modules``, else ``a``; relative imports made absolute)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
            if node.level:
                base = base[: len(base) - node.level + 1]
                source = ".".join([*base, node.module] if node.module else base)
            else:
                source = node.module or ""
            for alias in node.names:
                target = f"{source}.{alias.name}"
                names.add(target if modules is not None and target in modules else source)
    return names


def test_no_import_cycle_among_the_library_modules() -> None:
    modules = _module_names(LIBRARY)
    names = set(modules)
    graph = {m: _imported(m, p, names) & names - {m} for m, p in modules.items()}
    done: set[str] = set()

    def visit(node: str, path: list[str]) -> None:
        if node in path:
            raise AssertionError("import cycle: " + " -> ".join([*path[path.index(node) :], node]))
        if node in done:
            return
        for child in sorted(graph[node]):
            visit(child, [*path, node])
        done.add(node)

    for module in sorted(graph):
        visit(module, [])


def test_the_cycle_finder_finds_a_cycle(tmp_path: Path) -> None:
    """The reading above sees a relative import closing a loop (so the test can fail)."""
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text("from .b import x\n")
    (package / "b.py").write_text("def f():\n    from pkg import a\n")
    modules = _module_names(package)
    names = set(modules)
    assert _imported("pkg.a", modules["pkg.a"], names) & names == {"pkg.b"}
    assert _imported("pkg.b", modules["pkg.b"], names) & names == {"pkg.a"}


def test_the_checkers_import_nothing_from_twostep() -> None:
    checkers = ROOT / "checkers"
    modules = _module_names(checkers)
    assert {"checkers", "checkers.trace_check", "checkers.alfworld_engine"} <= modules.keys()
    for module, path in modules.items():
        imported = _imported(module, path)
        assert not {n for n in imported if n == "twostep" or n.startswith("twostep.")}, module


def test_skip_conditions_are_declared_once() -> None:
    """The IPC sample's place, Chromium's lookup and the alfworld checks are written in
    tests/support/skips.py only."""
    owner = ROOT / "tests" / "support" / "skips.py"
    patterns = ('"ipc-sample"', "= chromium_binary()", "alfworld_layouts_folder() is None",
                "engine_python() is None")  # fmt: skip
    for path in sorted((ROOT / "tests").rglob("*.py")):
        if path in (owner, Path(__file__)):
            continue
        text = path.read_text()
        assert not [p for p in patterns if p in text], path.name


def test_a_moved_module_still_imports_under_its_old_name_with_a_warning() -> None:
    import importlib
    import sys

    for old, new in twostep.MOVED_MODULES.items():
        assert not (ROOT / f"{old.replace('.', '/')}.py").exists()
        assert not (ROOT / old.replace(".", "/")).exists()
        sys.modules.pop(old, None)
        with pytest.warns(DeprecationWarning, match=f"{old} is now {new}"):
            moved = importlib.import_module(old)
        assert moved is importlib.import_module(new)
        sys.modules.pop(old, None)
    for name in ("twostep.execution", "twostep.execution.parallel"):
        sys.modules.pop(name, None)
    with pytest.warns(DeprecationWarning, match="twostep.execution.parallel is now"):
        from twostep.execution.parallel import parallel_length  # type: ignore[import-not-found]
    from twostep.makespan.parallel import parallel_length as moved

    assert parallel_length is moved  # the module itself, not a second copy of its file
    for name in ("twostep.execution", "twostep.execution.parallel"):
        sys.modules.pop(name, None)


def test_a_moved_function_still_imports_under_its_old_name_with_a_warning() -> None:
    import importlib

    for old, new in twostep.MOVED_NAMES.items():
        module, name = old.rsplit(".", 1)
        new_module, new_name = new.rsplit(".", 1)
        with pytest.warns(DeprecationWarning, match=f"{old} is now {new};"):
            moved = getattr(importlib.import_module(module), name)
        assert moved is getattr(importlib.import_module(new_module), new_name)


# ----------------------------------------------------------------- the config stays in flows/


def test_the_library_imports_no_orchestration() -> None:
    """``twostep/`` imports nothing from ``flows/`` (where the config's rules live), nor
    Hydra, Prefect or MLflow: a moved name reaches ``flows/`` only through the deprecation
    hook, by name (``twostep.MOVED_MODULES``, ``twostep.MOVED_NAMES``)."""
    modules = _module_names(LIBRARY)
    banned = ("flows", "hydra", "omegaconf", "prefect", "mlflow")
    for module, path in sorted(modules.items()):
        imported = _imported(module, path)
        assert not {n for n in imported if n.split(".")[0] in banned}, module


def test_the_library_uses_no_config_key_group_or_hydra_folder() -> None:
    found = [f"{name}:{line} {what}" for name, line, what in library_leaks(ROOT)]
    assert not found, "the config's shape in the library (it belongs in flows/):\n" + "\n".join(
        found
    )


def test_the_config_leak_finder_finds_planted_leaks() -> None:
    """Each kind of leak, planted in a module's text, is found on its line (so the test
    above can fail): a message or docstring that names a config key too; the canonical
    columns and result fields the library reads, its own parameters in a message and an
    attribute in an f-string's braces are not leaks; a group's override (``decomposer=llm``)
    is one, a keyword argument or a longer word is not."""
    planted = '''"""A module; its docstring may not say llm.model."""
NOT_IDENTITY = ("hydra", "mlflow")
KEY = "llm.cache_dir"
COLUMN = "param.planner.alias"
def f(config, runs, result, domain):
    llm = config.get("llm")
    script = llm.get("script")
    root = config["data"]["root"]
    name = config.get("method").get("name")
    folder = runs / ".hydra"
    ok = runs["method"], result.get("decomposer"), result["domain"], runs["param." + KEY]
    raise ValueError(f"no answer: record it with llm.mode=live, not {runs['seed']}")
def g(domain, decomposer):
    """Words a message: with LLMSettings.mode=live, not with
    planner.time_limit_s=10."""
    return f"{domain.name} {decomposer.name}: set LLMSettings.model" + "data.rooted"
def h():
    """Sweep it with experiment=paper_replay; GoalSplitDecomposer(decomposer=llm)."""
    return "run(decomposer=GoalSplitDecomposer()), method=plan-dealer, llm=local-ish"
'''
    assert config_leaks(planted) == [
        (1, "llm.model"),
        (2, "hydra"),
        (2, "mlflow"),
        (3, "llm.cache_dir"),
        (4, "param.planner.alias"),
        (7, "llm.script"),
        (8, "data.root"),
        (9, "method.name"),
        (10, ".hydra"),
        (12, "llm.mode"),
        (15, "planner.time_limit_s"),
        (18, "decomposer=llm"),
        (18, "experiment=paper_replay"),
    ]
