"""The package works anywhere (issue 20 finding 8, issue 21 item 5): configs and data come
with the package, so ``twostep`` runs from any directory and from an installed wheel; its
``--help`` and ``--version`` are its own; a bad value fails before anything heavy is
imported; the job log holds the run's summary; schedule columns fit their actions."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
import yaml

from flows.console import format_schedule

REPO = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
TWOSTEP = BIN / "twostep"
HEAVY = ("prefect", "mlflow", "litellm", "unified_planning")
QUIET = ["mlflow.enabled=false", "orchestration.prefect=false", "planner.time_limit_s=20"]


def run(args: list[str], cwd: Path, timeout: float = 240) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, capture_output=True, text=True, cwd=cwd, timeout=timeout)


# ----------------------------------------------------------------- what the wheel holds


def test_every_package_of_the_source_tree_is_in_the_wheel() -> None:
    """pyproject.toml lists the packages by hand (two are mapped from conf/ and data/):
    a package added to the tree and not to the list would be missing from the wheel."""
    setuptools = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    in_tree = {
        ".".join(init.parent.relative_to(REPO).parts)
        for top in ("twostep", "flows", "hydra_plugins")
        for init in (REPO / top).rglob("__init__.py")
    }
    mapped = {"flows.conf": "conf", "twostep.data": "data"}
    assert setuptools["package-dir"] == mapped
    assert all((REPO / folder / "__init__.py").is_file() for folder in mapped.values())
    assert set(setuptools["packages"]) == in_tree | set(mapped)


# ----------------------------------------------------------------- from any directory


def test_runs_from_a_directory_without_data_or_configs(tmp_path: Path) -> None:
    """Before: `error: data root <cwd>/data does not exist` from any other directory."""
    from importlib.resources import files

    done = run([str(TWOSTEP), "domain=grippers", "task=1", "method=sa", *QUIET], cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    (result,) = tmp_path.glob("outputs/runs/*/*/result.json")  # outputs: where it ran
    assert json.loads(result.read_text())["success"] is True
    config = yaml.safe_load((result.parent / ".hydra" / "config.yaml").read_text())
    assert Path(config["data"]["root"]) == Path(str(files("twostep.data")))  # the package's


def test_config_dir_adds_the_users_own_configs(tmp_path: Path) -> None:
    mine = tmp_path / "myconf" / "domain"
    mine.mkdir(parents=True)
    (mine / "my-grippers.yaml").write_text("name: grippers\nagent_predicates: [at-robby]\n")
    done = run(
        [str(TWOSTEP), "--config-dir", str(tmp_path / "myconf"), "domain=my-grippers",
         "task=1", "method=sa", *QUIET],
        cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    (result,) = tmp_path.glob("outputs/runs/*/*/.hydra/config.yaml")
    assert yaml.safe_load(result.read_text())["domain"] == {
        "name": "grippers",
        "agent_predicates": ["at-robby"],
    }


def test_the_job_log_holds_the_runs_summary(tmp_path: Path) -> None:
    """Before: cli.log was empty."""
    done = run(
        [str(TWOSTEP), "domain=blocksworld", "task=6", "method=twostep", "agents=2", *QUIET],
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    (log,) = tmp_path.glob("outputs/runs/*/*/cli.log")
    printed = done.stdout.splitlines()
    logged = log.read_text().splitlines()
    summary, table = printed[0], [line for line in printed if line.startswith("   1  ")]
    assert summary.startswith("blocksworld-p06-twostep-plan-deal-n2-s0 | success")
    assert summary in logged
    assert table and table[0] in logged  # the schedule's first step


# ----------------------------------------------------------------- help and version


def test_help_is_the_tools_own_text(tmp_path: Path) -> None:
    """Before: Hydra's generic text headed `cli is powered by Hydra`."""
    done = run([str(TWOSTEP), "--help"], cwd=tmp_path)
    assert done.returncode == 0
    text = done.stdout
    assert "powered by Hydra" not in text and text.startswith("twostep: ")
    for expected in ("Usage: twostep", "method=twostep", "agents=2", "data.root=", "Examples:"):
        assert expected in text
    groups = [line for line in text.splitlines() if line.startswith("domain: ")]
    assert groups and "blocksworld, grippers" in groups[0]  # Hydra fills in the groups
    assert "output.root" in text and "runs/<date>/<time>" in text  # where outputs go


