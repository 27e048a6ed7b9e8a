"""No traceback anywhere a user can reach (issue 20, finding 4): every console script, on a
corpus of bad files (binary, a UTF-8 byte-order mark, 20,000 nested ``(and``, a directory
where a file belongs, text that is not YAML), prints one line naming the file (and the line
where there is one) and exits 2.

Before: ``twostep-score`` on a non-UTF-8 plan file (``UnicodeDecodeError``, exit 1),
``twostep-report --sweep-dir`` with one non-UTF-8 ``result.json``, a goal of 20,000
nested ``(and`` (``RecursionError``, exit 1, no file), ``p01.pddl`` a directory (``unknown
task 1 ... tasks: 1..20``), a BOM (``a ')' too many``), ``twostep-data check`` on a binary
file (a traceback), ``expert.yaml`` or ``kitchen.yaml`` that is not YAML (``ParserError``
naming no file).

The cases the PDDL reader itself decides (a BOM in a PDDL file, a wrong arity, an
undeclared type, an action defined twice) are the lifted reader's (issue 17).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.bad_files import (
    binary,
    deep,
    directory,
    duplicate_action,
    not_yaml,
    undeclared_type,
    with_bom,
    wrong_arity,
)
from tests.conftest import DATA

BIN = Path(sys.executable).parent


def run(script: str, *args: str | Path, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(BIN / script), *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=240
    )


def one_line_naming(done: subprocess.CompletedProcess[str], path: Path, line: int | None) -> str:
    """The run's single error line (exit 2, no traceback) naming ``path`` (and ``line``)."""
    output = done.stdout + done.stderr
    assert "Traceback" not in output, output[-3000:]
    assert done.returncode == 2, output[-3000:]
    lines = [text for text in done.stderr.splitlines() if text.strip()]
    assert len(lines) == 1, lines
    where = f"{path}:{line}:" if line is not None else f"{path}"
    assert where in lines[0], lines[0]
    return lines[0]


@pytest.fixture
def blocks(tmp_path: Path) -> Path:
    """A data root with the benchmark's blocksworld, to spoil."""
    root = tmp_path / "data"
    shutil.copytree(DATA / "blocksworld", root / "blocksworld")
    return root


# ----------------------------------------------------------------- twostep


TWOSTEP_CASES: list[tuple[str, Callable[[Path], None], int | None, str]] = [
    ("p01.pddl", binary, None, "not a text file (byte 0 is not UTF-8)"),
    ("p01.pddl", deep, 13, "expressions nested 20003 levels deep"),
    ("p01.pddl", directory, None, "is a directory, not a regular file"),
    ("domain.pddl", binary, None, "not a text file (byte 0 is not UTF-8)"),
    ("domain.pddl", deep, 14, "expressions nested 20003 levels deep"),
    ("domain.pddl", directory, None, "is a directory, not a regular file"),
    ("expert.yaml", not_yaml, 3, "not valid YAML"),
    ("expert.yaml", binary, None, "not a text file (byte 0 is not UTF-8)"),
    ("p01.nl", binary, None, "not a text file (byte 0 is not UTF-8)"),
]


@pytest.mark.parametrize(
    ("name", "spoil", "line", "expected"),
    TWOSTEP_CASES,
    ids=[f"{name}-{spoil.__name__}" for name, spoil, _, _ in TWOSTEP_CASES],
)
def test_twostep_names_a_bad_data_file(
    blocks: Path,
    tmp_path: Path,
    name: str,
    spoil: Callable[[Path], None],
    line: int | None,
    expected: str,
) -> None:
    path = blocks / "blocksworld" / name
    spoil(path)
    method = ["method=twostep", "decomposer=expert", "agents=2"] if "expert" in name else []
    done = run(
        "twostep", "task=1", *method, f"data.root={blocks}", f"output.root={tmp_path / 'out'}",
        "mlflow.enabled=false", "orchestration.prefect=false", cwd=tmp_path,
    )  # fmt: skip
    assert expected in one_line_naming(done, path, line)


def test_twostep_names_a_kitchen_that_is_not_yaml(tmp_path: Path) -> None:
    root = tmp_path / "data"
    shutil.copytree(DATA / "alfworld", root / "alfworld")
    kitchen = root / "alfworld" / "kitchen.yaml"
    kitchen.write_text(kitchen.read_text() + "\nwalls: [[0, 0\n")
    done = run(
        "twostep", "domain=alfworld", "task=1", "method=sa", f"data.root={root}",
        f"output.root={tmp_path / 'out'}", "mlflow.enabled=false",
        "orchestration.prefect=false", cwd=tmp_path,
    )  # fmt: skip
    assert "not valid YAML" in one_line_naming(done, kitchen, None)


