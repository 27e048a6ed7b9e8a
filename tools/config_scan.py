"""Where code holds the job config's shape: the leaks ``tests/test_layout.py`` forbids in
the library (the config stays in ``flows/``) and ``bench/bench_structure.py --layout``
counts, before and after.

The config's names are read from this checkout: the dotted keys from the schema Hydra
checks every config against (``flows.config.schema_keys``), the groups' options from the
files of ``conf/``."""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

#: Groups only the orchestration has (never a field of a result, a column of a run table).
HYDRA_ONLY = ("hydra", "orchestration", "mlflow", "output", "experiment")


@dataclass(frozen=True)
class ConfigNames:
    """What the job config is called: its dotted keys, each group's fields, and each
    config group's options (``method`` -> ``sa``, ``plan-deal``, ...)."""

    dotted: frozenset[str]
    fields: dict[str, frozenset[str]]
    options: dict[str, frozenset[str]]


@cache
def config_names() -> ConfigNames:
    from flows.config import schema_keys

    dotted = frozenset(k for k in schema_keys() if "." in k)
    fields: dict[str, set[str]] = {"hydra": set()}
    for key in dotted:
        group, field = key.split(".", 1)
        fields.setdefault(group, set()).add(field.split(".")[0])
    conf = REPO / "conf"
    options = {
        folder.name: frozenset(p.stem for p in folder.glob("*.yaml"))
        for folder in sorted(conf.iterdir())
        if folder.is_dir() and folder.name not in ("hydra", "__pycache__")
    }
    return ConfigNames(dotted, {g: frozenset(f) for g, f in fields.items()}, options)


def _key_of(node: ast.AST) -> tuple[ast.AST, str] | None:
    """``(object, key)`` of a lookup by a literal: ``x["k"]`` or ``x.get("k", ...)``."""
    if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
        key = node.slice.value
        return (node.value, key) if isinstance(key, str) else None
    if (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and node.func.attr == "get"
        and node.args
        and isinstance(node.args[0], ast.Constant)
        and isinstance(node.args[0].value, str)
    ):
        return node.func.value, node.args[0].value
    return None


@cache
def _token() -> re.Pattern[str]:
    """The dotted keys and group overrides as one pattern (built once)."""
    names = config_names()
    keys = sorted(names.dotted, key=len, reverse=True)
    overrides = sorted(
        (f"{group}={option}" for group, found in names.options.items() for option in found),
        key=len,
        reverse=True,
    )
    return re.compile(
        r"(?<![\w.])(?:"
        + r"(?:param\.)?(?:" + "|".join(re.escape(k) for k in keys) + r")(?!\w)"
        + r"|(?:" + "|".join(re.escape(o) for o in overrides) + r")(?![\w-])"
        + r")"
    )  # fmt: skip


def config_leaks(source: str) -> list[tuple[int, str]]:
    """``(line, what)`` for every place a module's text holds the job config's shape:

    - a string or docstring that holds a dotted config key as a whole token (``"llm.model"``,
      ``"... record it with llm.mode=live"``), or the run-table column of one
      (``"param.planner.alias"``): the library names its own parameters
      (``LLMSettings.mode``) and ``flows/`` words them with the keys (``flows.wording``);
      code is not text (``domain.name``, an attribute, in an f-string's braces is code);
    - a string or docstring that holds a config group's override (``decomposer=llm``,
      ``method=plan-deal``, ``experiment=paper_replay``: a group of ``conf/`` and one of
      its files); a Python keyword argument (``decomposer=GoalSplitDecomposer()``) is not one;
    - a string that is a group only the orchestration has (``"mlflow"``, ``"hydra"``, ...);
    - a group's field looked up in that group: ``config["llm"]["script"]``,
      ``config.get("data").get("root")``, or ``llm.get("script")`` on a variable named
      after the group;
    - ``.hydra`` anywhere in the text (Hydra's run-directory layout), comments too."""
    names = config_names()
    token = _token()
    tree = ast.parse(source)
    found = [(n, ".hydra") for n, line in enumerate(source.splitlines(), 1) if ".hydra" in line]
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            text = node.value
            hits = list(token.finditer(text))
            # a key in a string of many lines: the line it is on
            if isinstance(node.end_lineno, int) and node.end_lineno == node.lineno:
                found += [(node.lineno, m.group(0)) for m in hits]
            else:
                found += [(node.lineno + text[: m.start()].count("\n"), m.group(0)) for m in hits]
            if text in HYDRA_ONLY:
                found.append((node.lineno, text))
            continue
        lookup = _key_of(node) if isinstance(node, ast.expr) else None
        if lookup is None or not isinstance(node, ast.expr):
            continue
        inner, field = lookup
        group = inner.id if isinstance(inner, ast.Name) else None
        outer = _key_of(inner)
        if outer is not None:
            group = outer[1]
        if group in names.fields and field in names.fields[group]:
            found.append((node.lineno, f"{group}.{field}"))
    return sorted(set(found))


def library_leaks(root: Path, package: str = "twostep") -> list[tuple[str, int, str]]:
    """``(file, line, what)`` of every leak in the package ``package`` under ``root``."""
    found = []
    for path in sorted((root / package).rglob("*.py")):
        shown = path.relative_to(root).as_posix()
        found += [(shown, line, what) for line, what in config_leaks(path.read_text())]
    return found
