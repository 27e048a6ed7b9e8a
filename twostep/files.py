"""Files that readers (or a ``kill -9``) never see half-written: the one atomic writer; and
the one reader of text and YAML files a user hands over (UTF-8, a byte-order mark dropped;
a file that is not text, or not YAML, named with its line)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any


def write_text_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` via a temporary file in the same folder and ``os.replace``."""
    write_bytes_atomic(path, text.encode("utf-8"))


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file in the same folder and ``os.replace``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_json_atomic(path: Path, data: Any, indent: int | None = 2) -> None:
    """Write ``data`` as JSON atomically (``default=str`` for paths and enums)."""
    text = json.dumps(data, indent=indent, ensure_ascii=False, default=str)
    write_text_atomic(path, text + "\n")


class NotTextError(ValueError):
    """A file that should hold text does not (binary, or another encoding than UTF-8)."""


def read_text_file(path: Path) -> str:
    """A text file's content, decoded as UTF-8 (a leading byte-order mark, which some
    editors write, is dropped); raises :class:`NotTextError` naming the file and the first
    byte that is not UTF-8, and ``OSError`` as reading does (a directory, no file)."""
    data = Path(path).read_bytes()
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise NotTextError(f"{path}: not a text file (byte {error.start} is not UTF-8)") from None


class FileFormatError(ValueError):
    """A text file whose content is not in the format it should be (``file:line: what``)."""


def yaml_problem(path: Path, error: Exception) -> str:
    """A YAML parser's error as one line: ``file:line: not valid YAML (what)``."""
    mark = getattr(error, "problem_mark", None)
    where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
    return f"{where}: not valid YAML ({getattr(error, 'problem', None) or 'unreadable'})"


def read_yaml_file(path: Path) -> Any:
    """A YAML file's data; :class:`NotTextError` or :class:`FileFormatError` (with the
    file and line) when it cannot be read as YAML, ``OSError`` as reading does."""
    import yaml

    text = read_text_file(path)
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise FileFormatError(yaml_problem(path, error)) from None
