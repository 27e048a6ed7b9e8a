"""The documentation site's reference pages, generated from the code on every build.

* :func:`config_page`: every key of the structured config schema (``flows/config.py``), its
  type, its default as the ``twostep`` command composes it from ``conf/`` (the schema's own
  default beside it where ``conf/`` sets another), the values it allows and the comment the
  schema or ``conf/config.yaml`` gives it; then every config group and its options.
* :func:`cli_page`: every console script of ``pyproject.toml``'s ``[project.scripts]``, with
  its ``--help`` output (and each sub-command's).
* :func:`api_pages`: one page per package of ``twostep/`` and ``flows/``, found by walking
  the source tree, each module rendered from its docstrings by mkdocstrings. A module moved
  to another package moves to that package's page with no edit here or in ``mkdocs.yml``.

``tools/mkdocs_hooks.py`` adds the pages to the site; ``python -m tools.reference OUT``
writes them into a folder to read them without a build.
"""

from __future__ import annotations

import ast
import dataclasses
import enum
import io
import os
import re
import subprocess
import sys
import tokenize
import tomllib
import types
import typing
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import yaml

from tools.griffe_roles import without_roles

REPO = Path(__file__).resolve().parent.parent
CONF = REPO / "conf"
SCHEMA_FILE = REPO / "flows" / "config.py"
PACKAGES = ("twostep", "flows")  # walked for the API pages (conf/ and data/ hold no code)
GENERATED = "Generated from the code by `tools/reference.py` on every `make docs`: do not edit."


# ------------------------------------------------------------------------------ config


@dataclasses.dataclass(frozen=True)
class ConfigKey:
    """One key of the schema, e.g. ``orchestration.task_runner``."""

    name: str
    type: str
    allowed: str
    schema_default: Any
    default: Any  # as composed from conf/ (the schema's default where conf/ is silent)
    comment: str


def _comments(source: str) -> dict[tuple[str, str], str]:
    """``(class, field) -> comment`` of a module's dataclass fields: the comment on the
    field's line, else the comment lines right above it."""
    lines: dict[int, str] = {}
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT:
            lines[token.start[0]] = token.string.lstrip("#").strip()
    full = {i for i, text in enumerate(source.splitlines(), 1) if text.strip().startswith("#")}
    found: dict[tuple[str, str], str] = {}
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.ClassDef):
            continue
        for item in node.body:
            if not (isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name)):
                continue
            end = item.end_lineno or item.lineno
            text = next((lines[i] for i in range(item.lineno, end + 1) if i in lines), "")
            if not text:
                above: list[str] = []
                i = item.lineno - 1
                while i in full:
                    above.insert(0, lines.get(i, ""))
                    i -= 1
                text = " ".join(above)
            found[(node.name, item.target.id)] = text
    return found


def _yaml_comments(path: Path) -> dict[str, str]:
    """``dotted key -> inline comment`` of a YAML file of nested mappings (two-space
    indents), as ``conf/config.yaml`` is written."""
    found: dict[str, str] = {}
    stack: list[tuple[int, str]] = []
    for line in path.read_text().splitlines():
        match = re.match(r"^( *)([A-Za-z_][\w-]*):(.*)$", line)
        if not match:
            continue
        indent, key, rest = len(match.group(1)), match.group(2), match.group(3)
        while stack and stack[-1][0] >= indent:
            stack.pop()
        dotted = ".".join([*(k for _, k in stack), key])
        value, _, comment = rest.partition(" #")
        if comment.strip():
            found[dotted] = comment.strip()
        if not value.strip():
            stack.append((indent, key))
    return found


def _type_name(hint: Any) -> str:
    if hint is type(None):
        return "null"
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        return "enum"
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_name(h) for h in typing.get_args(hint))
    if origin is not None:
        args = ", ".join(_type_name(h) for h in typing.get_args(hint))
        return f"{origin.__name__}[{args}]"
    if hint is Any:
        return "any"
    return str(getattr(hint, "__name__", hint))


