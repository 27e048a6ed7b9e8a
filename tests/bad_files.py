"""Ways to spoil a file a user hands over, for tests/test_bad_files.py and
bench/bench_faults.py: each turns a good file (in place) into a bad one of its kind."""

from __future__ import annotations

from pathlib import Path

BOM = b"\xef\xbb\xbf"


def binary(path: Path) -> None:
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe binary")


def with_bom(path: Path) -> None:
    path.write_bytes(BOM + path.read_bytes())


def deep(path: Path) -> None:
    """20,000 nested (and ...) in the file's first goal or precondition."""
    text = path.read_text()
    anchor = ":goal" if ":goal" in text else ":precondition"
    head, tail = text.split(anchor, 1)
    path.write_text(f"{head}{anchor} {'(and ' * 20_000}(arm-empty){')' * 20_000}\n{tail}")


def directory(path: Path) -> None:
    path.unlink()
    path.mkdir()


def not_yaml(path: Path) -> None:
    path.write_text("p01:\n  2: [(on b1 b2)\n  3: {broken\n")


def wrong_arity(path: Path) -> None:
    """blocksworld p01's `(on b1 b2)` with one argument."""
    path.write_text(path.read_text().replace("    (on b1 b2)\n", "    (on b1)\n", 1))


def undeclared_type(path: Path) -> None:
    """An object of a type the domain does not declare, on the line after ``(:objects``."""
    text = path.read_text()
    if "(:objects\n" not in text:
        raise ValueError(f"{path}: no '(:objects' line to add an object after")
    path.write_text(text.replace("(:objects\n", "(:objects\n    w1 - widget\n", 1))


def duplicate_action(path: Path) -> None:
    """The domain's first action written twice."""
    text = path.read_text()
    first = text.index("(:action")
    second = text.index("(:action", first + 1)
    path.write_text(text[:second] + text[first:second] + text[second:])
