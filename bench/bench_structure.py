"""The shape of a package's import graph: modules, cycles, back-arrows, private imports, and
the longest functions.

Every import counts: at module level, under ``if TYPE_CHECKING:`` and inside functions
(they all tie one module to another). An import of ``a.b.c`` points at module ``a.b.c``
when it exists, else at the package or module that defines the name. A *cycle* is a
group of modules that import each other, directly or not (or a module importing itself); a
*back-arrow* is an import that closes a cycle: an edge to a module still open in a
depth-first walk over the modules in sorted order (so the count is reproducible). A
*private import* names another module's ``_name``. Function length counts every line
from ``def`` to the function's last line (docstring and comments included).

With ``--layout`` (the default package only) it prints the house's shape as well:

- *root modules*: the modules at the root of the library package besides ``__init__.py``;
- *config mentions*: where the library's text or code holds the Hydra job config's shape
  (:func:`tools.config_scan.config_leaks`, the finder ``tests/test_layout.py`` uses): a
  dotted config key or a group's override (``decomposer=llm``) in a string or docstring,
  a Hydra-only group, a config lookup by group and field, ``.hydra``;
- *status vocabularies*: the ``*Status`` enums and ``*STATUSES`` constants in the library
  and ``flows/`` and the modules defining them, and the comparisons of a value with a
  bare status string (``==``, ``!=``, ``in`` a literal tuple/list/set, ``.isin``,
  ``.count``; a key test such as ``"error" in result`` is not one) outside the module that
  defines them all, when one does;
- *places a method touches*: for each method, the files of the library, ``flows/`` and
  ``conf/`` that name it (a string literal equal to its name, a ``MethodName`` member of
  it, a config file named after it, or its own module), the old spelling's aside
  (``method=twostep decomposer=plan-deal``: :data:`OLD_SPELLING`, kept for one release).
  A new method touches what the method that nothing else names touches (the fewest of
  :data:`NEW_METHODS`); the most is shown too: the others are named by features built on
  them (plan-deal is the default and the replay's baseline). A count of names, not of
  edits: ``tests/test_method_names.py`` adds a toy method with one module, one registry
  line and one config file;
- *imports among the folders*: test files importing a bench script, bench scripts
  importing another (:mod:`tools.import_scan`).

With ``--before REVISION`` the same is printed first for that revision's tree (``git
archive``), then for this checkout, then a table of the counts side by side; ``--json
FILE`` writes that output as a record (``tools/record.py``) for the results page.

    .venv/bin/python bench/bench_structure.py                 # twostep/ of this checkout
    .venv/bin/python bench/bench_structure.py --root /path/to/checkout --package flows
    .venv/bin/python bench/bench_structure.py --layout        # + root modules, config, ...
    .venv/bin/python bench/bench_structure.py --layout --before 2869c6e --json docs/bench/structure.json
"""

from __future__ import annotations

import argparse
import ast
import io
import subprocess
import sys
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager, redirect_stdout
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from tools import record  # noqa: E402
from tools.config_scan import library_leaks  # noqa: E402
from tools.import_scan import bench_importers_among_tests, bench_scripts_importing_another  # noqa: E402
from tools.status_scan import bare_status_comparisons  # noqa: E402


@dataclass(frozen=True)
class Function:
    module: str
    name: str  # dotted inside the module: Class.method, outer.inner
    line: int
    length: int


