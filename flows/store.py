"""Finished jobs, stored by job key, so that no finished job is ever computed twice.

What goes into the key (the identity config and the content of every input file) and
which results are kept is decided by :mod:`twostep.identity`; this module reads the
config and the files, and owns ``<orchestration.job_store>/<key>/``. A result is written
once, atomically, after the job finished; a job that raised, or whose result says it did
not finish (``llm_error``, ``error``), is not stored: a re-run tries it again.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from twostep import identity
from twostep.benchmark import BenchmarkError, task_path
from twostep.files import write_json_atomic


def job_config(cfg: Any) -> dict[str, Any]:
    """The job's resolved config as plain data, without ``hydra``."""
    from omegaconf import DictConfig, OmegaConf

    if isinstance(cfg, DictConfig):
        data = OmegaConf.to_container(cfg, resolve=True, enum_to_str=True)
    else:
        data = dict(cfg)
    assert isinstance(data, dict)
    data.pop("hydra", None)
    return {str(k): v for k, v in data.items()}


def job_inputs(config: Mapping[str, Any]) -> dict[str, str]:
    """Digest of every file the job reads, by role (an unknown task: no problem file)."""
    try:
        problem: Path | None = task_path(
            str(config["domain"]["name"]), int(config["task"]), Path(str(config["data"]["root"]))
        )
    except (BenchmarkError, KeyError, TypeError, ValueError):
        problem = None  # the job fails on its input; it is not stored either
    return identity.input_digests(identity.job_input_files(config, problem))


def job_key(config: Mapping[str, Any], inputs: Mapping[str, str] | None = None) -> str:
    """The job's key (:func:`twostep.identity.job_key`); ``inputs``: :func:`job_inputs`."""
    return identity.job_key(config, inputs)


class JobStore:
    """``<root>/<job key>/result.json`` (+ ``config.json``) for every finished job.

    ``mlflow.json`` beside them remembers the runs the result was fully logged to, so a
    re-run that reuses the result does not need MLflow at all (delete the file to log
    the job again, e.g. after deleting its run in MLflow).
    """

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self._locks: dict[str, int] = {}  # key -> file descriptor holding its lock

    def path(self, key: str) -> Path:
        return self.root / key / "result.json"

    def load(self, key: str) -> dict[str, Any] | None:
        try:
            data = json.loads(self.path(key).read_text())
        except (OSError, ValueError):
            return None
        return data if isinstance(data, dict) else None

    def load_or_claim(self, key: str) -> dict[str, Any] | None:
        """The stored result, or None after taking the key's lock: the caller computes
        the job, then calls :meth:`release` (:meth:`save` does not release).

        Two processes (two sweeps, or two single runs) asking for the same key: the
        second waits here until the first released its lock, then reads the first one's
        result. The lock is an ``flock``, so a process killed with ``kill -9`` drops it.
        """
        found = self.load(key)
        if found is not None or key in self._locks:
            return found
        import fcntl

        path = self.root / ".locks" / f"{key}.lock"
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            descriptor = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError:
            return None  # no lock possible here: compute (the store write reports why)
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            print(
                f"waiting: another process is computing job {key[:12]} (lock {path})",
                file=sys.stderr,
                flush=True,
            )
            fcntl.flock(descriptor, fcntl.LOCK_EX)
        self._locks[key] = descriptor
        return self.load(key)  # stored by the other process meanwhile?

    def release(self, key: str) -> None:
        descriptor = self._locks.pop(key, None)
        if descriptor is not None:
            os.close(descriptor)  # closing the descriptor drops the flock

    def save(self, key: str, config: Mapping[str, Any], result: Mapping[str, Any]) -> bool:
        """Store a finished job's result; False (nothing written) for one that did not
        finish its work (:func:`twostep.identity.is_storable`), or when the store cannot
        be written: the result is not lost, the job's run directory holds it, and a
        warning says so."""
        if not identity.is_storable(result):
            return False
        try:
            # config first: a stored result always has its config beside it.
            write_json_atomic(self.root / key / "config.json", dict(config))
            write_json_atomic(self.path(key), dict(result))
        except OSError as error:
            print(
                f"warning: job store {self.root} not written ({error.strerror or error}): "
                "the result is kept in the job's run directory (result.json); "
                "this job will be computed again next time",
                file=sys.stderr,
                flush=True,
            )
            return False
        return True

    def logged_to(self, key: str) -> dict[str, str]:
        """``"<tracking uri> <experiment>" -> run id`` for the runs holding this job."""
        try:
            data = json.loads((self.root / key / "mlflow.json").read_text())
        except (OSError, ValueError):
            return {}
        return {str(k): str(v) for k, v in data.items()} if isinstance(data, dict) else {}

    def mark_logged(self, key: str, tracking_uri: str, experiment: str, run_id: str) -> None:
        if not (self.root / key).is_dir():
            return  # the job is not stored (it failed): nothing to skip next time
        logged = self.logged_to(key)
        logged[f"{tracking_uri} {experiment}"] = run_id
        write_json_atomic(self.root / key / "mlflow.json", logged)
