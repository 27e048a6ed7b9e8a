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
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from twostep import identity
from twostep.benchmark import BenchmarkError, task_path
from twostep.files import write_json_atomic
from twostep.redaction import redact_config


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


def stored(cfg: Any) -> bool:
    """Whether the job of ``cfg`` (a job's config, without ``hydra``) has a whole result
    in its job store and reuses it: a read, no lock taken, nothing heavy imported (the
    twostep launcher asks about a sweep's first job before its workers start)."""
    config = job_config(cfg)
    orchestration = config.get("orchestration") or {}
    if not orchestration.get("reuse_results", True):
        return False
    found = JobStore(str(orchestration["job_store"])).load(job_key(config, job_inputs(config)))
    return found is not None and identity.is_complete_result(found)


class JobStore:
    """``<root>/<job key>/result.json`` (+ ``config.json``) for every finished job.

    ``mlflow.json`` beside them remembers the runs the result was fully logged to, and
    ``mlflow-record.json`` what was logged: a re-run that reuses the result checks that
    its run is still in the store (cheaply, without MLflow) and logs the same record
    again when it is not (the store is a view the job store can rebuild).
    """

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self._locks: dict[str, int] = {}  # key -> file descriptor holding its lock
        self._refused: set[str] = set()  # keys whose stored entry was refused (warned once)

    def path(self, key: str) -> Path:
        return self.root / key / "result.json"

    def load(self, key: str) -> dict[str, Any] | None:
        try:
            data = json.loads(self.path(key).read_text())
        except (OSError, ValueError):
            return None
        return data if isinstance(data, dict) else None

    def load_or_claim(
        self, key: str, accept: Callable[[Mapping[str, Any]], bool] | None = None
    ) -> dict[str, Any] | None:
        """The stored result, or None after taking the key's lock: the caller computes
        the job, then calls :meth:`release` (:meth:`save` does not release).

        Two processes (two sweeps, or two single runs) asking for the same key: the
        second waits here until the first released its lock, then reads the first one's
        result. The lock is an ``flock``, so a process killed with ``kill -9`` drops it.
        ``accept``: a stored entry it refuses (not a complete result) counts as absent,
        with a warning naming the file: the job is computed again and its entry replaced.
        """
        found = self._accepted(key, accept)
        if found is not None or key in self._locks:
            return found
        self._acquire(key, "waiting: another process is computing job")
        return self._accepted(key, accept)  # stored by the other process meanwhile?

    def _accepted(
        self, key: str, accept: Callable[[Mapping[str, Any]], bool] | None
    ) -> dict[str, Any] | None:
        found = self.load(key)
        if found is None or accept is None or accept(found):
            return found
        if key not in self._refused:
            self._refused.add(key)
            print(
                f"warning: job store entry {self.path(key)} is not a complete result: "
                "computing the job again",
                file=sys.stderr,
                flush=True,
            )
        return None

    def _acquire(self, key: str, waiting: str) -> bool:
        """Take the key's lock (False: no lock can be taken here, go on without)."""
        import fcntl

        path = self.root / ".locks" / f"{key}.lock"
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            descriptor = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError:
            return False  # the store write reports why
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            print(f"{waiting} {key[:12]} (lock {path})", file=sys.stderr, flush=True)
            fcntl.flock(descriptor, fcntl.LOCK_EX)
        self._locks[key] = descriptor
        return True

    @contextmanager
    def locked(self, key: str) -> Iterator[None]:
        """The key's lock for the block (kept as it is when this store holds it already):
        what one process does for a job (compute it, record it in MLflow) no other
        process does at the same time."""
        if key in self._locks:
            yield
            return
        acquired = self._acquire(key, "waiting: another process is recording job")
        try:
            yield
        finally:
            if acquired:
                self.release(key)

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
            # config first: a stored result always has its config beside it (no secrets).
            write_json_atomic(self.root / key / "config.json", redact_config(dict(config)))
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
        data = self._read_json(self.root / key / "mlflow.json")
        return {str(k): str(v) for k, v in data.items()}

    def logged_record(self, key: str, destination: str) -> dict[str, Any] | None:
        """What was logged to ``destination`` (``"<tracking uri> <experiment>"``): the
        record to log again when that run is lost (:func:`flows.tracking.runs.job_record`)."""
        record = self._read_json(self.root / key / "mlflow-record.json").get(destination)
        return dict(record) if isinstance(record, Mapping) else None

    def mark_logged(
        self,
        key: str,
        tracking_uri: str,
        experiment: str,
        run_id: str,
        record: Mapping[str, Any] | None = None,
    ) -> None:
        if not (self.root / key).is_dir():
            return  # the job is not stored (it failed): nothing to skip next time
        destination = f"{tracking_uri} {experiment}"
        if record is not None:
            records = self._read_json(self.root / key / "mlflow-record.json")
            records[destination] = dict(record)
            write_json_atomic(self.root / key / "mlflow-record.json", records)
        logged = self.logged_to(key)
        logged[destination] = run_id
        write_json_atomic(self.root / key / "mlflow.json", logged)

    @staticmethod
    def _read_json(path: Path) -> dict[str, Any]:
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError):
            return {}
        return data if isinstance(data, dict) else {}
