"""Finished jobs, stored by job key, so that no finished job is ever computed twice.

What goes into the key (the identity config and the content of every input file) and
which results are kept is decided by :mod:`flows.identity`; this module reads the
config and the files, and owns ``<orchestration.job_store>/<key>/``. A result is written
once, atomically, after the job finished; a job that raised, or whose result says it did
not finish (``llm_error``, ``error``), is not stored: a re-run tries it again.

A stored entry is used only when it provably belongs to the job (:meth:`JobStore.check`):
its folder is no symlink, its ``seal.json`` (written last) names the job's key, the job
(domain, task, method, decomposer, agents, seed) and its inputs' digests, and holds the
SHA-256 of its ``result.json``; the result says the same job and is whole and consistent
(:func:`flows.identity.result_problem`). Anything else is computed again, with one
warning line naming the entry and why (the sweep's summary counts them). An entry stored
before seals existed is checked by its ``config.json`` (it must hash to the key) and
sealed when first used.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sys
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flows import identity
from flows.redaction import redact_config
from twostep.tasks.benchmark import BenchmarkError, task_path
from twostep.util.files import json_text, write_json_atomic, write_text_atomic

SEAL = "seal.json"  # written last: the entry's key, job, inputs and result checksum
SEAL_FORMAT = 1


def job_config(cfg: Any) -> dict[str, Any]:
    """The job's resolved config as plain data, without ``hydra``, as it is recorded
    (:func:`flows.spelling.recorded`: plan-deal and the portfolios as the old spelling
    named them, so that their keys and names stay)."""
    from omegaconf import DictConfig, OmegaConf

    from flows.spelling import recorded

    if isinstance(cfg, DictConfig):
        data = OmegaConf.to_container(cfg, resolve=True, enum_to_str=True)
    else:
        data = dict(cfg)
    assert isinstance(data, dict)
    data.pop("hydra", None)
    return recorded({str(k): v for k, v in data.items()})


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
    """The job's key (:func:`flows.identity.job_key`); ``inputs``: :func:`job_inputs`."""
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


def job_fields(config: Mapping[str, Any]) -> dict[str, Any]:
    """What job a config (or a result.json dict) is: domain, task, method, decomposer
    (TwoStep's), the number of agents it runs (SA: 1) and seed."""

    def name(value: Any) -> Any:
        return value.get("name") if isinstance(value, Mapping) else value

    method = name(config.get("method"))
    agents = config.get("agents")
    return {
        "domain": name(config.get("domain")),
        "task": config.get("task"),
        "method": method,
        "decomposer": name(config.get("decomposer")) if method == "twostep" else None,
        "agents": 1 if method == "sa" else agents,
        "seed": config.get("seed"),
    }


@dataclass(frozen=True)
class JobEntry:
    """What a stored entry must say to be this job's (:meth:`JobStore.check`)."""

    key: str
    job: dict[str, Any]  # job_fields of the job's config
    inputs: dict[str, str]  # job_inputs: each input file's digest, by role

    @classmethod
    def of(cls, config: Mapping[str, Any], key: str, inputs: Mapping[str, str]) -> JobEntry:
        return cls(key, job_fields(config), dict(inputs))


def _digest(text: str | bytes) -> str:
    return hashlib.sha256(text.encode() if isinstance(text, str) else text).hexdigest()