def test_twostep_names_an_llm_script_that_is_not_text(blocks: Path, tmp_path: Path) -> None:
    script = tmp_path / "answers.yaml"
    binary(script)
    done = run(
        "twostep", "task=1", "decomposer=llm", "llm=scripted", f"llm.script={script}",
        f"data.root={blocks}", f"output.root={tmp_path / 'out'}", "mlflow.enabled=false",
        "orchestration.prefect=false", cwd=tmp_path,
    )  # fmt: skip
    assert "not a text file" in one_line_naming(done, script, None)


def test_embodied_execution_needs_a_kitchen(blocks: Path, tmp_path: Path) -> None:
    """Before: `FloorPlanError: no location objects to place`."""
    done = run(
        "twostep", "executor=embodied", "domain=blocksworld", "task=1", "method=sa",
        f"data.root={blocks}", f"output.root={tmp_path / 'out'}", "mlflow.enabled=false",
        "orchestration.prefect=false", cwd=tmp_path,
    )  # fmt: skip
    line = one_line_naming(done, blocks / "blocksworld", None)
    assert "executor=embodied needs a kitchen" in line and "alfworld" in line


# ----------------------------------------------------------------- twostep-score


@pytest.fixture
def score_files(tmp_path: Path) -> dict[str, Path]:
    files = {
        "domain": tmp_path / "domain.pddl",
        "problem": tmp_path / "p01.pddl",
        "plan": tmp_path / "agent0.plan",
    }
    shutil.copy(DATA / "blocksworld" / "domain.pddl", files["domain"])
    shutil.copy(DATA / "blocksworld" / "p01.pddl", files["problem"])
    result = run(
        "twostep", "method=sa", "task=1", f"data.root={DATA}", f"output.root={tmp_path / 'out'}",
        "mlflow.enabled=false", "orchestration.prefect=false", cwd=tmp_path,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (plan,) = tmp_path.glob("out/runs/*/*/plans/agent0.plan")
    shutil.copy(plan, files["plan"])
    return files


def score(files: dict[str, Path], cwd: Path) -> subprocess.CompletedProcess[str]:
    return run(
        "twostep-score", files["domain"], files["problem"], files["plan"], "--no-cache",
        "--agent-predicates", "none", cwd=cwd,
    )  # fmt: skip


SCORE_CASES: list[tuple[str, Callable[[Path], None], int | None, str]] = [
    ("domain", binary, None, "not a text file"),
    ("domain", deep, 14, "expressions nested"),
    ("domain", directory, None, "is a directory, not a regular file"),
    ("problem", binary, None, "not a text file"),
    ("problem", deep, 13, "expressions nested"),
    ("problem", directory, None, "is a directory, not a regular file"),
    ("plan", binary, None, "not a text file (byte 0 is not UTF-8): expected a plan"),
    ("plan", directory, None, "cannot read plan"),
]


@pytest.mark.parametrize(
    ("role", "spoil", "line", "expected"),
    SCORE_CASES,
    ids=[f"{role}-{spoil.__name__}" for role, spoil, _, _ in SCORE_CASES],
)
def test_score_names_a_bad_file(
    score_files: dict[str, Path],
    tmp_path: Path,
    role: str,
    spoil: Callable[[Path], None],
    line: int | None,
    expected: str,
) -> None:
    spoil(score_files[role])
    assert expected in one_line_naming(score(score_files, tmp_path), score_files[role], line)


def test_score_reads_a_plan_with_a_byte_order_mark_as_without(
    score_files: dict[str, Path], tmp_path: Path
) -> None:
    """Before: `unknown action '\\ufeff(unstack'`."""
    plain = score(score_files, tmp_path)
    assert plain.returncode == 0, plain.stderr
    with_bom(score_files["plan"])
    assert score(score_files, tmp_path).stdout == plain.stdout


@pytest.mark.parametrize("role", ["domain", "problem"])
def test_score_reads_pddl_with_a_byte_order_mark_as_without(
    score_files: dict[str, Path], tmp_path: Path, role: str
) -> None:
    """Before: `p01.pddl:1: unexpected '(' after the end of the define: a ')' too many`."""
    plain = score(score_files, tmp_path)
    with_bom(score_files[role])
    spoiled = score(score_files, tmp_path)
    assert (spoiled.returncode, spoiled.stdout) == (plain.returncode, plain.stdout)


# ----------------------------------------------------------------- the other scripts


@pytest.mark.parametrize("spoil", [binary, deep, directory], ids=lambda f: f.__name__)
def test_prompts_names_a_bad_task_file(
    blocks: Path, tmp_path: Path, spoil: Callable[[Path], None]
) -> None:
    path = blocks / "blocksworld" / "p01.pddl"
    spoil(path)
    done = run(
        "twostep-prompts", "--data", blocks, "--domain", "blocksworld", "--task", "1", cwd=tmp_path
    )
    one_line_naming(done, path, 13 if spoil is deep else None)


def test_data_check_names_a_binary_file(blocks: Path, tmp_path: Path) -> None:
    """Before: a UnicodeDecodeError traceback. The check lists every file that differs
    from what the generators write (exit 1): a binary one is named as such."""
    binary(blocks / "blocksworld" / "p01.pddl")
    deep(blocks / "blocksworld" / "p02.pddl")
    done = run("twostep-data", "check", "--data", blocks, "--domain", "blocksworld", cwd=tmp_path)
    assert done.returncode == 1 and "Traceback" not in done.stderr
    lines = done.stderr.splitlines()
    assert f"  {blocks}/blocksworld/p01.pddl: not a text file (byte 0 is not UTF-8)" in lines
    assert max(len(line) for line in lines) < 400  # a 20,000-deep line is cut, not printed


@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("bad-files-sweep")
    done = run(
        "twostep", "-m", "task=1,2", "method=sa", f"data.root={DATA}", f"output.root={out}",
        "mlflow.enabled=false", "orchestration.prefect=false", cwd=out,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    (folder,) = out.glob("multiruns/*/*")
    return folder


@pytest.mark.parametrize("name", ["result.json", ".hydra/config.yaml"])
def test_report_names_a_sweep_file_that_is_not_text(
    sweep_dir: Path, tmp_path: Path, name: str
) -> None:
    copy = tmp_path / "sweep"
    shutil.copytree(sweep_dir, copy)
    (job,) = [p for p in copy.iterdir() if p.name.startswith("0_")]
    binary(job / name)
    done = run("twostep-report", "--sweep-dir", copy, "--out", tmp_path / "report", cwd=tmp_path)
    assert "not a text file" in one_line_naming(done, job / name, None)


def test_report_names_a_runs_csv_that_is_not_text(tmp_path: Path) -> None:
    runs = tmp_path / "runs.csv"
    binary(runs)
    done = run("twostep-report", "--runs-csv", runs, "--out", tmp_path / "report", cwd=tmp_path)
    assert "not a text file" in one_line_naming(done, runs, None)


def test_services_read_a_record_that_is_not_text_as_no_services(tmp_path: Path) -> None:
    binary(tmp_path / "services.json")
    done = run("twostep-services", "status", "--root", tmp_path, cwd=tmp_path)
    assert "Traceback" not in done.stderr and done.returncode == 3  # nothing is up
    assert done.stdout.splitlines() == ["prefect: down", "mlflow: down"]


@pytest.mark.parametrize(
    ("role", "spoil", "line", "words"),
    [
        ("problem", wrong_arity, 8, ("'on'", "2")),
        ("problem", undeclared_type, 4, ("widget", "type")),
        ("domain", duplicate_action, 18, ("pickup", "twice")),
    ],
    ids=["wrong-arity", "undeclared-type", "duplicate-action"],
)
def test_score_names_what_is_wrong_in_pddl_with_file_and_line(
    score_files: dict[str, Path],
    tmp_path: Path,
    role: str,
    spoil: Callable[[Path], None],
    line: int,
    words: tuple[str, ...],
) -> None:
    """Before: unified-planning's text (`UPExpressionDefinitionError(...)` on two lines,
    `Name pickup already defined! ... error_used_name`, no line) and a bare `'widget'`."""
    spoil(score_files[role])
    message = one_line_naming(score(score_files, tmp_path), score_files[role], line)
    assert all(word in message for word in words), message
    assert "Error(" not in message and "error_used_name" not in message


@pytest.mark.parametrize(
    "command",
    [
        ["twostep", "--help"],
        ["twostep", "--version"],
        ["twostep-prompts", "--domain", "blocksworld", "--task", "5", "--agents", "3"],
        ["twostep-report", "--help"],
        ["twostep-services", "status", "--root", "."],
        ["twostep-data", "--help"],
        ["twostep-score", "--help"],
    ],
    ids=lambda command: " ".join(command[:2]),
)
def test_no_traceback_when_the_reader_goes_away(tmp_path: Path, command: list[str]) -> None:
    """`twostep --help | head -1` printed a BrokenPipeError traceback: the reader closes
    the pipe here before the command writes."""
    process = subprocess.Popen(
        [str(BIN / command[0]), *command[1:]],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path,
    )  # fmt: skip
    assert process.stdout is not None and process.stderr is not None
    process.stdout.close()
    stderr = process.stderr.read().decode()
    process.wait(timeout=120)
    assert "Traceback" not in stderr and "Exception ignored" not in stderr, stderr
    assert process.returncode in (0, 3, 141)  # 3: services status with nothing up
