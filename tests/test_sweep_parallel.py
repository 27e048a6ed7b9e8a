"""A sweep on every core (the default launcher) against the same sweep in one process,
through the ``twostep`` command: the same results and job keys, one MLflow run and one job
record per job; and ``kill -9`` of a parallel sweep, then the same command: every job
done once, nothing computed twice, one run per job.

Each sweep starts its own Prefect server on 127.0.0.1 (stopped by the sweep, or by its
watchdog once the sweep is killed) and writes a SQLite MLflow store in a temporary root.
"""

from __future__ import annotations

import json
import signal
import sqlite3
import subprocess
import time
from collections import Counter
from contextlib import closing
from pathlib import Path
from typing import Any

import pytest

from flows.launcher import available_cores
from flows.servers import pid_alive, read_info
from tests.support.commands import TWOSTEP, mlflow_experiment, run, summary, sweep_dirs
from tests.support.data import make_data

pytestmark = [pytest.mark.integration, pytest.mark.slow]

GRID = ["-m", "domain=blocksworld", "task=1,2,3", "method=sa,twostep", "decomposer=goal-split",
        "agents=2"]  # fmt: skip
JOBS = 6


def untimed(data: Any) -> Any:
    """``data`` without the seconds things took (keys like ``planning_time_s``)."""
    if isinstance(data, dict):
        return {k: untimed(v) for k, v in data.items() if not ("time" in k and k.endswith("_s"))}
    if isinstance(data, list):
        return [untimed(v) for v in data]
    return data


def results(sweep: Path) -> dict[str, dict[str, Any]]:
    """Each job's result.json without how it ran (its timings and the orchestration's), by
    job folder name without its number (``0_blocksworld_p1_sa_n1_s0`` -> ``blocksworld_p1_sa_n1_s0``)."""
    found = {}
    for path in sweep.glob("*/result.json"):
        result = json.loads(path.read_text())
        result.pop("orchestration")
        found[path.parent.name.split("_", 1)[1]] = untimed(result)
    return found


def records(sweep: Path) -> list[dict[str, Any]]:
    return [json.loads(p.read_text()) for p in (sweep / ".twostep" / "jobs").glob("*.json")]


def task_runs(out: Path) -> list[tuple[str, str]]:
    """(flow run id, state type) of every task run in the sweep's Prefect database, read
    once its server has stopped."""
    database = out / "prefect" / "prefect.db"
    with closing(sqlite3.connect(f"file:{database}?mode=ro", uri=True)) as db:
        return [
            (str(f), str(s)) for f, s in db.execute("SELECT flow_run_id, state_type FROM task_run")
        ]


def job_runs(out: Path) -> list[Any]:
    _, runs = mlflow_experiment(out)
    return [r for r in runs if r.data.tags["twostep.kind"] == "job"]


@pytest.mark.skipif(available_cores() < 2, reason="a parallel sweep needs 2 cores")
@pytest.mark.timeout(1200)  # three sweeps, each with its Prefect server, on a busy machine
def test_a_parallel_sweep_gives_what_a_one_process_sweep_gives(tmp_path: Path) -> None:
    data = make_data(tmp_path / "data")
    sweeps = {}
    launchers = {
        "parallel": [],
        "one": ["hydra.launcher.n_jobs=1"],
        "basic": ["hydra/launcher=basic"],
    }
    for name, extra in launchers.items():
        out = tmp_path / name
        done = run([*GRID, f"data.root={data}", f"output.root={out}", *extra])
        assert done.returncode == 0, done.stdout + done.stderr
        (sweeps[name],) = sweep_dirs(out)
        assert "time: " in done.stdout and " beyond them " in done.stdout  # the timing line
        facts = summary(sweeps[name])
        assert facts["jobs_done"] == JOBS and facts["jobs_failed"] == 0
        assert facts["prefect_flow_runs"] == {"COMPLETED": JOBS}
        # every task run's end reached the server's records before it stopped
        tasks = task_runs(out)
        assert len({flow for flow, _ in tasks}) == JOBS
        assert {state for _, state in tasks} == {"COMPLETED"}, Counter(s for _, s in tasks)
        runs = job_runs(out)
        assert len(runs) == JOBS  # one MLflow run per job
        assert len({r.data.tags["twostep.job_key"] for r in runs}) == JOBS
        assert all(r.data.tags["twostep.status"] == "success" for r in runs)
        jobs = records(sweeps[name])
        assert sorted(r["num"] for r in jobs) == list(range(JOBS))  # one record per job
        assert {r["mlflow_run_id"] for r in jobs} == {r.info.run_id for r in runs}
    workers = {r["launch"]["worker"] for r in records(sweeps["parallel"])}
    assert len(workers) == 2  # both cores ran jobs
    assert len({r["launch"]["worker"] for r in records(sweeps["one"])}) == 1
    parallel, one = results(sweeps["parallel"]), results(sweeps["one"])
    assert len(parallel) == JOBS and parallel == one  # the same plans, lengths and keys
    assert parallel == results(sweeps["basic"])  # as Hydra's own basic launcher gives
    assert all(r["success"] and r["plans"] and r["job_key"] for r in parallel.values())


@pytest.mark.skipif(available_cores() < 2, reason="a parallel sweep needs 2 cores")
def test_a_parallel_sweep_killed_with_sigkill_resumes_without_duplicates(tmp_path: Path) -> None:
    data, out = make_data(tmp_path / "data"), tmp_path / "out"
    command = [*GRID, f"data.root={data}", f"output.root={out}"]
    process = subprocess.Popen(
        [str(TWOSTEP), *command], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        deadline = time.monotonic() + 400
        while not list(out.glob("multiruns/*/*/.twostep/jobs/*.json")):
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        process.send_signal(signal.SIGKILL)  # jobs done, others running in the workers
        process.wait()
    finally:
        if process.poll() is None:
            process.kill()
    (sweep,) = sweep_dirs(out)
    workers = {r["launch"]["worker"] for r in records(sweep)}
    server = read_info(sweep / ".twostep" / "server.json")
    assert server is not None and server.pid is not None
    deadline = time.monotonic() + 30
    while any(pid_alive(p) for p in [*workers, server.pid]) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not any(pid_alive(p) for p in workers)  # the workers died with the sweep
    assert not pid_alive(server.pid)  # and the server with its watchdog
    stored = len(list(out.glob("jobs/*/result.json")))
    assert 1 <= stored < JOBS

    again = run(command)
    assert again.returncode == 0, again.stdout + again.stderr
    facts = summary(sweep_dirs(out)[-1])
    assert facts["jobs_done"] == JOBS and facts["jobs_failed"] == 0
    assert facts["jobs_reused"] == stored  # what was stored is not computed again
    assert len(list(out.glob("jobs/*/result.json"))) == JOBS
    runs = job_runs(out)
    assert Counter(Counter(r.data.tags["twostep.job_key"] for r in runs).values()) == {1: JOBS}
    assert all(r.data.tags["twostep.status"] == "success" for r in runs)
    _, all_runs = mlflow_experiment(out)
    assert len([r for r in all_runs if r.data.tags["twostep.kind"] == "sweep"]) == 1
    assert sorted(r["num"] for r in records(sweep_dirs(out)[-1])) == list(range(JOBS))
