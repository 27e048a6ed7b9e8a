"""Inputs that cannot hang or run away (issue 39, findings 2, 10 and 13): every input file
is checked to be a regular file of bounded size before anything reads it, the job key
included; YAML goes through one safe loader; a kitchen's sizes are bounded.

Before: a FIFO as ``domain.pddl``, ``expert.yaml`` or the LLM script hung the job for
ever with no output (the job key read it first); ``domain.pddl`` linked to ``/dev/zero``
was read until memory ran out (a ``MemoryError`` traceback); a FIFO ``p01.pddl`` was "not a
file (a directory?)", a symlink loop "unknown domain"/"unknown task"; a 452-byte alias-bomb
LLM script ran for minutes to 3 GB; a 100,000 x 100,000 kitchen reached 3.8 GB; a binary
``kitchen.yaml`` gave a bare ``UnicodeDecodeError``; ``[6.5, "x"]`` a bare ``ValueError``; a
negative furniture size was accepted; ``executor.layout=FloorPlan99999`` exited 1.

Each case runs the ``twostep`` command as a user does (with a timeout, so a hang fails
the test): one line naming the file and what it is, exit 2, no traceback, nothing stored.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

from flows.identity import file_digest
from tests.conftest import DATA
from twostep.embodied import FloorPlanError, floor_plan_from_dict
from twostep.util.files import (
    MAX_YAML_NODES,
    FileFormatError,
    NotAFileError,
    file_problem,
    load_yaml,
    read_input_bytes,
    read_yaml_file,
)

BIN = Path(sys.executable).parent
# 9 levels of 9 aliases: 9**9 (387 million) strings once expanded, in under 500 bytes.
ALIAS_BOMB = "a: &a ['lol','lol','lol','lol','lol','lol','lol','lol','lol']\n" + "".join(
    f"{c}: &{c} [{','.join(['*' + p] * 9)}]\n" for p, c in zip("abcdefgh", "bcdefghi", strict=True)
)


def twostep(*args: str | Path, cwd: Path, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(BIN / "twostep"), *map(str, args), "mlflow.enabled=false",
         "orchestration.prefect=false"],
        capture_output=True, text=True, cwd=cwd, timeout=timeout,
    )  # fmt: skip


def refused(done: subprocess.CompletedProcess[str], path: Path | str, words: str) -> str:
    """The run's one ``error:`` line: exit 2, no traceback, naming ``path`` and ``words``."""
    output = done.stdout + done.stderr
    assert "Traceback" not in output, output[-3000:]
    assert done.returncode == 2, output[-3000:]
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, lines
    assert str(path) in lines[0] and words in lines[0], lines[0]
    return lines[0]


def nothing_stored(out: Path) -> None:
    assert not list((out / "jobs").glob("*/result.json"))


@pytest.fixture
def blocks(tmp_path: Path) -> Path:
    root = tmp_path / "data"
    shutil.copytree(DATA / "blocksworld", root / "blocksworld")
    return root


# ----------------------------------------------------------------- the checked reader


def fifo(path: Path) -> None:
    path.unlink(missing_ok=True)
    os.mkfifo(path)


def zero(path: Path) -> None:
    path.unlink(missing_ok=True)
    path.symlink_to("/dev/zero")


def loop(path: Path) -> None:
    path.unlink(missing_ok=True)
    path.symlink_to(path.name)


def dangling(path: Path) -> None:
    path.unlink(missing_ok=True)
    path.symlink_to("nowhere.pddl")


KINDS: list[tuple[Callable[[Path], None], str]] = [
    (fifo, "is a FIFO (named pipe), not a regular file"),
    (zero, "is a symlink to /dev/zero, which is a character device, not a regular file"),
    (loop, "is a symlink loop"),
    (dangling, "is a dangling symlink (to nowhere.pddl"),
]


@pytest.mark.parametrize(("spoil", "words"), KINDS, ids=[s.__name__ for s, _ in KINDS])
def test_the_checked_reader_names_what_a_file_is_without_opening_it(
    tmp_path: Path, spoil: Callable[[Path], None], words: str
) -> None:
    path = tmp_path / "domain.pddl"
    path.write_text("(define (domain d))")
    spoil(path)
    problem = str(file_problem(path))
    assert problem.startswith(f"{path}: ") and words in problem, problem
    done: list[object] = []
    # a FIFO with no writer blocks an ordinary open() for ever: this returns at once
    reader = threading.Thread(target=lambda: done.append(file_digest(path)), daemon=True)
    reader.start()
    reader.join(timeout=10)
    assert done == ["missing"]  # the job key does not wait; the check before work names it
    if spoil is not dangling:
        with pytest.raises(NotAFileError, match=r"not a regular file|symlink loop"):
            read_input_bytes(path)


