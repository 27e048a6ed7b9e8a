"""The documentation site's generated parts (mkdocs.yml; ``make docs``, ``make results``).

* The config reference lists every key of the schema with the default the command
  composes; the expected default is derived here from ``flows/config.py``'s dataclasses and
  the YAML files of ``conf/`` merged by hand (schema, then the defaults list's options, then
  ``conf/config.yaml`` itself), not by Hydra, which the generator uses.
* The console commands' page holds what each installed console script prints for
  ``--help`` (run here as a user runs it), and the API pages cover every module found by
  ``pkgutil`` (the generator walks the file tree).
* The results pages are what ``make results`` makes from the committed rows, every file of
  ``docs/bench/`` is a page's rows or listed in its index and cited, and no page written by
  hand holds a results number (a decimal outside code): those come from generated pages.
"""

from __future__ import annotations

import dataclasses
import enum
import os
import pkgutil
import re
import subprocess
import sys
import tomllib
import typing
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.support.docs import NUMBER, prose
from tools import reference, results

REPO = Path(__file__).resolve().parent.parent
DOCS = REPO / "docs"
README_FILE = REPO / "README.md"


# ------------------------------------------------------------------------------ config


def schema_defaults() -> dict[str, Any]:
    """Every leaf key of TwostepConfig with its dataclass default."""
    from flows.config import TwostepConfig

    found: dict[str, Any] = {}

    def walk(cls: type, prefix: str) -> None:
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            if dataclasses.is_dataclass(hints[f.name]):
                walk(hints[f.name], f"{prefix}{f.name}.")
                continue
            factory: Any = f.default_factory
            value = f.default if f.default is not dataclasses.MISSING else factory()
            found[f"{prefix}{f.name}"] = value.value if isinstance(value, enum.Enum) else value

    walk(TwostepConfig, "")
    return found


