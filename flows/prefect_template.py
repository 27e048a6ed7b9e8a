"""The environment's empty Prefect database: made once by Prefect's own server, copied into
every new Prefect home.

A Prefect server on a new database first runs its whole migration history and registers
its block types: 8-30 s on a small machine, which the first sweep of a new output root
waited for. ``make setup`` has a Prefect server make one empty database per environment
(:func:`make_template`, ``python -m flows.prefect_template``: a server started on a
temporary home until it answers, then stopped), kept beside the Prefect that made it; a
new home is then a copy (:func:`seed_home`, milliseconds) and its server starts as on a
warm database. Without a template a server migrates its new database as before.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import uuid
from contextlib import suppress
from importlib import metadata
from pathlib import Path

DATABASE = "prefect.db"  # Prefect's default database in its home (PREFECT_HOME)


def template_path() -> Path:
    """The empty database of the installed Prefect, inside this environment (named after
    Prefect's version: another Prefect makes its own)."""
    version = metadata.version("prefect")
    return Path(sys.prefix) / "share" / "twostep" / f"prefect-{version}.db"


def seed_home(home: Path) -> bool:
    """Copy the template into ``home`` if it has no database yet (False: nothing copied,
    no template or a database already there). Two processes seeding at once both
    succeed: the first copy is linked into place, the other is dropped."""
    template = template_path()
    target = Path(home) / DATABASE
    if not template.is_file() or target.exists():
        return False
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_name(f".{target.name}.{uuid.uuid4().hex}")
    try:
        shutil.copyfile(template, partial)
        try:
            os.link(partial, target)
        except FileExistsError:  # never over a database another process put there
            return False
    finally:
        partial.unlink(missing_ok=True)
    return True


def make_template(target: Path | None = None, timeout_s: float = 600.0) -> Path:
    """Have a Prefect server create, migrate and fill (block types) an empty database,
    and keep it as the template."""
    from flows.servers import ServerSettings, spawn_server, stop_server, wait_until_healthy

    target = target or template_path()
    if target.is_file():
        return target
    with tempfile.TemporaryDirectory() as folder:
        home = Path(folder) / "prefect"
        info = spawn_server(
            ServerSettings(str(home), startup_timeout_s=timeout_s), os.getpid(), ui=True
        )
        try:
            wait_until_healthy(info)
        finally:
            stop_server(info)
        database = home / DATABASE
        with suppress(OSError):  # fold the write-ahead log into the file
            import sqlite3

            connection = sqlite3.connect(database)
            connection.execute("PRAGMA wal_checkpoint(TRUNCATE)")
            connection.close()
        target.parent.mkdir(parents=True, exist_ok=True)
        partial = target.with_name(f".{target.name}.{uuid.uuid4().hex}")
        shutil.copyfile(database, partial)
        os.replace(partial, target)
    return target


if __name__ == "__main__":  # `make setup`: the template database for this environment
    from flows.environment import quiet_defaults

    quiet_defaults()
    try:
        print(f"Prefect database template: {make_template()}")
    except Exception as error:  # a server then migrates its first database itself
        print(f"no Prefect database template ({type(error).__name__}: {error})", file=sys.stderr)