def test_the_checked_reader_bounds_the_size(tmp_path: Path) -> None:
    path = tmp_path / "big.pddl"
    with path.open("wb") as handle:  # sparse: 300 MiB that take no disk
        handle.truncate(300 * 2**20)
    assert "is 300 MiB, larger than the 256 MiB an input file may be" in str(file_problem(path))
    with pytest.raises(NotAFileError, match="larger than"):
        read_input_bytes(path)
    assert file_digest(path) == "missing"


def test_a_regular_file_and_a_link_to_one_are_read_as_before(tmp_path: Path) -> None:
    path = tmp_path / "p.pddl"
    path.write_bytes(b"(define (problem p))\n")
    link = tmp_path / "link.pddl"
    link.symlink_to(path)
    assert file_problem(path) is None and file_problem(link) is None
    assert read_input_bytes(link) == path.read_bytes()
    import hashlib

    assert file_digest(link) == hashlib.sha256(path.read_bytes()).hexdigest()


# ----------------------------------------------------------------- through the command


TWOSTEP_INPUTS = [
    ("domain.pddl", fifo, "is a FIFO (named pipe)"),
    ("domain.pddl", zero, "/dev/zero, which is a character device"),
    ("domain.pddl", loop, "is a symlink loop"),
    ("p01.pddl", fifo, "is a FIFO (named pipe)"),
    ("p01.pddl", zero, "/dev/zero, which is a character device"),
    ("p01.pddl", loop, "is a symlink loop"),
    ("expert.yaml", fifo, "is a FIFO (named pipe)"),
    ("p01.nl", fifo, "is a FIFO (named pipe)"),
]


@pytest.mark.parametrize(
    ("name", "spoil", "words"),
    TWOSTEP_INPUTS,
    ids=[f"{n}-{s.__name__}" for n, s, _ in TWOSTEP_INPUTS],
)
def test_twostep_refuses_an_input_that_is_no_regular_file(
    blocks: Path, tmp_path: Path, name: str, spoil: Callable[[Path], None], words: str
) -> None:
    path = blocks / "blocksworld" / name
    spoil(path)
    if name == "p01.nl":
        method = ["method=twostep", "decomposer=llm", "llm=scripted",
                  f"llm.script={tmp_path / 'answers.yaml'}"]  # fmt: skip
        (tmp_path / "answers.yaml").write_text("answers: [none]\n")
    elif name == "expert.yaml":
        method = ["method=twostep", "decomposer=expert"]
    else:
        method = ["method=sa"]
    out = tmp_path / "out"
    done = twostep("task=1", *method, f"data.root={blocks}", f"output.root={out}", cwd=tmp_path)
    refused(done, path, words)
    nothing_stored(out)


def test_twostep_refuses_an_llm_script_that_is_a_fifo(blocks: Path, tmp_path: Path) -> None:
    script = tmp_path / "answers.yaml"
    fifo(script)
    done = twostep(
        "task=1", "decomposer=llm", "llm=scripted", f"llm.script={script}",
        f"data.root={blocks}", f"output.root={tmp_path / 'out'}", cwd=tmp_path,
    )  # fmt: skip
    refused(done, script, "is a FIFO (named pipe)")


# ----------------------------------------------------------------- YAML


def test_an_alias_bomb_is_refused_at_once(tmp_path: Path) -> None:
    assert len(ALIAS_BOMB) < 500
    path = tmp_path / "bomb.yaml"
    path.write_text(ALIAS_BOMB)
    with pytest.raises(FileFormatError, match=rf"{path}: its aliases expand to more than"):
        read_yaml_file(path)


def test_aliases_that_stand_for_few_values_are_read_as_pyyaml_reads_them() -> None:
    import yaml

    text = "base: &b {x: 1, y: [1, 2]}\nmore: *b\nlist: [*b, *b]\n"
    assert load_yaml(text, "t.yaml") == yaml.safe_load(text)
    assert load_yaml("", "t.yaml") is None
    # counted by hand: the mapping, 2 keys, and the list of n numbers twice (once through
    # its alias): 1 + 2 + 2 (n + 1) values; at the bound it is read, one more is refused
    n = (MAX_YAML_NODES - 5) // 2

    def doc(count: int) -> str:
        return "a: &a [" + ",".join(["1"] * count) + "]\nb: *a\n"

    assert len(load_yaml(doc(n), "t.yaml")["b"]) == n
    with pytest.raises(FileFormatError, match="aliases expand"):
        load_yaml(doc(n + 1), "t.yaml")


def test_a_yaml_cycle_and_deep_nesting_are_refused(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="refers to a value that contains it"):
        load_yaml("a: &a [1, *a]\n", "cycle.yaml")
    with pytest.raises(FileFormatError, match=r"deep\.yaml"):
        load_yaml("[" * 100_000 + "]" * 100_000, "deep.yaml")