def flat(data: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict) and value:
            out.update(flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def composed_by_hand() -> dict[str, Any]:
    """The schema's defaults, then each group option conf/config.yaml's defaults list picks
    (its keys under the group's name), then conf/config.yaml's own keys (``_self_`` last)."""
    conf = REPO / "conf"
    values = schema_defaults()
    main = yaml.safe_load((conf / "config.yaml").read_text())
    for entry in main["defaults"]:
        if not isinstance(entry, dict):
            continue
        ((group, option),) = entry.items()
        if group.startswith("override") or option is None:
            continue
        text = (conf / group / f"{option}.yaml").read_text()
        assert "@package" not in text  # the default options are plain group files
        data = {k: v for k, v in (yaml.safe_load(text) or {}).items() if k != "defaults"}
        values.update(flat(data, f"{group}."))
    values.update({k: v for k, v in flat(main).items() if k in values})
    return values


def as_written(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, list):
        return "[" + ", ".join(str(v) for v in value) + "]"
    return str(value)


def test_the_config_reference_lists_every_key_with_its_default() -> None:
    from twostep.tasks.benchmark import DEFAULT_DATA_ROOT

    keys_part = reference.config_page().split("## Config groups")[0]
    rows = {
        line.split(" | ")[0].strip("| `"): line
        for line in keys_part.splitlines()
        if line.startswith("| `")
    }
    expected = composed_by_hand()
    assert len(expected) > 50  # the schema has its sections (a walk that found nothing fails)
    for key, value in expected.items():
        assert key in rows, f"{key} is not on the config reference page"
        shown = (
            "<the data installed with twostep>"
            if value == str(DEFAULT_DATA_ROOT)
            else as_written(value)
        )
        default_cell = rows[key].split(" | ")[2]
        if isinstance(value, int | float) and not isinstance(
            value, bool
        ):  # 60 is a float key's 60.0
            assert float(default_cell.split("`")[1]) == value, (key, value, default_cell)
            continue
        assert default_cell.startswith(f"`{shown}`".replace("|", "\\|")), (key, shown, default_cell)
    # a few values checked against conf/ as written: a group's option and an interpolation
    assert rows["planner.alias"].split(" | ")[2] == "`lama-first`"
    assert rows["output.root"].split(" | ")[2].startswith("`${hydra:runtime.cwd}/outputs`")
    assert (
        "`[at-robby, free, carry]`" not in rows["domain.agent_predicates"]
    )  # not the default domain's


def test_the_config_reference_gives_the_ranges_a_run_is_checked_against() -> None:
    """A key with a range (flows/checks.py) shows it, not just its type."""
    from flows.checks import VALUE_RULES

    keys_part = reference.config_page().split("## Config groups")[0]
    allowed = {
        line.split(" | ")[0].strip("| `"): line.split(" | ")[3]
        for line in keys_part.splitlines()
        if line.startswith("| `")
    }
    # by hand: a sampling temperature from 0 to 2, at least one agent, a positive time limit
    assert "0 to 2" in allowed["llm.temperature"]
    assert ">= 1" in allowed["agents"] and "any int" not in allowed["agents"]
    assert allowed["planner.time_limit_s"].startswith("> 0")
    for rule in VALUE_RULES:
        if not rule.key.endswith(".name"):  # a group's options stand for its names
            assert allowed[rule.key] == rule.allowed.replace("|", "\\|"), rule.key


def test_the_config_reference_lists_every_group_option() -> None:
    page = reference.config_page()
    for folder in (REPO / "conf").iterdir():
        if folder.is_dir() and folder.name != "hydra":
            for option in folder.glob("*.yaml"):
                assert f"| `{folder.name}` |" in page and f"| `{option.stem}` |" in page, option
    assert "| `hydra/launcher` |  | `slurm` |" in page


# ------------------------------------------------------------------------------ commands


def test_the_commands_page_holds_each_installed_scripts_help() -> None:
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    page = reference.cli_page()
    env = {**os.environ, "COLUMNS": "100", "NO_COLOR": "1"}
    for name in scripts:
        script = Path(sys.executable).with_name(name)
        done = subprocess.run([str(script), "--help"], capture_output=True, text=True, env=env,
                              cwd=REPO, timeout=120, check=True)  # fmt: skip
        assert f"$ {name} --help\n{done.stdout.rstrip()}\n```" in page, name
    # a sub-command's own help: twostep-data scale
    done = subprocess.run([str(Path(sys.executable).with_name("twostep-data")), "scale", "--help"],
                          capture_output=True, text=True, env=env, cwd=REPO, timeout=120, check=True)  # fmt: skip
    assert done.stdout.rstrip() in page


# ------------------------------------------------------------------------------ API


def walk(package: str, folder: Path) -> tuple[set[str], set[str]]:
    """(packages, modules) under ``folder`` by pkgutil (nothing imported)."""
    packages, modules = {package}, set()
    for info in pkgutil.iter_modules([str(folder)]):
        if info.name.startswith("_"):
            continue
        name = f"{package}.{info.name}"
        if info.ispkg:
            more_packages, more_modules = walk(name, folder / info.name)
            packages |= more_packages
            modules |= more_modules
        else:
            modules.add(name)
    return packages, modules


def test_the_api_reference_has_a_page_per_package_with_each_of_its_modules() -> None:
    pages = reference.api_pages()
    for top in ("twostep", "flows"):
        packages, modules = walk(top, REPO / top)
        for package in packages:
            assert f"{package}.md" in pages, package
            assert f"[`{package}`]({package}.md)" in pages["index.md"]
        for module in modules:
            owner = module.rsplit(".", 1)[0]
            assert f"\n::: {module}\n" in pages[f"{owner}.md"], module
    assert (
        "twostep.dealing.deal" in pages["twostep.dealing.md"]
    )  # a real module, not a walk of nothing


# ------------------------------------------------------------------------------ results


def test_every_results_page_is_what_make_results_makes_from_the_committed_rows() -> None:
    problems = results.stale(results.generate())
    assert problems == [], "run `make results` and commit:\n" + "\n\n".join(problems)


def cited_outside_the_folder(name: str) -> bool:
    """``name`` (``docs/bench/...``) is named by the README, the CHANGELOG, a test, a bench
    or a page of the site outside docs/bench/ (a results page links it as ``../bench/...``:
    the printed output that names the command of rows written before bench records)."""
    places = [REPO / "README.md", REPO / "CHANGELOG.md", *(REPO / "tests").glob("*.py"),
              *(REPO / "bench").glob("*.py"), *(p for p in DOCS.rglob("*.md") if "bench" not in p.parts)]  # fmt: skip
    linked = f"](../{name.removeprefix('docs/')})"
    return any(
        name in p.read_text() or (p.parent.name == "results" and linked in p.read_text())
        for p in places
        if p.name not in ("results.py", "test_docs_site.py")
    )


def test_every_file_of_docs_bench_is_a_pages_rows_or_listed_and_cited() -> None:
    sources = {name for page in results.PAGES for name in page.sources}
    listed = {f.name for f in results.BENCH_FILES}
    assert not sources & listed
    for path in (DOCS / "bench").iterdir():
        if path.name in ("README.md", "archive"):
            continue
        assert path.name in sources | listed, (
            f"docs/bench/{path.name}: no page reads it, the index does not list it"
        )
        if path.name in listed:  # kept for a citation: it must have one
            assert cited_outside_the_folder(f"docs/bench/{path.name}"), (
                f"docs/bench/{path.name} is cited nowhere"
            )
    for name in listed | sources:
        assert (DOCS / "bench" / name).is_file(), f"docs/bench/{name} is listed but missing"
    archived = {p.name for p in (DOCS / "bench" / "archive").iterdir()}
    assert archived == set(results.ARCHIVED)
    for name in archived:
        assert cited_outside_the_folder(f"docs/bench/archive/{name}"), name
    index = (DOCS / "bench" / "README.md").read_text()
    for name in sources | listed:
        assert f"[`{name}`]({name})" in index


GENERATED = ("Generated by `make results`", "by `twostep-report")
# Numbers in pages written by hand that are not results: addresses and versions.
NOT_RESULTS_ANYWHERE = {"127.0.0.1"}
NOT_RESULTS = {
    "install.md": {"2.24", "18.04", "3.11", "3.12", "3.13", "4.3.1", "3.11.2", "0.13.8"},
    "index.md": {"3.11", "3.12"},
    "tutorial/index.md": {"3.17", "3.17.2"},  # the MLflow version whose UI it clicks through
    "how-to/embodied.md": {"1.7.0"},  # TextWorld's
    # the figures' print widths in inches (one and two columns): a specification
    "how-to/reproduce-paper.md": {"3.5", "7.16"},
}


def site_pages() -> list[Path]:
    excluded = yaml.safe_load((REPO / "mkdocs.yml").read_text().split("\ntheme:")[0])[
        "exclude_docs"
    ]
    skip = {DOCS / line.strip().lstrip("/") for line in excluded.splitlines() if line.strip()}
    return [p for p in sorted(DOCS.rglob("*.md")) if p not in skip]


def test_no_page_written_by_hand_holds_a_results_number() -> None:
    checked = 0
    for path in site_pages():
        text = path.read_text()
        if any(mark in text[:600] for mark in GENERATED):
            continue
        checked += 1
        name = path.relative_to(DOCS).as_posix()
        allowed = NOT_RESULTS_ANYWHERE | NOT_RESULTS.get(name, set())
        numbers = NUMBER.findall(prose(text))
        found = [n for n in numbers if n not in allowed]
        assert not found, (
            f"{path.relative_to(REPO)}: {found}: generate them (make results) and link the page"
        )
    assert checked > 10


def test_the_number_check_finds_a_typed_number() -> None:
    assert re.findall(
        r"(?<![\w.])\d+(?:\.\d+)+", prose("plan-deal gives `0.532` or 0.532 (`x`)")
    ) == ["0.532"]


@pytest.mark.parametrize("page", results.PAGES, ids=lambda p: p.slug)
def test_each_results_page_names_its_rows_and_has_a_figure(page: results.Page) -> None:
    text = (DOCS / "results" / f"{page.slug}.md").read_text()
    for name in page.sources:
        assert f"[`docs/bench/{name}`](../bench/{name})" in text
    for figure in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text):
        assert (DOCS / "results" / figure).is_file(), figure
    # faults: a table of counts, all 0 when they pass; a printed output: its tables and text
    if page.slug not in ("faults",) and page.render != "tools.record:printed_page":
        assert "![" in text


PATH_IN_CODE = re.compile(
    r"`((?:twostep|flows|bench|evaluation|tests|tools|conf|data|docs)/[\w./-]*\w)`"
)


def test_every_repository_path_the_readme_and_pages_name_exists() -> None:
    """A module or file moved in the code leaves no page pointing at its old place."""
    pages = [README_FILE, *(p for p in site_pages() if not p.read_text()[:600].count("Generated"))]
    named = 0
    for page in pages:
        for path in PATH_IN_CODE.findall(page.read_text()):
            if any(c in path for c in "<>*{"):
                continue  # a pattern, not a path
            named += 1
            assert (REPO / path).exists(), f"{page.relative_to(REPO)} names {path}, which is gone"
    assert named > 50  # the pages do name files (a pattern that matched nothing fails)


def test_the_path_check_sees_a_path() -> None:
    text = "see `twostep/methods/plan_deal.py`, `bench/x_*.py` and `twostep` (a name)"
    assert PATH_IN_CODE.findall(text) == ["twostep/methods/plan_deal.py"]