def _result_job(result: Mapping[str, Any]) -> dict[str, Any]:
    """The job a result says it is (its decomposer is its own name for the method: not
    compared)."""
    return {**job_fields(result), "decomposer": None}


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
        # key -> why its stored entry was not used (warned once; the sweep counts them)
        self.refused: dict[str, str] = {}
        self.unwritten: dict[str, str] = {}  # key -> why its result could not be stored

    def path(self, key: str) -> Path:
        return self.root / key / "result.json"

    def load(self, key: str) -> dict[str, Any] | None:
        try:
            data = json.loads(self.path(key).read_text())
        except (OSError, ValueError):
            return None
        return data if isinstance(data, dict) else None

    def load_or_claim(
        self,
        key: str,
        accept: Callable[[Mapping[str, Any]], bool] | None = None,
        expect: JobEntry | None = None,
    ) -> dict[str, Any] | None:
        """The stored result, or None after taking the key's lock: the caller computes
        the job, then calls :meth:`release` (:meth:`save` does not release).

        Two processes (two sweeps, or two single runs) asking for the same key: the
        second waits here until the first released its lock, then reads the first one's
        result. The lock is an ``flock``, so a process killed with ``kill -9`` drops it.
        ``expect``: the job the entry must be (:meth:`check`); ``accept``: a test of the
        result alone. An entry refused counts as absent, with a warning naming it and why
        (:attr:`refused`): the job is computed again and its entry replaced.
        """
        found = self._accepted(key, accept, expect)
        if found is not None or key in self._locks:
            return found
        self._acquire(key, "waiting: another process is computing job")
        return self._accepted(key, accept, expect)  # stored by the other process meanwhile?

    def _accepted(
        self,
        key: str,
        accept: Callable[[Mapping[str, Any]], bool] | None,
        expect: JobEntry | None,
    ) -> dict[str, Any] | None:
        if expect is not None:
            found, problem = self.check(expect)
        else:
            found = self.load(key)
            problem = None
            if found is not None and accept is not None and not accept(found):
                problem = f"{self.path(key)} is not a complete result"
        if problem is None:
            return found
        if key not in self.refused:
            self.refused[key] = problem
            print(
                f"warning: job store entry {problem}: computing the job again",
                file=sys.stderr,
                flush=True,
            )
        return None

    def check(self, expect: JobEntry) -> tuple[dict[str, Any] | None, str | None]:
        """The entry of ``expect.key`` when it is this job's (result, None); (None, None)
        when there is none; (None, why) when there is one that must not be used: one line
        starting with the entry's folder or file."""
        key = expect.key
        folder = self.root / key
        for path in (folder, folder / "result.json", folder / SEAL):
            if path.is_symlink():
                return None, f"{path} is a symlink (to {os.readlink(path)}), not this job's own"
        try:
            data = (folder / "result.json").read_bytes()
        except FileNotFoundError:
            return None, None
        except OSError as error:
            return None, f"{self.path(key)} cannot be read ({error.strerror or error})"
        try:
            result = json.loads(data)
        except ValueError:
            result = None
        if not isinstance(result, dict):
            return None, f"{self.path(key)} is not a complete result (not a JSON object)"
        problem = identity.result_problem(result)
        if problem is not None:
            return None, f"{self.path(key)} is not a complete result ({problem})"
        if _result_job(result) != {**expect.job, "decomposer": None}:
            return None, (
                f"{self.path(key)} is not this job's: it holds {identity.job_name(result)}'s "
                f"result, not {identity.job_name(expect.job)}'s"
            )
        seal = self._read_json(folder / SEAL)
        if not seal:
            return self._adopted(expect, result, data)
        if seal.get("key") != key or seal.get("job") != expect.job:
            return None, f"{folder / SEAL} is another job's seal"
        if seal.get("inputs") != expect.inputs:
            return None, f"{folder / SEAL} was sealed with other input files"
        if seal.get("result_sha256") != _digest(data):
            return None, (
                f"{self.path(key)} has changed since it was stored (its SHA-256 is not "
                f"the one in {SEAL})"
            )
        return result, None

    def _adopted(
        self, expect: JobEntry, result: dict[str, Any], data: bytes
    ) -> tuple[dict[str, Any] | None, str | None]:
        """An entry stored before seals existed: used (and sealed now) when its
        ``config.json`` hashes to the key with the job's inputs."""
        config = self._read_json(self.root / expect.key / "config.json")
        if not config or identity.job_key(config, expect.inputs) != expect.key:
            return None, (
                f"{self.root / expect.key} has no {SEAL} and no config.json of this job "
                "(cut short, or not written by twostep)"
            )
        with contextlib.suppress(OSError):  # a read-only store: checked again next time
            self._seal(expect, data)
        return result, None

    def _seal(self, expect: JobEntry, result_bytes: bytes) -> None:
        seal = {
            "format": SEAL_FORMAT,
            "key": expect.key,
            "job": expect.job,
            "inputs": expect.inputs,
            "result_sha256": _digest(result_bytes),
        }
        write_json_atomic(self.root / expect.key / SEAL, seal)

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

    def save(
        self,
        key: str,
        config: Mapping[str, Any],
        result: Mapping[str, Any],
        inputs: Mapping[str, str] | None = None,
    ) -> bool:
        """Store a finished job's result; False (nothing written) for one that did not
        finish its work (:func:`flows.identity.is_storable`), or when the store cannot
        be written: the result is not lost, the job's run directory holds it, and a
        warning says so. ``inputs`` (the job's input digests): the entry is sealed
        (``seal.json``, written last), so that a later run can check it is this job's."""
        if not identity.is_storable(result):
            return False
        folder = self.root / key
        try:
            if folder.is_symlink():  # someone else's folder: never written through
                folder.unlink()
            # config first: a stored result always has its config beside it (no secrets).
            write_json_atomic(folder / "config.json", redact_config(dict(config)))
            text = json_text(dict(result))
            (folder / SEAL).unlink(missing_ok=True)  # unsealed while the result changes
            write_text_atomic(self.path(key), text)
            if inputs is not None:
                self._seal(JobEntry.of(config, key, inputs), text.encode())
        except OSError as error:
            self.unwritten[key] = f"job store {self.root} not written ({error.strerror or error})"
            print(
                f"warning: {self.unwritten[key]}: "
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