def test_version_names_twostep_and_what_it_runs_on(tmp_path: Path) -> None:
    """Before: `Hydra 1.3.8`. The Fast Downward release is checked against its own driver
    (`fast-downward.py --version`); nothing heavy is imported for it."""
    done = run([sys.executable, "-X", "importtime", "-m", "flows.cli", "--version"], cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    # A checkout names its commit; a copy without git metadata (the container image) says so.
    where = "(git " if (REPO / ".git").exists() else "(installed package, no git checkout)"
    assert lines[0].startswith(f"twostep {metadata.version('twostep')} {where}")
    driver = Path(str(metadata.distribution("up-fast-downward").locate_file("")))
    driver = driver / "up_fast_downward" / "downward" / "fast-downward.py"
    own = run([sys.executable, str(driver), "--version"], cwd=tmp_path).stdout.splitlines()[0]
    assert any(line.startswith(own + " (up-fast-downward") for line in lines), (own, lines)
    for label, name in (("Prefect", "prefect"), ("MLflow", "mlflow"), ("litellm", "litellm")):
        assert f"{label} {metadata.version(name)}" in lines
    imported = {line.split("|")[-1].strip() for line in done.stderr.splitlines()}
    assert not {m for m in imported if m.split(".")[0] in HEAVY}


# ----------------------------------------------------------------- fail fast


@pytest.mark.parametrize(
    ("override", "expected"),
    [
        ("data.root={tmp}/nowhere", "data root {tmp}/nowhere does not exist"),
        ("task=99", "unknown task 99 of domain 'grippers'"),
        ("domain.name=grippperz", "unknown domain 'grippperz'"),
        ("domain=grippperz", "unknown domain 'grippperz' (choices: "),  # one line (issue 37)
        ("planner.time_limit_s=1e9", "planner.time_limit_s=1000000000.0 is too large"),
        ("agents=0", "agents=0 must be at least 1"),
        ("llm.api_key_env=sk-proj-Zx81", "llm.api_key_env looks like a key"),
    ],
)
def test_a_bad_value_fails_before_anything_heavy_is_imported(
    tmp_path: Path, override: str, expected: str
) -> None:
    """Before: the one-line error came after 5-6 s of start-up. Asserted on what the
    process had imported when it stopped, not on time."""
    code = (  # report what was imported however the process ends (sys.exit or os._exit)
        "import atexit, os, sys\n"
        f"heavy = {HEAVY!r}\n"
        "def report(): print('IMPORTED', sorted(m for m in heavy if m in sys.modules), "
        "file=sys.stderr, flush=True)\n"
        "atexit.register(report)\n"
        "real_exit = os._exit\n"
        "os._exit = lambda code: (report(), real_exit(code))\n"
        "from flows.cli import main\n"
        "main()\n"
    )
    argv = ["twostep", "domain=grippers", "task=1", override.format(tmp=tmp_path)]
    done = run([sys.executable, "-c", f"import sys; sys.argv = {argv!r}\n{code}"], cwd=tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    assert expected.format(tmp=tmp_path) in done.stderr and "Traceback" not in done.stderr
    assert "IMPORTED []" in done.stderr.splitlines()


# ----------------------------------------------------------------- schedule columns


def test_schedule_columns_are_as_wide_as_their_actions() -> None:
    """Before: 34 characters per column, so longer actions ran into the next one."""
    long = "(pick-up-the-very-long-object-name ball12 room-with-a-long-name left-gripper)"
    result = {
        "plans": {"agent0": [long, "(b)"], "agent1": ["(c)"]},
        "schedule": [[["agent0", long], ["agent1", "(c)"]], [["agent0", "(b)"]]],
    }
    lines = format_schedule(result).splitlines()
    assert lines[0] == "step  agent0" + " " * (len(long) - len("agent0") + 2) + "agent1"
    assert lines[1] == "-" * (4 + 2 + len(long) + 2 + len("agent1"))
    assert lines[2] == f"   1  {long}  (c)"
    assert lines[3] == "   2  (b)" + " " * (len(long) - 3) + "  ."  # an idle agent: a dot


# ----------------------------------------------------------------- the wheel


@pytest.mark.slow
def test_installed_wheel_runs_the_demo_from_a_fresh_directory(tmp_path: Path) -> None:
    """`uv build`; a new virtual environment with the locked dependencies (offline, from
    uv's cache) and the wheel (no source tree); the demo, --version and --help from an
    empty directory."""
    # uv as `make` finds it: $UV, the one on PATH, else the Makefile's private copy
    uv = os.environ.get("UV") or shutil.which("uv") or str(REPO / ".uv-bootstrap" / "bin" / "uv")
    dist, venv, work = tmp_path / "dist", tmp_path / "venv", tmp_path / "work"
    work.mkdir()
    # Built from a copy of the sources: a build writes twostep.egg-info beside the packages,
    # which in the checkout would shadow the installed metadata (version, entry points).
    source = tmp_path / "source"
    shutil.copytree(
        REPO, source,
        ignore=shutil.ignore_patterns(".git", ".venv*", ".uv-bootstrap", "outputs", "build",
                                      "dist", "*.egg-info", ".mypy_cache", ".ruff_cache",
                                      ".pytest_cache", "multirun"),
    )  # fmt: skip
    pretend = {**os.environ, "SETUPTOOLS_SCM_PRETEND_VERSION": metadata.version("twostep")}
    built = subprocess.run(
        [uv, "build", "--wheel", "--out-dir", str(dist), str(source)],
        capture_output=True, text=True, cwd=source, env=pretend, timeout=600,
    )  # fmt: skip
    assert built.returncode == 0, built.stderr[-2000:]
    (wheel,) = dist.glob("twostep-*.whl")
    environment = {**os.environ, "UV_PROJECT_ENVIRONMENT": str(venv)}
    locked = subprocess.run(
        [uv, "sync", "--frozen", "--offline", "--no-dev", "--no-install-project",
         "--python", sys.executable],
        capture_output=True, text=True, cwd=REPO, env=environment, timeout=1200,
    )  # fmt: skip
    assert locked.returncode == 0, locked.stderr[-2000:]
    python = venv / "bin" / "python"
    installed = run(
        [uv, "pip", "install", "--offline", "--no-deps", "--python", str(python), str(wheel)],
        tmp_path,
    )
    assert installed.returncode == 0, installed.stderr[-2000:]
    twostep = venv / "bin" / "twostep"
    demo = run([str(twostep), "domain=grippers", "task=1", "method=sa"], work, 600)
    assert demo.returncode == 0, demo.stdout + demo.stderr
    assert demo.stdout.startswith("grippers-p01-sa-n1-s0 | success | exec_length=")
    assert list(work.glob("outputs/runs/*/*/result.json"))
    assert (work / "outputs" / "mlflow.db").is_file()  # logged to MLflow by default
    version = run([str(twostep), "--version"], work).stdout.splitlines()[0]
    assert version.endswith("(installed package, no git checkout)")
    assert "Usage: twostep" in run([str(twostep), "--help"], work).stdout
    where = run([str(python), "-c", "import flows, twostep.data; print(flows.__file__)"], work)
    assert str(venv) in where.stdout  # the installed package, not a source tree
