"""Where a job writes on this disk: the SQLite file or folder behind an MLflow URI, and
whether a folder can take new files."""

from __future__ import annotations

import time
from pathlib import Path
from urllib.parse import urlparse

SQLITE = "sqlite:///"


def sqlite_path(uri: str) -> Path | None:
    """The database file of a ``sqlite:///`` URI (None: another scheme, or in memory)."""
    if not uri.startswith(SQLITE):
        return None
    path = uri[len(SQLITE) :]
    return None if path in ("", ":memory:") else Path(path)


def local_folder(uri: str | None) -> Path | None:
    """The local folder of an MLflow store or artifact URI (None: not on this disk)."""
    if not uri:
        return None
    if uri.startswith(SQLITE):
        database = sqlite_path(uri)
        return None if database is None else database.parent
    parsed = urlparse(uri)
    if parsed.scheme in ("", "file"):
        return Path(parsed.path or uri)
    return None


def write_problem(folder: Path) -> str | None:
    """Why ``folder`` cannot hold new files (None: it can). Creates the folder (as the
    job would) and writes and deletes a probe file: permission bits alone do not tell
    (root ignores them; a read-only mount does not)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".twostep-probe-{time.time_ns()}"
        probe.write_text("")
        probe.unlink()
    except OSError as error:
        return error.strerror or type(error).__name__
    return None
