"""Files that readers (or a ``kill -9``) never see half-written: the one atomic writer; and
the one reader of the files a user hands over (PDDL, YAML, plans, prompts' text): checked
to be a regular file of bounded size before a byte is read (a FIFO would block for ever,
``/dev/zero`` never end), text as UTF-8 (a byte-order mark dropped), YAML with its aliases'
expansion bounded; each problem one line naming the file (and line) and what it is.

Limits (module constants, documented in docs/explanations/reliability.md, "Limits and checks"):
:data:`MAX_INPUT_BYTES` for any input file, :data:`MAX_YAML_BYTES` and
:data:`MAX_YAML_NODES` for YAML.
"""

from __future__ import annotations

import errno
import json
import os
import stat
from pathlib import Path
from typing import Any

MAX_INPUT_BYTES = 256 * 2**20
"""The largest input file read (PDDL, plans, text): 256 MiB (a 56 MB PDDL problem reads
in seconds; anything near the limit is no hand-written input)."""
MAX_YAML_BYTES = 8 * 2**20
"""The largest YAML file read (expert subgoals, LLM scripts, kitchens, titles): 8 MiB."""
MAX_YAML_NODES = 1_000_000
"""The most values a YAML file may stand for once its aliases are expanded (an "alias
bomb" of 450 bytes stands for billions)."""


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


def json_text(data: Any, indent: int | None = 2) -> str:
    """``data`` as the JSON text :func:`write_json_atomic` writes (``default=str`` for
    paths and enums)."""
    return json.dumps(data, indent=indent, ensure_ascii=False, default=str) + "\n"


def write_json_atomic(path: Path, data: Any, indent: int | None = 2) -> None:
    """Write ``data`` as JSON atomically (``default=str`` for paths and enums)."""
    write_text_atomic(path, json_text(data, indent))


class NotTextError(ValueError):
    """A file that should hold text does not (binary, or another encoding than UTF-8), or
    is no regular file of bounded size (:class:`NotAFileError`)."""


class NotAFileError(NotTextError):
    """An input file that is not a regular file (a FIFO, a device, a directory, a symlink
    loop), or larger than its limit: the message names the file and what it is."""


def _kind(mode: int) -> str | None:
    """What a file of this ``st_mode`` is, when it is not a regular file."""
    kinds = (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    )
    for test, kind in kinds:
        if test(mode):
            return kind
    return None if stat.S_ISREG(mode) else "not a regular file"


def _size(count: int) -> str:
    return f"{count / 2**20:.0f} MiB" if count >= 2**20 else f"{count} bytes"


def file_problem(path: Path, limit: int = MAX_INPUT_BYTES) -> str | None:
    """Why ``path`` cannot be read as an input file, as one line naming it (None: a regular
    file, or a symlink to one, of at most ``limit`` bytes; also None when nothing is there,
    which its reader reports in its own words). Nothing is opened: a FIFO is not waited on."""
    path = Path(path)
    try:
        info = os.stat(path)
    except OSError as error:
        if error.errno == errno.ELOOP:
            return f"{path}: is a symlink loop (the links never reach a file)"
        if error.errno == errno.ENOENT and os.path.islink(path):
            return f"{path}: is a dangling symlink (to {os.readlink(path)}, which does not exist)"
        return None
    kind = _kind(info.st_mode)
    if kind is not None:
        link = f"a symlink to {os.readlink(path)}, which is " if os.path.islink(path) else ""
        return f"{path}: is {link}{kind}, not a regular file"
    if info.st_size > limit:
        return (
            f"{path}: is {_size(info.st_size)}, larger than the {_size(limit)} an input file may be"
        )
    return None


def exists(path: Path) -> bool:
    """Whether anything is at ``path`` (a symlink loop or a dangling link too)."""
    return os.path.lexists(path)


