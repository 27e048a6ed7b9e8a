"""Real sweeps through the ``twostep`` command: Prefect server, MLflow, kill -9 and resume.

Each test starts the command as a user would (``twostep -m ...``) in a temporary output
root: the sweep starts its own Prefect server on 127.0.0.1 (a fresh database: its
migrations run first) and stops it; nothing reaches outside this machine.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

from flows.servers import pid_alive, read_info
from tests.support.commands import TWOSTEP, mlflow_experiment, run, summary, sweep_dirs
from tests.support.data import make_data

REPO = Path(__file__).resolve().parent.parent

pytestmark = [pytest.mark.integration, pytest.mark.slow]


def benchmark_data(tmp: Path) -> Path:
    """The project's data/ if it is there, else the same files from the generators."""
    if all((REPO / "data" / d / "p02.pddl").is_file() for d in ("blocksworld", "grippers")):
        return REPO / "data"
    from twostep.generators import benchmark_files

    for domain in ("blocksworld", "grippers"):
        folder = tmp / domain
        folder.mkdir(parents=True)
        for name, text in benchmark_files(domain).items():
            (folder / name).write_text(text)
    return tmp


def stored_files(out: Path) -> dict[Path, tuple[int, int, bytes]]:
    """Each result and config file of the job store with its inode, modification time (ns)
    and content: a job computed again rewrites them (a new file, atomically)."""
    files = sorted(p for name in ("result.json", "config.json") for p in out.glob(f"jobs/*/{name}"))
    return {p: (p.stat().st_ino, p.stat().st_mtime_ns, p.read_bytes()) for p in files}


def job_results(sweep_dir: Path) -> list[dict[str, Any]]:
    """The result.json of each job of a sweep, in job order."""
    paths = sorted(sweep_dir.glob("*/result.json"), key=lambda p: int(p.parent.name.split("_")[0]))
    return [json.loads(p.read_text()) for p in paths]


def test_four_job_joblib_sweep_then_the_same_command_plans_nothing(tmp_path: Path) -> None:
    """The issue's command: 4 jobs, one parent run, 4 complete child runs, flow runs; the
    same command again reuses every job from the job store (what makes it fast; its time
    is bench/bench_resume.py's): not one stored file rewritten, no planner call, no flow."""
    data, out = benchmark_data(tmp_path / "data"), tmp_path / "out"
    command = [
        "-m", "domain=blocksworld,grippers", "task=1,2", "agents=2", "method=twostep",
        "decomposer=goal-split", "hydra/launcher=joblib", f"data.root={data}", f"output.root={out}",
    ]  # fmt: skip
    first = run(command)
    assert first.returncode == 0, first.stdout + first.stderr
    (sweep,) = sweep_dirs(out)
    facts = summary(sweep)
    assert facts["jobs_done"] == 4 and facts["jobs_failed"] == 0 and facts["jobs_reused"] == 0
    assert facts["prefect_flow_runs"] == {"COMPLETED": 4}  # the server's own record
    assert facts["prefect_server_started"] is True
    assert "[4/4: 4 ok, 0 failed, 0 timed out" in first.stdout

    client, runs = mlflow_experiment(out)
    parents = [r for r in runs if r.data.tags["twostep.kind"] == "sweep"]
    jobs = [r for r in runs if r.data.tags["twostep.kind"] == "job"]
    assert len(parents) == 1 and len(jobs) == 4
    assert {r.data.tags["mlflow.parentRunId"] for r in jobs} == {parents[0].info.run_id}
    for job in jobs:
        assert job.data.tags["twostep.status"] == "success"
        assert {"success", "exec_length", "sa_length", "speedup_exec", "planning_time_s",
                "subgoals_accepted", "planner_time_s"} <= set(job.data.metrics)  # fmt: skip
        names = {a.path for a in client.list_artifacts(job.info.run_id)}
        assert {"result.json", "plans", "schedule.txt"} <= names
    stored = stored_files(out)
    assert len(stored) == 8  # a result and a config per job
    computed = job_results(sweep)
    assert [r["orchestration"]["reused"] for r in computed] == [False] * 4
    assert all(r["orchestration"]["plan_calls"] > 0 for r in computed)

    second = run(command)
    assert second.returncode == 0, second.stdout + second.stderr
    again_dir = sweep_dirs(out)[-1]
    facts = summary(again_dir)
    assert facts["jobs_reused"] == 4 and facts["planner_calls_run"] == 0
    assert facts["prefect_server_started"] is False  # nothing to compute: no server
    assert stored_files(out) == stored  # every stored job read back, none computed again
    reused = job_results(again_dir)
    assert [r["job_key"] for r in reused] == [r["job_key"] for r in computed]
    for old, new in zip(computed, reused, strict=True):
        assert new["orchestration"]["reused"] is True
        assert new["orchestration"]["plan_calls"] == 0 and new["orchestration"]["prefect"] is False
        assert {k: v for k, v in new.items() if k != "orchestration"} == {
            k: v for k, v in old.items() if k != "orchestration"
        }  # the first run's plans and numbers, as they were
    _, again = mlflow_experiment(out)
    assert len(again) == 5  # no duplicate run