def module_names(root: Path, package: str) -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` file of ``package`` under ``root``."""
    found = {}
    for path in sorted((root / package).rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join(parts)] = path
    return found


def _absolute(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".")
    base = base if is_package else base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def imports(
    module: str, path: Path, modules: Mapping[str, Path]
) -> Iterator[tuple[str, str | None]]:
    """``(imported module, private name or None)`` for every import in the file."""
    tree = ast.parse(path.read_text(), str(path))
    is_package = path.name == "__init__.py"
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name in modules:
                    yield alias.name, None
        elif isinstance(node, ast.ImportFrom):
            source = _absolute(module, is_package, node)
            for alias in node.names:
                target = f"{source}.{alias.name}"
                if target in modules:
                    yield target, None
                elif source in modules:
                    private = alias.name if alias.name.startswith("_") else None
                    yield source, private


def functions(module: str, path: Path) -> Iterator[Function]:
    tree = ast.parse(path.read_text(), str(path))

    def walk(node: ast.AST, prefix: str) -> Iterator[Function]:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef):
                name = f"{prefix}{child.name}"
                length = (child.end_lineno or child.lineno) - child.lineno + 1
                yield Function(module, name, child.lineno, length)
                yield from walk(child, f"{name}.")
            elif isinstance(child, ast.ClassDef):
                yield from walk(child, f"{prefix}{child.name}.")
            else:
                yield from walk(child, prefix)

    yield from walk(tree, "")


def reachable(graph: Mapping[str, set[str]], start: str) -> set[str]:
    """Every module ``start`` reaches by imports (itself only through a cycle)."""
    seen: set[str] = set()
    frontier = list(graph[start])
    while frontier:
        node = frontier.pop()
        if node not in seen:
            seen.add(node)
            frontier.extend(graph[node])
    return seen


def cycles_of(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """The groups of modules that import each other, directly or not (a module importing
    itself is a group of one); the graphs here are small enough to compare reach sets."""
    reach = {node: reachable(graph, node) for node in graph}
    groups: list[list[str]] = []
    placed: set[str] = set()
    for node in sorted(graph):
        if node in placed or node not in reach[node]:
            continue
        group = sorted(other for other in reach[node] if node in reach[other])
        placed.update(group)
        groups.append(group)
    return groups


def back_arrows(graph: Mapping[str, set[str]]) -> list[tuple[str, str]]:
    """Edges to a module still open in a depth-first walk in sorted order."""
    state: dict[str, int] = {}  # 1 open, 2 done
    found: list[tuple[str, str]] = []
    for start in sorted(graph):
        if start in state:
            continue
        state[start] = 1
        work = [(start, iter(sorted(graph[start])))]
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is None:
                state[node] = 2
                work.pop()
            elif state.get(child) == 1:
                found.append((node, child))
            elif child not in state:
                state[child] = 1
                work.append((child, iter(sorted(graph[child]))))
    return found


METHODS = ("sa", "ma", "twostep", "plan-deal", "portfolio", "portfolio-lite")
NEW_METHODS = ("plan-deal", "portfolio", "portfolio-lite")  # the headline: methods added
# after the paper's (the paper's own are named all over: "twostep" is also the project)
OLD_SPELLING = ("flows/spelling.py", "conf/decomposer/")  # method=twostep decomposer=<method>


# Words that are statuses besides the enums' values (the report's, the unfinished set's).
STATUS_WORDS = {"success", "failed", "running", "error", "timeout"}
NOT_ONLY_STATUS = {"none"}  # also the LLM's answer kind and a CLI value


def status_vocabularies(root: Path) -> tuple[list[str], list[tuple[str, int, str]]]:
    """The status vocabularies of the library and ``flows/`` (``module.Name``), and the
    comparisons with a bare string that is one of their values (module, line, string),
    outside the module that defines them all (when one does)."""
    vocabularies: list[str] = []
    values: set[str] = set()
    trees = {}
    for package in ("twostep", "flows"):
        for module, path in module_names(root, package).items():
            tree = ast.parse(path.read_text(), str(path))
            trees[module] = tree
            for node in tree.body:
                if isinstance(node, ast.ClassDef) and node.name.endswith("Status"):
                    vocabularies.append(f"{module}.{node.name}")
                    for item in node.body:
                        if isinstance(item, ast.Assign) and isinstance(item.value, ast.Constant):
                            values.add(str(item.value.value))
                targets = (
                    [node.target] if isinstance(node, ast.AnnAssign)
                    else node.targets if isinstance(node, ast.Assign) else []
                )  # fmt: skip
                for target in targets:
                    if isinstance(target, ast.Name) and target.id.endswith("STATUSES"):
                        vocabularies.append(f"{module}.{target.id}")
    values = (values | STATUS_WORDS) - NOT_ONLY_STATUS
    owners = {name.rsplit(".", 1)[0] for name in vocabularies}
    bare = [
        (module, line, word)
        for module, tree in trees.items()
        if not (len(owners) == 1 and module in owners)
        for line, word in bare_status_comparisons(tree, values)
    ]
    return vocabularies, sorted(bare)


def method_places(root: Path) -> dict[str, list[str]]:
    """Method -> the files of twostep/, flows/ and conf/ that name it."""
    places: dict[str, set[str]] = {m: set() for m in METHODS}
    for package in ("twostep", "flows"):
        for path in module_names(root, package).values():
            shown = path.relative_to(root).as_posix()
            tree = ast.parse(path.read_text(), str(path))
            for method in METHODS:
                if path.stem == method.replace("-", "_") and "methods" in path.parts:
                    places[method].add(shown)
            for node in ast.walk(tree):
                if isinstance(node, ast.Constant) and node.value in places:
                    places[str(node.value)].add(shown)
                elif (
                    isinstance(node, ast.Attribute)
                    and isinstance(node.value, ast.Name)
                    and node.value.id == "MethodName"
                    and node.attr.lower().replace("_", "-") in places
                ):
                    places[node.attr.lower().replace("_", "-")].add(shown)
    for path in (root / "conf").rglob("*.yaml"):
        if path.stem in places and "hydra" not in path.parts:
            places[path.stem].add(path.relative_to(root).as_posix())
    return {m: sorted(found) for m, found in places.items()}


def layout(root: Path, package: str) -> dict[str, object]:
    """Print the house's shape; return its counts by name (the record's rows)."""
    top = sorted(p.name for p in (root / package).glob("*.py") if p.name != "__init__.py")
    print(f"root modules: {len(top)}")
    if top:
        print(f"  {' '.join(top)}")
    mentions = library_leaks(root, package)
    print(f"config mentions in the library: {len(mentions)} "
          f"in {len({m for m, _, _ in mentions})} modules")  # fmt: skip
    for module, line, text in mentions:
        print(f"  {module}:{line} {text!r}")
    vocabularies, bare = status_vocabularies(root)
    owners = sorted({name.rsplit(".", 1)[0] for name in vocabularies})
    print(f"status vocabularies: {len(vocabularies)} in {len(owners)} modules")
    for name in vocabularies:
        print(f"  {name}")
    print(f"bare status-string comparisons: {len(bare)}")
    for module, line, text in bare:
        print(f"  {module}:{line} {text!r}")
    places = method_places(root)
    # The old spelling's shim (a tree with flows/spelling.py) is not where a method lives;
    # before it existed, conf/decomposer/ was where the methods were configured.
    shim = OLD_SPELLING if (root / OLD_SPELLING[0]).exists() else ()
    old = {m: [f for f in files if shim and f.startswith(shim)] for m, files in places.items()}
    places = {m: [f for f in files if f not in old[m]] for m, files in places.items()}
    fewest = min(NEW_METHODS, key=lambda m: (len(places[m]), m))
    most = max(NEW_METHODS, key=lambda m: (len(places[m]), m))
    print(f"places a new method touches (the fewest of {', '.join(NEW_METHODS)}, as {fewest}): "
          f"{len(places[fewest])}; the most (as {most}): {len(places[most])}")  # fmt: skip
    for method, files in places.items():
        print(f"  {method}: {len(files)}: {' '.join(files)}")
    for title, found in (
        ("test files importing a bench script", bench_importers_among_tests(root)),
        ("bench scripts importing another", bench_scripts_importing_another(root)),
    ):
        print(f"{title}: {len(found)}")
        for path, names in found.items():
            print(f"  {path}: {' '.join(n for n in names if '.' not in n.removeprefix('bench.'))}")
    spelled = {m: files for m, files in old.items() if files}
    if spelled:
        print(f"old spelling (for one release): {sum(map(len, spelled.values()))} places")
        for method, files in spelled.items():
            print(f"  {method}: {' '.join(files)}")
    imports_of = {
        "tests importing bench": len(bench_importers_among_tests(root)),
        "bench scripts importing another": len(bench_scripts_importing_another(root)),
    }
    return {
        "root modules": len(top),
        "config mentions in the library": len(mentions),
        "modules defining a status vocabulary": len(owners),
        "bare status-string comparisons": len(bare),
        "places a new method touches (fewest)": len(places[fewest]),
        "places a new method touches (most)": len(places[most]),
        **imports_of,
    }


def report(
    root: Path, package: str, longest: int, shown: str, with_layout: bool
) -> dict[str, object]:
    """Print the shape of ``package`` under ``root`` (named ``shown``); return its counts."""
    modules = module_names(root, package)
    graph: dict[str, set[str]] = {m: set() for m in modules}
    private: list[tuple[str, str, str]] = []
    for module, path in modules.items():
        for target, name in imports(module, path, modules):
            graph[module].add(target)
            if name is not None and target != module:
                private.append((module, target, name))
    cycles = cycles_of(graph)
    arrows = back_arrows(graph)
    print(f"package {package} under {shown}")
    print(f"modules: {len(modules)}, imports between them: {sum(map(len, graph.values()))}")
    print(f"cycles: {len(cycles)}")
    for cycle in cycles:
        print(f"  {' <-> '.join(cycle)}")
    print(f"back-arrows: {len(arrows)}")
    for source, target in arrows:
        print(f"  {source} -> {target}")
    print(f"private imports: {len(private)}")
    for source, target, name in private:
        print(f"  {source} imports {target}.{name}")
    every = [f for module, path in modules.items() for f in functions(module, path)]
    every.sort(key=lambda f: (-f.length, f.module, f.line))
    print(f"functions: {len(every)}; over 60 lines: {sum(f.length > 60 for f in every)}, "
          f"over 100 lines: {sum(f.length > 100 for f in every)}")  # fmt: skip
    print(f"{longest} longest:")
    for f in every[:longest]:
        print(f"  {f.length:4d}  {f.module}.{f.name} (line {f.line})")
    counts: dict[str, object] = {"modules": len(modules), "cycles": len(cycles)}
    if with_layout:
        counts.update(layout(root, package))
    return counts


@contextmanager
def checkout_of(revision: str) -> Iterator[Path]:
    """The tree of ``revision`` of this repository in a temporary folder (``git archive``)."""
    with tempfile.TemporaryDirectory(prefix="structure-") as tmp:
        archive = subprocess.run(
            ["git", "-C", str(REPO), "archive", revision], capture_output=True, check=True
        ).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        yield Path(tmp)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=str(REPO))
    parser.add_argument("--package", default="twostep")
    parser.add_argument("--longest", type=int, default=10)
    parser.add_argument("--layout", action="store_true", help="also the house's shape")
    parser.add_argument(
        "--before",
        metavar="REVISION",
        help="first the same for this git revision (e.g. 2869c6e), then a table",
    )
    parser.add_argument("--json", type=Path, help="write the record (counts and printed text)")
    args = parser.parse_args(argv)
    with record.capture(args.json, title="The library's shape"):
        columns: dict[str, dict[str, object]] = {}
        printed = io.StringIO()  # the counts' table first, then the reports it sums up
        with redirect_stdout(printed):
            if args.before:
                with checkout_of(args.before) as before:
                    print(f"## before: {args.before}\n")
                    columns[args.before] = report(before, args.package, args.longest,
                                                  f"<{args.before}>", args.layout)  # fmt: skip
                print("\n## after: this checkout\n")
            shown = "<this checkout>" if args.before else args.root
            columns["now"] = report(Path(args.root), args.package, args.longest, shown, args.layout)
        if args.before:
            rows = [[name, *(c.get(name, "") for c in columns.values())] for name in columns["now"]]
            for line in record.table(["measure", *columns], rows):
                print(line)
            print()
        print(printed.getvalue(), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
