"""A helper process that logs one single run to MLflow through its client, started as
early as the run.

Importing MLflow's client and its SQLite store (SQLAlchemy, alembic) costs 2-3 CPU
seconds, as much as the rest of a short run. The ``twostep`` command therefore starts
this process first thing (:meth:`TrackingWorker.prestart`, from :mod:`flows.command`,
before Hydra is imported): it imports MLflow on the other core while the command imports
Hydra and the library, composes the config, reads its task and plans. The job then tells it the store and experiment (one JSON line on stdin:
it opens them), later sends the run's record (a second line) and waits for the run id
(one JSON line on stdout). A job with nothing to log (MLflow off, its run already in the
store) stops the process.

    python -m flows.tracking.worker
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from typing import IO, Any

from flows.console import one_line


class TrackingWorker:
    """The job's side: start the process, tell it the store, send the record, read the run id."""

    _prestarted: TrackingWorker | None = None

    def __init__(self, process: subprocess.Popen[str]) -> None:
        self.process = process

    @classmethod
    def spawn(cls) -> TrackingWorker:
        process = subprocess.Popen(
            [sys.executable, "-m", "flows.tracking.worker"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )  # stderr: the console's, for MLflow's own warnings
        return cls(process)

    @classmethod
    def prestart(cls) -> None:
        """Start the process now, for the next :meth:`start` of this process to take."""
        if cls._prestarted is None:
            cls._prestarted = cls.spawn()

    @classmethod
    def discard_prestarted(cls) -> None:
        """Stop a process started by :meth:`prestart` that no job took."""
        worker, cls._prestarted = cls._prestarted, None
        if worker is not None:
            worker.close()

    @classmethod
    def start(cls, uri: str, artifact_location: str | None, experiment: str) -> TrackingWorker:
        """The process (the prestarted one, else a new one), told the store and experiment."""
        worker, cls._prestarted = cls._prestarted or cls.spawn(), None
        assert worker.process.stdin is not None
        setup = {"uri": uri, "artifact_location": artifact_location, "experiment": experiment}
        try:
            worker.process.stdin.write(json.dumps(setup) + "\n")
            worker.process.stdin.flush()
        except OSError:  # it died: log() reports it
            pass
        return worker

    def log(self, record: dict[str, Any], timeout_s: float = 120.0) -> str:
        """Send the record; return the run id (raise with the worker's error)."""
        out, _ = self.process.communicate(json.dumps(record) + "\n", timeout=timeout_s)
        lines = [line for line in out.splitlines() if line.startswith("{")]
        if not lines:
            raise RuntimeError(f"the MLflow logging process exited ({self.process.returncode})")
        answer = json.loads(lines[-1])
        if "error" in answer:
            raise RuntimeError(str(answer["error"]))
        return str(answer["run_id"])

    def close(self) -> None:
        """Let the process go: after :meth:`log` it has ended; with nothing logged it is
        stopped (it may still be importing MLflow: nobody waits for that)."""
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()


def serve(stdin: IO[str], stdout: IO[str]) -> int:
    try:  # the slow part, done while the job composes its config and runs
        import mlflow.store.tracking.sqlalchemy_store
        import mlflow.tracking  # noqa: F401
    except Exception:  # said again below, where it matters
        pass
    line = stdin.readline()
    if not line.strip():
        return 0  # nothing to log
    try:
        from flows.tracking.client import Tracker, log_job_run

        setup = json.loads(line)
        tracker = Tracker(setup["uri"], setup["artifact_location"])
        experiment_id = tracker.experiment_id(setup["experiment"])
    except Exception as error:
        setup_error: Exception | None = error
    else:
        setup_error = None
    line = stdin.readline()
    if not line.strip():
        return 0  # nothing to log
    try:
        if setup_error is not None:
            raise setup_error
        run_id = log_job_run(tracker, experiment_id, None, json.loads(line))
        answer: dict[str, str] = {"run_id": run_id}
    except Exception as error:
        answer = {"error": one_line(error, limit=300)}
    stdout.write(json.dumps(answer) + "\n")
    stdout.flush()
    return 0


if __name__ == "__main__":
    from flows.environment import quiet_defaults

    quiet_defaults()
    code = serve(sys.stdin, sys.stdout)
    # The answer is out and the run is in the store (each write is committed, artifacts
    # are copied). Python's own teardown with MLflow and SQLAlchemy loaded, which frees
    # their modules, takes about a second more, and the job waits for this process to
    # end (TrackingWorker.log): skip the teardown.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
