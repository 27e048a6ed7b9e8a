"""The environment's empty MLflow store: made once by MLflow itself, copied for every new
store.

Creating a SQLite store through MLflow runs its whole migration history (4-5 s). ``make
setup`` has MLflow create and migrate one empty store per environment
(:func:`make_template`, ``python -m flows.tracking.template``; it lives in the virtual
environment, beside the MLflow that made it); a new store is then a copy
(:func:`seed_store`, milliseconds). Without a template the first run creates the store
through MLflow, as before.
"""

from __future__ import annotations

import logging
import os
import shutil
import sqlite3
import sys
import tempfile
import time
import uuid
from contextlib import closing, suppress
from importlib import metadata
from pathlib import Path


def millis() -> int:
    """Now, as MLflow stores times (milliseconds since the epoch)."""
    return int(time.time() * 1000)


def quiet_mlflow_logging() -> None:
    """MLflow announces schema migrations at INFO on the job's console (it sets its
    logger's level when imported: call this after importing it)."""
    for name in ("mlflow", "alembic"):
        logging.getLogger(name).setLevel(logging.WARNING)


def template_path() -> Path:
    """The empty store of the installed MLflow, inside this environment (named after
    MLflow's version: another MLflow makes its own)."""
    version = metadata.version("mlflow")
    return Path(sys.prefix) / "share" / "twostep" / f"mlflow-{version}.db"


def make_template(target: Path | None = None) -> Path:
    """Have MLflow create and migrate an empty store, and keep it as the template."""
    target = target or template_path()
    if target.is_file():
        return target
    from mlflow.tracking import MlflowClient

    quiet_mlflow_logging()
    with tempfile.TemporaryDirectory() as folder:
        db = Path(folder) / "mlflow.db"
        MlflowClient(tracking_uri=f"sqlite:///{db}").search_experiments()  # MLflow makes it
        target.parent.mkdir(parents=True, exist_ok=True)
        partial = target.with_name(f".{target.name}.{uuid.uuid4().hex}")
        shutil.copyfile(db, partial)
        os.replace(partial, target)
    return target


def seed_store(path: Path) -> bool:
    """Copy the template to ``path`` if no store is there yet (False: no template).

    The Default experiment (id 0) gets the artifact folder MLflow gives it, ``mlruns/0``
    under the working directory, and the current time. Two processes seeding at once
    both succeed: the first copy is linked into place, the other is dropped."""
    template = template_path()
    if not template.is_file():
        return False
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.{uuid.uuid4().hex}")
    try:
        shutil.copyfile(template, partial)
        now = millis()
        with closing(sqlite3.connect(partial)) as db:
            db.execute(
                "UPDATE experiments SET artifact_location = ?, creation_time = ?,"
                " last_update_time = ? WHERE experiment_id = 0",
                (str(Path("mlruns").resolve() / "0"), now, now),
            )
            db.commit()
        with suppress(FileExistsError):  # never over a store another process put there
            os.link(partial, path)
    finally:
        partial.unlink(missing_ok=True)
    return True


if __name__ == "__main__":  # `make setup`: the template store for this environment
    from flows.environment import quiet_defaults

    quiet_defaults()  # offline: no telemetry from MLflow
    try:
        print(f"MLflow store template: {make_template()}")
    except Exception as error:  # a run then creates its first store through MLflow
        print(f"no MLflow store template ({type(error).__name__}: {error})", file=sys.stderr)