def _allowed(hint: Any, comment: str) -> str:
    """The values a key takes: an enum's members, true/false, null where it is optional,
    and a list spelled ``a | b | c`` in its comment."""
    options: list[str] = []
    for h in typing.get_args(hint) if typing.get_origin(hint) is types.UnionType else (hint,):
        if isinstance(h, type) and issubclass(h, enum.Enum):
            options += [str(m.value) for m in h]
        elif h is bool:
            options += ["true", "false"]
        elif h is type(None):
            options.append("null")
        elif h in (int, float, str):
            listed = _listed(comment)
            options += listed or [f"any {h.__name__}"]
        else:
            options.append(_type_name(h))
    return " | ".join(dict.fromkeys(options))


_VALUE = r"[\w][\w.-]*(?: \([^)]*\))?"
_LIST = re.compile(rf"(?<![\w-]){_VALUE}(?: \| {_VALUE})+")


def _listed(comment: str) -> list[str]:
    """The values of the first ``a | b (what b is) | c`` list in a comment."""
    match = _LIST.search(comment)
    if not match:
        return []
    return [part.split(" (")[0] for part in match.group(0).split(" | ")]


def _walk(
    cls: type, prefix: str, hints_of: dict[type, dict[str, Any]]
) -> Iterator[tuple[type, str, str, Any, Any]]:
    hints = hints_of.setdefault(cls, typing.get_type_hints(cls))
    for f in dataclasses.fields(cls):
        hint = hints[f.name]
        name = f"{prefix}{f.name}"
        if isinstance(hint, type) and dataclasses.is_dataclass(hint):
            yield from _walk(hint, f"{name}.", hints_of)
            continue
        factory: Any = f.default_factory
        default = f.default if f.default is not dataclasses.MISSING else factory()
        yield cls, f.name, name, hint, default


def composed_defaults() -> dict[str, Any]:
    """The config the ``twostep`` command composes with no override (Hydra over the schema
    and ``conf/``), interpolations left as written; flattened to dotted keys."""
    from hydra import compose, initialize_config_module
    from omegaconf import OmegaConf

    from flows.config import register

    register()
    with initialize_config_module(config_module="flows.conf", version_base="1.3"):
        cfg = compose(config_name="config")
    return dict(_flatten(OmegaConf.to_container(cfg, resolve=False)))