def test_sweep_killed_with_sigkill_resumes_without_duplicates(tmp_path: Path) -> None:
    data, out = make_data(tmp_path / "data"), tmp_path / "out"
    command = [
        "-m", "domain=blocksworld", "task=1,2,3", "method=twostep", "agents=2",
        f"data.root={data}", f"output.root={out}",
    ]  # fmt: skip
    process = subprocess.Popen(
        [str(TWOSTEP), *command], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        deadline = time.monotonic() + 400
        while not list(out.glob("multiruns/*/*/.twostep/jobs/0.json")):
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        process.send_signal(signal.SIGKILL)  # mid-sweep: job 0 done, job 1 running
        process.wait()
    finally:
        if process.poll() is None:
            process.kill()
    (sweep,) = sweep_dirs(out)
    done_before = len(list((sweep / ".twostep" / "jobs").glob("*.json")))
    assert 1 <= done_before < 3
    server = read_info(sweep / ".twostep" / "server.json")
    assert server is not None and server.pid is not None
    deadline = time.monotonic() + 30
    while pid_alive(server.pid) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not pid_alive(server.pid)  # the watchdog stopped the orphaned server

    again = run(command)
    assert again.returncode == 0, again.stdout + again.stderr
    facts = summary(sweep_dirs(out)[-1])
    assert facts["jobs_done"] == 3 and facts["jobs_failed"] == 0
    assert facts["jobs_reused"] == done_before  # finished jobs were not recomputed

    _, runs = mlflow_experiment(out)
    parents = [r for r in runs if r.data.tags["twostep.kind"] == "sweep"]
    jobs = [r for r in runs if r.data.tags["twostep.kind"] == "job"]
    assert len(parents) == 1  # the killed sweep's parent run was found again
    assert sorted(r.data.params["task"] for r in jobs) == ["1", "2", "3"]  # one run per job
    assert all(r.data.tags["twostep.status"] == "success" for r in jobs)
    assert {r.data.tags["mlflow.parentRunId"] for r in jobs} == {parents[0].info.run_id}
    assert os.environ.get("PREFECT_API_URL") is None  # nothing leaked into this process


def test_two_by_two_sweep_logs_what_ran_with_system_tags_and_a_results_table(
    tmp_path: Path,
) -> None:
    """Issue 21's check: ``method=sa,twostep agents=2,3``: SA logs the one agent it ran
    (the grid's N as a tag), at most 15 params per job run, user/source/git commit tags,
    runs as long as their jobs, and the sweep ends with a results table and results.csv
    that agree with the runs' own metrics."""
    import csv
    import getpass

    data, out = benchmark_data(tmp_path / "data"), tmp_path / "out"
    command = [
        "-m", "domain=grippers", "task=1", "method=sa,twostep", "agents=2,3",
        "decomposer=goal-split", "hydra/launcher=joblib", f"data.root={data}", f"output.root={out}",
    ]  # fmt: skip
    done = run(command)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "HTTP Request" not in done.stdout and "Joblib.Parallel" not in done.stdout
    client, runs = mlflow_experiment(out)
    experiment = client.get_experiment(runs[0].info.experiment_id)
    assert experiment.tags["mlflow.experimentKind"] == "custom_model_development"
    assert experiment.tags["mlflow.note.content"].startswith("twostep -m domain=grippers")
    jobs = [r for r in runs if r.data.tags["twostep.kind"] == "job"]
    assert len(jobs) == 4
    commit = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    for job in jobs:
        params, tags = job.data.params, job.data.tags
        assert len(params) <= 15
        assert not any(k.startswith(("orchestration.", "mlflow.", "output.")) for k in params)
        assert tags["mlflow.user"] == getpass.getuser()
        assert Path(tags["mlflow.source.name"]).name == "twostep"
        if commit:  # a checkout (not an installed wheel)
            assert tags["mlflow.source.git.commit"] == commit
        folder = tmp_path / job.info.run_id
        folder.mkdir()
        result = json.loads(
            Path(client.download_artifacts(job.info.run_id, "result.json", str(folder))).read_text()
        )
        # The run lasts as long as its job, not the logging window.
        duration_s = (job.info.end_time - job.info.start_time) / 1000
        assert duration_s >= result["orchestration"]["job_wall_time_s"] - 0.5
    sa = sorted((r for r in jobs if r.data.params["method.name"] == "sa"),
                key=lambda r: r.data.tags["twostep.grid_agents"])  # fmt: skip
    assert [r.data.params["agents"] for r in sa] == ["1", "1"]
    assert [r.data.tags["twostep.grid_agents"] for r in sa] == ["2", "3"]

    (sweep,) = sweep_dirs(out)
    with open(sweep / "results.csv") as handle:
        rows = {(r["method"], r["agents"]): r for r in csv.DictReader(handle)}
    assert set(rows) == {("sa", "1"), ("twostep (goal-split)", "2"), ("twostep (goal-split)", "3")}
    sa_lengths = [r.data.metrics["exec_length"] for r in sa]
    assert rows[("sa", "1")]["jobs"] == "2"
    assert float(rows[("sa", "1")]["mean_exec_length"]) == sum(sa_lengths) / 2
    assert "domain    method" in done.stdout and f"results: {sweep / 'results.csv'}" in done.stdout
    parent = next(r for r in runs if r.data.tags["twostep.kind"] == "sweep")
    names = {a.path for a in client.list_artifacts(parent.info.run_id)}
    assert {"results.csv", "report"} <= names