def test_twostep_refuses_an_alias_bomb_llm_script(blocks: Path, tmp_path: Path) -> None:
    script = tmp_path / "answers.yaml"
    script.write_text(ALIAS_BOMB + "answers: [*i]\n")
    done = twostep(
        "task=1", "decomposer=llm", "llm=scripted", f"llm.script={script}",
        f"data.root={blocks}", f"output.root={tmp_path / 'out'}", cwd=tmp_path, timeout=60,
    )  # fmt: skip
    refused(done, script, "aliases expand to more than")


# ----------------------------------------------------------------- kitchens


@pytest.fixture
def kitchen_root(tmp_path: Path) -> Path:
    root = tmp_path / "data"
    shutil.copytree(DATA / "alfworld", root / "alfworld")
    return root


def embodied(root: Path, tmp_path: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return twostep(
        "domain=alfworld", "task=4", "method=sa", "executor.render=false",
        f"data.root={root}", f"output.root={tmp_path / 'out'}", *extra, cwd=tmp_path,
    )  # fmt: skip


def edit_kitchen(root: Path, old: str, new: str) -> Path:
    kitchen = root / "alfworld" / "kitchen.yaml"
    text = kitchen.read_text()
    assert old in text
    kitchen.write_text(text.replace(old, new, 1))
    return kitchen


KITCHENS = [
    ("width: 13\nheight: 11", "width: 100000\nheight: 100000", "width and height must be 1 to"),
    ("width: 13\nheight: 11", "width: 13\nheight: -11", "width and height must be 1 to"),
    ("diningtable1: [5, 5, 3, 2]", "diningtable1: [5, 5, -3, -2]", "size -3 x -2 is out of range"),
    ("loc-door: [6, 9]", 'loc-door: [6.5, "x"]', "location loc-door: expected [x, y] of integers"),
]


@pytest.mark.parametrize(("old", "new", "words"), KITCHENS, ids=["huge", "negative-height",
                                                                 "negative-size", "not-a-number"])  # fmt: skip
def test_out_of_range_kitchens_are_refused(
    kitchen_root: Path, tmp_path: Path, old: str, new: str, words: str
) -> None:
    kitchen = edit_kitchen(kitchen_root, old, new)
    line = refused(embodied(kitchen_root, tmp_path, "executor=embodied"), kitchen, words)
    assert line.count(str(kitchen)) == 1  # once (the path was printed twice)


def test_a_binary_or_fifo_kitchen_is_named(kitchen_root: Path, tmp_path: Path) -> None:
    kitchen = kitchen_root / "alfworld" / "kitchen.yaml"
    kitchen.write_bytes(os.urandom(2000).replace(b"\n", b"\x83"))
    refused(embodied(kitchen_root, tmp_path, "executor=embodied"), kitchen, "not a text file")
    fifo(kitchen)
    refused(embodied(kitchen_root, tmp_path, "executor=embodied"), kitchen, "is a FIFO")


def test_an_unknown_scene_is_an_input_error(kitchen_root: Path, tmp_path: Path) -> None:
    pytest.importorskip("alfworld")
    done = embodied(kitchen_root, tmp_path, "executor=embodied", "executor.layout=FloorPlan99999")
    refused(done, "executor.layout=FloorPlan99999", "no layout FloorPlan99999")


def test_kitchen_bounds_in_the_library() -> None:
    plan = {"width": 4, "height": 3, "locations": {"a": [1, 1]}}
    assert floor_plan_from_dict(plan).free((1, 1))
    for bad, words in [
        ({**plan, "width": 0}, "must be 1 to"),
        ({**plan, "width": 1000, "height": 1000}, "more than the 250,000 cells"),
        ({**plan, "walls": [[0, 0, 5, 1]]}, "wall 1: size 5 x 1 is out of range"),
        ({**plan, "furniture": {"t": [0, 0, 0, 1]}}, "furniture t: size 0 x 1"),
        ({**plan, "walls": [[0, 0, 4, 3]] * 100_000}, "cover 1,200,000 cells"),
        ({**plan, "locations": {"a": [True, 1]}}, "expected [x, y] of integers"),
    ]:
        with pytest.raises(FloorPlanError, match=__import__("re").escape(words)):
            floor_plan_from_dict(bad)


def test_data_check_and_generate_never_open_a_fifo(blocks: Path, tmp_path: Path) -> None:
    """``twostep-data check`` lists a FIFO among the files that differ; ``generate``
    replaces it (opening it, to read or to write, would block)."""
    path = blocks / "blocksworld" / "p01.pddl"
    fifo(path)
    command = [str(BIN / "twostep-data"), "check", "--data", str(blocks), "--domain", "blocksworld"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 1 and f"{path}: is a FIFO (named pipe)" in done.stderr, done.stderr
    generate = [
        str(BIN / "twostep-data"),
        "generate",
        "--out",
        str(blocks),
        "--domain",
        "blocksworld",
    ]
    done = subprocess.run(generate, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and path.is_file(), done.stderr
    assert path.read_text() == (DATA / "blocksworld" / "p01.pddl").read_text()