def read_input_bytes(path: Path, limit: int = MAX_INPUT_BYTES) -> bytes:
    """An input file's bytes, once :func:`file_problem` found it a regular file of at most
    ``limit`` bytes (:class:`NotAFileError` otherwise); ``OSError`` as reading does (no
    such file, no permission, a directory: ``IsADirectoryError``, which callers that look
    for a file in a folder take as "none there"). Opened without blocking and checked
    again once open, so a file swapped for a FIFO in between cannot block."""
    problem = file_problem(path, limit)
    if problem is not None:
        if os.path.isdir(path):
            raise IsADirectoryError(errno.EISDIR, problem.removeprefix(f"{path}: "), str(path))
        raise NotAFileError(problem)
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    with os.fdopen(descriptor, "rb") as handle:
        info = os.fstat(handle.fileno())
        kind = _kind(info.st_mode)
        if kind is not None:
            raise NotAFileError(f"{path}: is {kind}, not a regular file")
        data = handle.read(limit + 1)
    if len(data) > limit:
        raise NotAFileError(f"{path}: is larger than the {_size(limit)} an input file may be")
    return data


def read_text_file(path: Path, limit: int = MAX_INPUT_BYTES) -> str:
    """A text file's content, decoded as UTF-8 (a leading byte-order mark, which some
    editors write, is dropped); raises :class:`NotTextError` naming the file and the first
    byte that is not UTF-8, :class:`NotAFileError` for a file that is no regular file of
    at most ``limit`` bytes, and ``OSError`` as reading does (a directory, no file, no
    permission)."""
    data = read_input_bytes(Path(path), limit)
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
    """A YAML file's data; :class:`NotTextError` (also :class:`NotAFileError`: larger than
    :data:`MAX_YAML_BYTES`, or no regular file) or :class:`FileFormatError` (with the
    file and line) when it cannot be read as YAML, ``OSError`` as reading does."""
    return load_yaml(read_text_file(path, MAX_YAML_BYTES), path)


def load_yaml(text: str, path: Path | str) -> Any:
    """YAML text's data as ``yaml.safe_load`` reads it, refused with a
    :class:`FileFormatError` naming ``path`` when its aliases stand for more than
    :data:`MAX_YAML_NODES` values or for themselves, or it is nested deeper than the
    reader can follow."""
    import yaml

    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        problem = _expansion_problem(node)
        if problem is not None:
            raise FileFormatError(f"{path}: {problem}")
        return loader.construct_document(node)
    except yaml.YAMLError as error:
        raise FileFormatError(yaml_problem(Path(path), error)) from None
    except RecursionError:
        raise FileFormatError(f"{path}: YAML nested deeper than the reader can follow") from None
    finally:
        loader.dispose()


def _expansion_problem(root: Any) -> str | None:
    """How a YAML node graph goes wrong once its aliases are expanded (None: it stands for
    at most :data:`MAX_YAML_NODES` values and never for itself): counted over the graph,
    each node once, so the count costs no more than the file."""
    import yaml

    sizes: dict[int, int] = {}
    open_nodes: set[int] = set()
    stack: list[tuple[Any, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        key = id(node)
        if key in sizes:
            continue
        if isinstance(node, yaml.SequenceNode):
            children = list(node.value)
        elif isinstance(node, yaml.MappingNode):
            children = [part for pair in node.value for part in pair]
        else:
            sizes[key] = 1
            continue
        if children_done:
            open_nodes.discard(key)
            sizes[key] = 1 + sum(sizes[id(child)] for child in children)
            if sizes[key] > MAX_YAML_NODES:
                return (
                    f"its aliases expand to more than {MAX_YAML_NODES:,} values "
                    "(an alias bomb?); write the values out"
                )
            continue
        if key in open_nodes:
            return "a YAML alias refers to a value that contains it (a cycle)"
        open_nodes.add(key)
        stack.append((node, True))
        for child in children:
            if id(child) in open_nodes:
                return "a YAML alias refers to a value that contains it (a cycle)"
            if id(child) not in sizes:
                stack.append((child, False))
    return None