def _flatten(value: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    if isinstance(value, dict) and value:
        for key, item in value.items():
            yield from _flatten(item, f"{prefix}{key}.")
    else:
        yield prefix.rstrip("."), value


def config_keys() -> list[ConfigKey]:
    """Every key of :class:`flows.config.TwostepConfig`, in the schema's order."""
    from flows.checks import VALUE_RULES
    from flows.config import TwostepConfig

    comments = _comments(SCHEMA_FILE.read_text())
    yaml_comments = _yaml_comments(CONF / "config.yaml")
    for group in config_groups():  # the comments of the options conf/config.yaml picks
        path = CONF / group.name / f"{group.default}.yaml"
        picked = group.default and "/" not in group.name and path.is_file()
        if picked and "@package _global_" not in path.read_text():
            for key, text in _yaml_comments(path).items():
                yaml_comments.setdefault(f"{group.name}.{key}", text)
    composed = composed_defaults()
    ranges = {rule.key: rule.allowed for rule in VALUE_RULES}  # what a run checks
    groups = {
        g.name: [_option_name(g.name, o) for o in g.options]
        for g in config_groups()
        if "/" not in g.name
    }
    keys = []
    for cls, field, name, hint, default in _walk(TwostepConfig, "", {}):
        comment = comments.get((cls.__name__, field)) or yaml_comments.get(name, "")
        allowed = _allowed(hint, comment)
        section = name.rsplit(".", 1)[0]
        if name.endswith(".name") and section in groups and section != "domain":
            allowed = " | ".join(groups[section])  # the options registered in conf/
        elif name == "domain.name":
            allowed = "a folder of data.root (group `domain`: " + ", ".join(groups["domain"]) + ")"
        elif name in ranges:  # the range every run is checked against (flows/checks.py)
            allowed = ranges[name]
        if _LIST.fullmatch(comment):
            comment = ""  # the list alone: the allowed values say it
        keys.append(
            ConfigKey(
                name=name,
                type=_type_name(hint),
                allowed=allowed,
                schema_default=_plain(default),
                default=_plain(composed.get(name, default)),
                comment=comment,
            )
        )
    # The default method's options (conf/method/<default>.yaml): keys of its file, not of
    # the schema (a method's options are its own: flows.config.MethodConfig).
    known = {key.name for key in keys}
    for name, value in composed.items():
        if name.startswith("method.") and name not in known:
            comment = yaml_comments.get(name, "")
            keys.append(
                ConfigKey(
                    name=name,
                    type=_type_name(type(value)),
                    allowed=ranges.get(name) or _allowed(type(value), comment),
                    schema_default=_plain(value),
                    default=_plain(value),
                    comment="" if _LIST.fullmatch(comment) else comment,
                )
            )
    return keys


def _plain(value: Any) -> Any:
    return value.value if isinstance(value, enum.Enum) else value


def show(value: Any) -> str:
    """A value as YAML writes it on a command line (``null``, ``true``, ``[a, b]``), the
    package's own data folder by name rather than by this machine's path."""
    from twostep.tasks.benchmark import DEFAULT_DATA_ROOT

    if value == str(DEFAULT_DATA_ROOT):
        return "<the data installed with twostep>"
    if isinstance(value, str):
        return value
    dumped = yaml.safe_dump(value, default_flow_style=True, width=1000).strip()
    return dumped.removesuffix("...").strip()


def _cell(text: str) -> str:
    return text.replace("|", "\\|").strip()


def _code(value: Any) -> str:
    return f"`{show(value)}`".replace("|", "\\|")


@dataclasses.dataclass(frozen=True)
class Group:
    """A config group of ``conf/`` (``domain``, ``hydra/launcher``, ...)."""

    name: str
    default: str | None
    options: dict[str, str]  # option -> the first comment line of its file


def config_groups() -> list[Group]:
    """The groups a user picks options of (``group=option``), with the option
    ``conf/config.yaml`` picks; Hydra's own help and logging groups are left out."""
    defaults: dict[str, str | None] = {}
    for entry in yaml.safe_load((CONF / "config.yaml").read_text())["defaults"]:
        if isinstance(entry, dict):
            for key, value in entry.items():
                if not key.startswith("override"):
                    defaults[key] = value
    groups = []
    for folder in sorted(p for p in CONF.rglob("*") if p.is_dir() and list(p.glob("*.yaml"))):
        name = folder.relative_to(CONF).as_posix()
        if name in ("hydra/help", "hydra/job_logging", "hydra/hydra_logging"):
            continue
        options = {path.stem: _first_comment(path) for path in sorted(folder.glob("*.yaml"))}
        groups.append(Group(name, defaults.get(name), options))
    return groups


def _option_name(group: str, option: str) -> str:
    """The ``name`` an option's file sets (its file name where it sets none)."""
    data = yaml.safe_load((CONF / group / f"{option}.yaml").read_text()) or {}
    return str(data.get("name", option))


def option_sets(group: str, option: str) -> dict[str, Any]:
    """The keys an option's file sets (dotted within the group's package), its defaults
    list and Hydra's keys left out."""
    data = yaml.safe_load((CONF / group / f"{option}.yaml").read_text()) or {}
    data = {k: v for k, v in data.items() if k not in ("defaults", "hydra", "name")}
    return dict(_flatten(data)) if data else {}


def _first_comment(path: Path) -> str:
    lines: list[str] = []
    for line in path.read_text().splitlines():
        if line.startswith("# @package"):
            continue
        if not line.startswith("#"):
            if lines:
                break
            continue
        lines.append(line.lstrip("#").strip())
    text = " ".join(lines)
    return text.split(". ")[0].rstrip(".") if text else ""


def config_page() -> str:
    keys = config_keys()
    out = [
        "# Configuration keys",
        "",
        f"<!-- {GENERATED} -->",
        "",
        "Every key the `twostep` command accepts (`key=value` on the command line, or in a",
        "config file of your own with `--config-dir`). The list is generated from the",
        "structured config schema (`flows/config.py`) and the defaults the command composes",
        "from `conf/`; a key that is not here, or a value of the wrong type, fails at once",
        "with Hydra's message naming the key.",
        "",
        "**default** is what a run gets with no override; where the schema's own default",
        "differs (the value a key takes when `conf/` does not set it), it is shown below it.",
        "`${...}` is an interpolation, resolved when the job runs (`${output.root}` is the",
        "`output.root` key's value).",
        "",
    ]
    sections: dict[str, list[ConfigKey]] = {}
    for key in keys:
        head = key.name.split(".")[0] if "." in key.name else "(top level)"
        sections.setdefault(head, []).append(key)
    for section, members in sections.items():
        out += [f"## `{section}`" if section != "(top level)" else "## Top-level keys", ""]
        out += ["| key | type | default | allowed values | what it is |", "|---|---|---|---|---|"]
        for key in members:
            default = _code(key.default)
            if show(key.default) != show(key.schema_default):
                default += f"<br>schema: {_code(key.schema_default)}"
            cells = [f"`{key.name}`", _cell(key.type), default, _cell(key.allowed)]
            cells.append(_cell(key.comment))
            out.append("| " + " | ".join(cells) + " |")
        out.append("")
    out += [
        "## Config groups",
        "",
        "A group's option (`group=option`, e.g. `domain=grippers`) sets several keys at once",
        "from its file in `conf/<group>/`; the keys above then override single values",
        "(`domain=grippers domain.agent_predicates=[free]`). Your own options go in",
        "`<folder>/<group>/<name>.yaml` with `--config-dir <folder>`.",
        "",
        "| group | default | option | what it is |",
        "|---|---|---|---|",
    ]
    for group in config_groups():
        for option, text in group.options.items():
            default = "yes" if option == group.default else ""
            sets = option_sets(group.name, option)
            if sets and len(sets) <= 3:  # a short option: what it sets says what it is
                text += "<br>" if text else ""
                text += ", ".join(f"`{k}={show(v)}`" for k, v in sets.items())
            cells = [f"`{group.name}`", default, f"`{option}`", _cell(text)]
            out.append("| " + " | ".join(cells) + " |")
    out += [
        "",
        "`hydra/launcher` also takes the options of Hydra's installed launcher plugins",
        "(`basic`, the default; `joblib`; `submitit_local`; `submitit_slurm`), e.g.",
        "`hydra/launcher=joblib hydra.launcher.n_jobs=2`.",
        "",
    ]
    return "\n".join(out)


# ------------------------------------------------------------------------------ commands


def console_scripts() -> dict[str, str]:
    """``name -> module:function`` of ``[project.scripts]``."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    return dict(project["scripts"])


def help_text(name: str, target: str, arguments: tuple[str, ...] = ()) -> str:
    """What ``name [arguments] --help`` prints, run from the source tree (a fresh process,
    100 columns wide, no colour)."""
    module, _, function = target.partition(":")
    code = f"import sys; sys.argv[0] = {name!r}; from {module} import {function} as m; m()"
    env = {**os.environ, "COLUMNS": "100", "NO_COLOR": "1", "PYTHONPATH": str(REPO)}
    env.pop("FORCE_COLOR", None)
    done = subprocess.run(
        [sys.executable, "-c", code, *arguments, "--help"],
        capture_output=True,
        text=True,
        cwd=REPO,
        env=env,
        timeout=120,
        check=False,
    )
    if done.returncode != 0:
        raise RuntimeError(f"{name} {' '.join(arguments)} --help failed: {done.stderr[-500:]}")
    return done.stdout.rstrip()


def _subcommands(text: str) -> list[str]:
    """The choices of the first ``{a,b,c}`` of a usage line."""
    match = re.search(r"\{([\w,-]+)\}", text)
    return match.group(1).split(",") if match else []


def cli_page() -> str:
    scripts = console_scripts()
    with ThreadPoolExecutor(max_workers=4) as pool:
        started = {n: pool.submit(help_text, n, scripts[n]) for n in scripts}
        helps = {n: future.result() for n, future in started.items()}
        subs: dict[tuple[str, str], Any] = {}
        for name, text in helps.items():
            for sub in _subcommands(text):
                subs[(name, sub)] = pool.submit(help_text, name, scripts[name], (sub,))
        sub_helps = {key: future.result() for key, future in subs.items()}
    out = [
        "# Console commands",
        "",
        f"<!-- {GENERATED} -->",
        "",
        "The commands `pip install` / `make setup` put on the PATH (`pyproject.toml`,",
        "`[project.scripts]`), each with its own `--help` output.",
        "",
        "| command | entry point |",
        "|---|---|",
        *(f"| [`{n}`](#{n}) | `{t}` |" for n, t in scripts.items()),
        "",
    ]
    for name, text in helps.items():
        out += [f"## `{name}` {{#{name}}}", "", "```text", f"$ {name} --help", text, "```", ""]
        for (owner, sub), sub_text in sub_helps.items():
            if owner == name and sub_text != text:  # a sub-command of its own
                out += [f"### `{name} {sub}`", "", "```text", f"$ {name} {sub} --help"]
                out += [sub_text, "```", ""]
    return "\n".join(out)


# ------------------------------------------------------------------------------ API


def packages() -> list[str]:
    """Every package under :data:`PACKAGES` (a folder with an ``__init__.py``), dotted."""
    found = []
    for top in PACKAGES:
        for init in sorted((REPO / top).rglob("__init__.py")):
            parts = init.parent.relative_to(REPO).parts
            if not any(p.startswith(("_", ".")) for p in parts):
                found.append(".".join(parts))
    return sorted(found)


def modules(package: str) -> list[str]:
    """The public modules directly in a package (not its sub-packages)."""
    folder = REPO.joinpath(*package.split("."))
    return [
        f"{package}.{path.stem}"
        for path in sorted(folder.glob("*.py"))
        if not path.stem.startswith("_")
    ]


def _summary(module_file: Path) -> str:
    docstring = ast.get_docstring(ast.parse(module_file.read_text())) or ""
    first = docstring.strip().split("\n\n")[0]
    return without_roles(" ".join(first.split()).replace("``", "`"))


def api_page(package: str) -> str:
    folder = REPO.joinpath(*package.split("."))
    out = [f"# `{package}`", "", f"<!-- {GENERATED} -->", ""]
    out += [
        f"::: {package}",
        "    options:",
        "      show_root_heading: false",
        "      members: false",
        "",
    ]
    listed = modules(package)
    subpackages = [p for p in packages() if p.rsplit(".", 1)[0] == package and p != package]
    if listed or subpackages:
        out += ["| module | what it is |", "|---|---|"]
        out += [f"| [`{m}`](#{m}) | {_cell(_summary(folder / (m.rsplit('.', 1)[1] + '.py')))} |"
                for m in listed]  # fmt: skip
        out += [f"| [`{p}`]({p}.md) (package) | {_cell(_summary(REPO.joinpath(*p.split('.'), '__init__.py')))} |"
                for p in subpackages]  # fmt: skip
        out.append("")
    for module in listed:
        out += [f"::: {module}", "    options:", "      show_root_heading: true", ""]
    return "\n".join(out)


def api_index() -> str:
    out = ["# Library API", "", f"<!-- {GENERATED} -->", ""]
    out += [
        "One page per package, rendered from the modules' docstrings. `twostep` is the",
        "library (typed, no orchestration imports); `flows` is the orchestration around it",
        "(Hydra, Prefect, MLflow).",
        "",
        "| package | what it is |",
        "|---|---|",
    ]
    for package in packages():
        init = REPO.joinpath(*package.split("."), "__init__.py")
        out.append(f"| [`{package}`]({package}.md) | {_cell(_summary(init))} |")
    return "\n".join(out) + "\n"


def api_pages() -> dict[str, str]:
    """``path under reference/api/ -> markdown``: the index and one page per package."""
    pages = {"index.md": api_index()}
    pages.update({f"{p}.md": api_page(p) for p in packages()})
    return pages


def pages() -> dict[str, str]:
    """Every generated reference page, by its path under ``docs/``."""
    found = {"reference/config.md": config_page(), "reference/cli.md": cli_page()}
    found.update({f"reference/api/{k}": v for k, v in api_pages().items()})
    return found


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0] if args else "outputs/reference")
    for relative, text in pages().items():
        path = out / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
