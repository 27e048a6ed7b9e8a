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

    .venv/bin/python bench/bench_structure.py                 # twostep/ of this checkout
    .venv/bin/python bench/bench_structure.py --root /path/to/checkout --package flows
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path


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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=str(Path(__file__).resolve().parent.parent))
    parser.add_argument("--package", default="twostep")
    parser.add_argument("--longest", type=int, default=10)
    args = parser.parse_args(argv)
    modules = module_names(Path(args.root), args.package)
    graph: dict[str, set[str]] = {m: set() for m in modules}
    private: list[tuple[str, str, str]] = []
    for module, path in modules.items():
        for target, name in imports(module, path, modules):
            graph[module].add(target)
            if name is not None and target != module:
                private.append((module, target, name))
    cycles = cycles_of(graph)
    arrows = back_arrows(graph)
    print(f"package {args.package} under {args.root}")
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
    print(f"{args.longest} longest:")
    for f in every[: args.longest]:
        print(f"  {f.length:4d}  {f.module}.{f.name} (line {f.line})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
