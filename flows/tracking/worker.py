"""A helper process that logs one single run to MLflow, started when the run starts.

Importing MLflow and opening a SQLite store costs 2-3 s (SQLAlchemy's ORM set-up), as
much as the rest of a short run. The ``twostep`` command therefore starts this process
first: it imports MLflow and opens the store on the other core while the job reads its
task and plans; the job then sends it the run's record (one JSON line on stdin) and
waits for the run id (one JSON line on stdout). Nothing is logged if the job sends
nothing (stdin closed): the process just exits.

    python -m flows.tracking.worker <tracking uri> <artifact location or ""> <experiment>
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Sequence
from typing import IO, Any

from flows.console import one_line


class TrackingWorker:
    """The job's side: start the process, send the record, read the run id."""

    def __init__(self, process: subprocess.Popen[str]) -> None:
        self.process = process

    @classmethod
    def start(cls, uri: str, artifact_location: str | None, experiment: str) -> TrackingWorker:
        command = [sys.executable, "-m", "flows.tracking.worker", uri]
        command += [artifact_location or "", experiment]
        process = subprocess.Popen(
            command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )  # stderr: the console's, for MLflow's own warnings
        return cls(process)

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
        """Let the process go (after :meth:`log`, or with nothing to log)."""
        if self.process.poll() is None:
            try:
                self.process.communicate("", timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def serve(argv: Sequence[str], stdin: IO[str], stdout: IO[str]) -> int:
    uri, artifact_location, experiment = argv
    try:
        from flows.tracking.client import Tracker, log_job_run

        tracker = Tracker(uri, artifact_location or None)  # the slow part: done meanwhile
        experiment_id = tracker.experiment_id(experiment)
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
    sys.exit(serve(sys.argv[1:], sys.stdin, sys.stdout))
