"""flows/: one job through the runner, MLflow records, job store, failures, Prefect caching.

The fast tests run jobs on the library path (``orchestration.prefect=false``) against a
SQLite MLflow store in a temporary folder. Tests marked ``integration`` share one Prefect
server for the session (started on 127.0.0.1, stopped by PID) and run jobs as flows:
planner task caching (counted calls), the API's record of the runs, and a
2-job sweep on a local Dask cluster.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import DictConfig

from flows import job as runner
from flows.artifacts import write_job_files
from flows.build import Job
from flows.config import register
from flows.console import format_summary, progress_line
from flows.identity import job_name
from flows.job import execute_job
from flows.servers import pid_alive
from flows.store import JobStore, job_config, job_key
from flows.sweep_state import SweepState, record_job
from flows.tracking.contents import config_tags, job_metrics, job_params
from flows.tracking.runs import TrackingError
from tests.support.commands import api
from tests.support.data import make_data

REPO = Path(__file__).resolve().parent.parent
CONF = REPO / "conf"
TWOSTEP = Path(sys.executable).parent / "twostep"  # the console script of this venv


@pytest.fixture(scope="module")
def shared(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One data root and one MLflow store for the module (a new store takes seconds)."""
    base = tmp_path_factory.mktemp("flows")
    return {"data": make_data(base / "data"), "out": base / "out"}


@pytest.fixture(scope="module", autouse=True)
def hydra_conf() -> Iterator[None]:
    register()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        yield


def job_cfg(shared: dict[str, Path], tmp: Path, *overrides: str) -> DictConfig:
    return compose(
        "config",
        overrides=[
            f"data.root={shared['data']}",
            f"output.root={shared['out']}",
            f"orchestration.job_store={tmp / 'jobs'}",
            f"mlflow.experiment={tmp.name}",
            "orchestration.prefect=false",
            "domain=blocksworld",
            "planner.time_limit_s=20",
            *overrides,
        ],
    )


def mlflow_runs(shared: dict[str, Path], experiment: str) -> list[Any]:
    from mlflow.tracking import MlflowClient

    client = MlflowClient(f"sqlite:///{shared['out']}/mlflow.db")
    found = client.get_experiment_by_name(experiment)
    return [] if found is None else list(client.search_runs([found.experiment_id]))


def artifact_paths(shared: dict[str, Path], run_id: str) -> list[str]:
    from mlflow.tracking import MlflowClient

    client = MlflowClient(f"sqlite:///{shared['out']}/mlflow.db")
    paths: list[str] = []

    def walk(path: str | None = None) -> None:
        for item in client.list_artifacts(run_id, path):
            walk(item.path) if item.is_dir else paths.append(item.path)

    walk()
    return sorted(paths)


# ----------------------------------------------------------------- library path


def test_job_is_recorded_then_reused_without_planning(
    shared: dict[str, Path], tmp_path: Path
) -> None:
    # goal-split: a helper and a main agent to plan (the default plan-deal plans SA only)
    cfg = job_cfg(shared, tmp_path, "method=twostep", "decomposer=goal-split", "task=2", "agents=2")
    first = execute_job(cfg, tmp_path / "job1")
    assert first.status == "success" and not first.reused
    assert first.stats.plan_calls == 3  # SA for sa_length, one helper, the main agent
    result = json.loads((tmp_path / "job1" / "result.json").read_text())
    assert result["exec_length"] < result["sa_length"]  # two towers in parallel
    assert result["job_key"] == first.key
    assert result["orchestration"]["plan_calls"] == 3
    assert (tmp_path / "jobs" / first.key / "result.json").is_file()

    (run,) = mlflow_runs(shared, tmp_path.name)
    tags, metrics, params = run.data.tags, run.data.metrics, run.data.params
    assert tags["twostep.kind"] == "job" and tags["twostep.job_key"] == first.key
    assert tags["twostep.status"] == "success" and tags["twostep.reused"] == "false"
    assert "mlflow.parentRunId" not in tags  # a single run has no parent
    assert metrics["success"] == 1.0 and metrics["exec_length"] == result["exec_length"]
    assert metrics["speedup_exec"] == pytest.approx(result["sa_length"] / result["exec_length"])
    assert metrics["subgoals_accepted"] == 1.0 and metrics["subgoals_proposed"] == 1.0
    assert {"planner_time_s.helper.agent1", "planner_time_s.main.agent0"} <= set(metrics)
    assert params["domain.name"] == "blocksworld" and params["task"] == "2"
    assert params["method.name"] == "twostep" and params["planner.alias"] == "lama-first"
    assert artifact_paths(shared, run.info.run_id) == [
        "plans/agent0.plan",
        "plans/agent1.plan",
        "result.json",
        "schedule.txt",
        "subgoals/helper1.pddl",
    ]

    second = execute_job(cfg, tmp_path / "job2")
    assert second.reused and second.stats.plan_calls == 0
    assert second.result["exec_length"] == result["exec_length"]
    assert len(mlflow_runs(shared, tmp_path.name)) == 1  # no duplicate run


def test_logged_run_is_found_again_by_job_key(shared: dict[str, Path], tmp_path: Path) -> None:
    """As after a kill -9 between the job store write and MLflow: no second run."""
    cfg = job_cfg(shared, tmp_path, "method=sa", "task=1")
    first = execute_job(cfg, tmp_path / "job1")
    (tmp_path / "jobs" / first.key / "mlflow.json").unlink()  # forget that it was logged
    second = execute_job(cfg, tmp_path / "job2")
    assert second.reused and second.mlflow_run_id == first.mlflow_run_id
    assert len(mlflow_runs(shared, tmp_path.name)) == 1


def test_bad_input_is_a_failed_job(shared: dict[str, Path], tmp_path: Path) -> None:
    for task in (9, 4):  # unknown task; malformed PDDL
        outcome = execute_job(
            job_cfg(shared, tmp_path, "method=sa", f"task={task}"), tmp_path / f"j{task}"
        )
        assert outcome.status == "failed" and outcome.input_error
        written = json.loads((tmp_path / f"j{task}" / "result.json").read_text())
        assert written["status"] == "failed" and written["error"] == outcome.error
        assert not (tmp_path / "jobs" / outcome.key).exists()  # not stored: a re-run retries
    outcome = execute_job(job_cfg(shared, tmp_path, "task=9"), tmp_path / "j")
    assert "unknown task 9" in format_summary(outcome.result)
    runs = {r.data.params["task"]: r for r in mlflow_runs(shared, tmp_path.name)}
    assert runs["9"].data.tags["twostep.status"] == "failed"
    assert "unknown task 9" in runs["9"].data.tags["twostep.error"]
    assert runs["9"].info.status == "FAILED" and runs["9"].data.metrics["success"] == 0.0


def test_a_timed_out_job_is_not_a_success_in_mlflow(
    shared: dict[str, Path], tmp_path: Path, data_root: Path
) -> None:
    """Issue 37: a timed-out run was FINISHED (a green check) with planning_time_s at the
    limit, and MLflow's grouped mean of planning_time_s took it in. termes p06's SA search
    runs out of a 1 s limit (its first plan takes seconds more: README, termes)."""
    cfg = job_cfg(shared, tmp_path, "method=sa", "domain=termes", "task=6",
                  f"data.root={data_root}", "planner.time_limit_s=1")  # fmt: skip
    outcome = execute_job(cfg, tmp_path / "job")
    assert outcome.status == "timeout"
    (run,) = mlflow_runs(shared, tmp_path.name)
    metrics, tags = run.data.metrics, run.data.tags
    assert run.info.status == "KILLED" and tags["twostep.status"] == "timeout"
    # no metric of a success's name but the shared ones: the timed-out time stands apart
    assert "planning_time_s" not in metrics and "exec_length" not in metrics
    assert metrics["unsolved.planning_time_s"] == outcome.result["planning_time_s"] > 0
    assert metrics["success"] == 0.0 and metrics["planner_timeouts"] == 1.0
    assert tags["twostep.distinct_runs"].startswith("1 (deterministic")


def test_crash_is_recorded_with_its_traceback(
    shared: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def crash(*args: object, **kwargs: object) -> None:
        raise RuntimeError("planner exploded")

    monkeypatch.setattr(Job, "run", crash)
    outcome = execute_job(job_cfg(shared, tmp_path, "method=sa", "task=1"), tmp_path / "job")
    assert outcome.status == "failed" and not outcome.input_error
    assert outcome.error == "RuntimeError: planner exploded"
    assert "Traceback" in (tmp_path / "job" / "error.txt").read_text()


@pytest.mark.parametrize("uri", ["http://127.0.0.1:9", "sqlite:///{tmp}/a-file/mlflow.db"])
def test_unusable_tracking_store_fails_before_any_work(
    shared: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, uri: str
) -> None:
    (tmp_path / "a-file").write_text("not a folder")

    def no_work(*args: object, **kwargs: object) -> None:
        raise AssertionError("planning started")

    monkeypatch.setattr(runner, "compute_job", no_work)
    cfg = job_cfg(shared, tmp_path, f"mlflow.tracking_uri={uri.format(tmp=tmp_path)}")
    with pytest.raises(TrackingError) as info:
        execute_job(cfg, tmp_path / "job")
    assert "\n" not in str(info.value) and "mlflow.tracking_uri" in str(info.value)


def test_cli_errors_are_one_line(shared: dict[str, Path], tmp_path: Path) -> None:
    common = [f"data.root={shared['data']}", f"output.root={tmp_path}", "domain=blocksworld"]
    cases = [
        (["task=1", "mlflow.tracking_uri=http://127.0.0.1:9"], "MLflow tracking server"),
        (["task=99"], "unknown task 99"),
    ]
    for extra, expected in cases:
        done = subprocess.run(
            [str(TWOSTEP), *common, *extra], capture_output=True, text=True, timeout=120
        )
        assert done.returncode == 2, done.stderr
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0]
    assert not (tmp_path / "prefect").exists()  # no server was started for bad input


# ----------------------------------------------------------------- keys, records


def test_job_key_ignores_where_and_how() -> None:
    base = {
        "domain": {"name": "blocksworld"},
        "task": 1,
        "seed": 0,
        "llm": {"model": "m", "cache_dir": "/a"},
    }
    moved = {
        **base,
        "output": {"root": "/elsewhere"},
        "orchestration": {"task_runner": "dask"},
        "mlflow": {"tracking_uri": "http://x"},
        "llm": {"model": "m", "cache_dir": "/b"},
    }
    assert job_key(base) == job_key(moved)
    assert job_key(base) != job_key({**base, "seed": 1})
    assert job_key(base) != job_key({**base, "llm": {"model": "other", "cache_dir": "/a"}})


def test_planner_input_is_the_same_text_in_every_process(tmp_path: Path) -> None:
    """The plan cache key hashes this text: it must not depend on set iteration order."""
    make_data(tmp_path)
    code = (
        "import hashlib,sys; from twostep.tasks.benchmark import load_task; "
        "from twostep.planner import planner_input; "
        f"t=load_task('blocksworld', 2, {str(tmp_path)!r}); "
        "print(hashlib.sha256(''.join(planner_input(t.problem)).encode()).hexdigest())"
    )
    digests = {
        subprocess.run(
            [sys.executable, "-c", code],
            capture_output=True,
            text=True,
            check=True,
            env={**os.environ, "PYTHONHASHSEED": seed},
        ).stdout.strip()
        for seed in ("1", "2")
    }
    assert len(digests) == 1


def test_metrics_and_params_follow_the_contract() -> None:
    result = {
        "method": "twostep",
        "success": True,
        "exec_length": 4,
        "sa_length": 6,
        "planning_time_s": 1.5,
        "subgoals": [{"status": "accepted"}, {"status": "discarded"}],
        "planner_calls": [
            {"role": "helper", "agent": "agent1", "planner_time_s": 0.2},
            {"role": "main", "agent": "agent0", "planner_time_s": 0.3},
        ],
    }
    metrics = job_metrics(result, {"job_wall_time_s": 2.0})
    assert metrics["speedup_exec"] == 1.5 and metrics["success"] == 1.0
    assert (
        metrics["subgoals_proposed"],
        metrics["subgoals_accepted"],
        metrics["subgoals_discarded"],
    ) == (2, 1, 1)
    assert metrics["planner_time_s.helper.agent1"] == 0.2 and metrics["planner_time_s"] == [
        0.2,
        0.3,
    ]
    assert "llm_time_s" not in metrics and metrics["job_wall_time_s"] == 2.0
    params = job_params(
        {"llm": {"api_key": "sk-secret", "api_key_env": "OPENAI_API_KEY", "model": "m"}, "task": 3}
    )
    # What defines the experiment only: the key's variable name says where it runs.
    assert params == {"llm.model": "m", "task": "3"}
    assert "sk-secret" not in json.dumps(config_tags({"llm": {"api_key": "sk-secret"}}))


GRID_JOB = {
    "domain": {"name": "grippers", "agent_predicates": ["at-robby"]},
    "task": 1,
    "agents": 3,
    "seed": 0,
    "method": {"name": "sa", "fallback_if_longer": True},
    "decomposer": {"name": "llm", "cut": "best"},
    "llm": {"model": "openai/gpt-4o", "mode": "live", "api_base": "https://u:pw@h/v1"},
    "planner": {"alias": "lama-first", "time_limit_s": 60.0},
    "score_mode": "exact",
    "score_max_nodes": 2000,
    "executor": {"name": "symbolic"},
    "data": {"root": "/somewhere/data"},
    "output": {"root": "/somewhere/outputs"},
    "orchestration": {"prefect": None, "job_store": "/somewhere/outputs/jobs"},
    "mlflow": {"tracking_uri": "sqlite:////somewhere/outputs/mlflow.db"},
}


def test_sa_logs_the_one_agent_it_ran_and_the_grid_n_as_a_tag() -> None:
    params = job_params(GRID_JOB)
    assert params["agents"] == "1" and params["method.name"] == "sa"
    # SA reads neither the decomposer nor the LLM; nothing about where it ran is a param.
    assert not any(k.startswith(("decomposer.", "llm.", "data.", "output.")) for k in params)
    assert not any(k.startswith(("orchestration.", "mlflow.")) for k in params)
    tags = config_tags(GRID_JOB)
    assert tags["twostep.grid_agents"] == "3" and tags["twostep.data_root"] == "/somewhere/data"
    rest = json.loads(tags["twostep.config"])
    assert rest["score_max_nodes"] == "2000" and "decomposer.cut" not in rest
    # one name everywhere (console, Prefect, MLflow): SA runs N = 1 (the grid's N: a tag)
    assert job_name(GRID_JOB) == "grippers-p01-sa-n1-s0"


def test_twostep_with_the_llm_logs_at_most_15_params_and_no_credentials() -> None:
    config = {**GRID_JOB, "method": {"name": "twostep", "fallback_if_longer": True}}
    params = job_params(config)
    assert len(params) <= 15
    assert params["agents"] == "3" and params["decomposer.name"] == "llm"
    assert params["llm.model"] == "openai/gpt-4o" and params["planner.alias"] == "lama-first"
    rest = json.loads(config_tags(config)["twostep.config"])
    assert rest["decomposer.cut"] == "best" and rest["llm.api_base"] == "https://***@h/v1"
    assert job_name(config) == "grippers-p01-twostep-llm-n3-s0"  # the decomposer named


def test_job_files_layout(tmp_path: Path) -> None:
    result = {
        "plans": {"agent0": ["(pickup a)"], "agent1": ["(pickup b)", "(putdown b)"]},
        "schedule": [
            [["agent0", "(pickup a)"], ["agent1", "(pickup b)"]],
            [["agent1", "(putdown b)"]],
        ],
        "subgoals": [
            {
                "helper": 1,
                "pddl": "(and (on-table b))",
                "status": "accepted",
                "exchanges": [{"step": "generate"}],
            },
            {
                "helper": 2,
                "pddl": None,
                "status": "discarded",
                "reason": "no PDDL",
                "exchanges": [],
            },
        ],
    }
    files = write_job_files(tmp_path, result)
    names = [str(path.relative_to(tmp_path)) for path, _ in files]
    assert names == [
        "plans/agent0.plan",
        "plans/agent1.plan",
        "schedule.txt",
        "subgoals/helper1.pddl",
        "llm/helper1.json",
        "result.json",
    ]
    assert (tmp_path / "plans" / "agent1.plan").read_text() == "(pickup b)\n(putdown b)\n"
    assert json.loads((tmp_path / "llm" / "helper1.json").read_text())["exchanges"] == [
        {"step": "generate"}
    ]


def test_progress_line_counts_and_estimates(tmp_path: Path) -> None:
    state = SweepState(str(tmp_path), time.time() - 30, os.getpid(), total_jobs=4)
    record_job(tmp_path, 0, {"status": "success"})
    record_job(tmp_path, 1, {"status": "failed", "reused": False})
    record_job(tmp_path, 2, {"status": "success", "reused": True})
    record_job(tmp_path, 3, {"status": "timeout"})
    now = state.started_at + 30  # a fixed clock: a busy machine cannot make it 0:31
    state.total_jobs = 5
    line = progress_line(state, now)
    # 2 ok + 1 failed + 1 timed out = the 4 finished: a timeout is counted, apart
    assert line == "[4/5: 2 ok, 1 failed, 1 timed out | 1 reused | 0:30 elapsed, ~0:08 left]"


def test_eta_uses_the_finished_jobs_times_without_the_server_start(tmp_path: Path) -> None:
    """The first job waited 35 s for the server: the throughput so far (50 s for 3 jobs)
    would say ~0:50 for 3 more; the jobs' own times say (5 + 5 + 6) / 3 s per job, twice
    (3 jobs left, 2 at once): 10.7 s."""
    state = SweepState(str(tmp_path), time.time() - 50, os.getpid(), total_jobs=6, parallel=2)
    record_job(tmp_path, 0, {"status": "success", "job_wall_time_s": 40.0, "server_wait_s": 35.0})
    record_job(tmp_path, 1, {"status": "success", "job_wall_time_s": 5.0, "server_wait_s": 0.0})
    record_job(tmp_path, 2, {"status": "success", "job_wall_time_s": 6.0})
    line = progress_line(state, state.started_at + 50)
    assert line == "[3/6: 3 ok, 0 failed, 0 timed out | 0:50 elapsed, ~0:11 left]"


def test_job_store_round_trip(tmp_path: Path) -> None:
    store = JobStore(tmp_path)
    assert store.load("k") is None
    store.save("k", {"task": 1}, {"success": True})
    store.mark_logged("k", "sqlite:///x.db", "exp", "run1")
    assert store.load("k") == {"success": True}
    assert store.logged_to("k") == {"sqlite:///x.db exp": "run1"}
    assert job_config({"hydra": {"a": 1}, "task": 1}) == {"task": 1}


# ----------------------------------------------------------------- the server watchdog


def test_watchdog_stops_its_command_when_the_owner_is_killed(tmp_path: Path) -> None:
    owner = subprocess.Popen(["sleep", "60"])
    pid_file = tmp_path / "child.pid"
    watchdog = subprocess.Popen(
        [sys.executable, "-m", "flows.servers", "--owner", str(owner.pid), "--",
         "sh", "-c", f"echo $$ > {pid_file}; exec sleep 60"],
        start_new_session=True,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 10
        while not pid_file.is_file() or not pid_file.read_text().strip():
            assert time.monotonic() < deadline
            time.sleep(0.05)
        child = int(pid_file.read_text())
        assert pid_alive(child)
        owner.send_signal(signal.SIGKILL)  # the sweep's process dies by kill -9
        owner.wait()
        watchdog.wait(timeout=10)
        deadline = time.monotonic() + 5
        while pid_alive(child) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not pid_alive(child)
    finally:
        for process in (owner, watchdog):
            if process.poll() is None:
                process.kill()
                process.wait()


# ----------------------------------------------------------------- with a Prefect server


class CountingPlanner:
    """Wraps twostep.planner.plan_pddl (what the ``plan`` task calls) to count calls."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        import twostep.planner

        self.calls = 0
        self._real = twostep.planner.plan_pddl
        monkeypatch.setattr(twostep.planner, "plan_pddl", self)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        self.calls += 1
        return self._real(*args, **kwargs)


@pytest.mark.integration
def test_flow_caches_planner_calls_across_runs(
    shared: dict[str, Path], tmp_path: Path, prefect_server: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    planner = CountingPlanner(monkeypatch)
    cfg = job_cfg(
        shared,
        tmp_path,
        "method=twostep",
        "decomposer=goal-split",  # SA, a helper and a main agent: three planner calls
        "task=2",
        "orchestration.prefect=true",
        f"orchestration.prefect_api_url={prefect_server}",
        f"orchestration.result_storage={tmp_path / 'results'}",
        "orchestration.reuse_results=false",  # run the flow again: only the task cache helps
    )
    first = execute_job(cfg, tmp_path / "job1")
    assert first.status == "success", first.error
    assert planner.calls == first.stats.plan_calls == 3
    second = execute_job(cfg, tmp_path / "job2")
    assert (
        second.status == "success" and second.result["exec_length"] == first.result["exec_length"]
    )
    assert planner.calls == 3  # nothing planned again
    assert second.stats.plan_calls == 0 and second.stats.plan_cache_hits == 3
    assert len(mlflow_runs(shared, tmp_path.name)) == 1

    runs = api(prefect_server, "/flow_runs/filter", {"flow_runs": {"name": {"any_": [first.name]}}})
    assert [r["state"]["type"] for r in runs] == ["COMPLETED", "COMPLETED"]
    # Task runs reach the server as events: give its recorder a moment.
    deadline = time.monotonic() + 30
    while True:
        tasks = api(
            prefect_server,
            "/task_runs/filter",
            {"flow_runs": {"id": {"any_": [r["id"] for r in runs]}}},
        )
        names = sorted(  # task runs are named by step, role and agent: "plan helper agent1"
            (t["name"].split(" ")[0], t["state"]["name"]) for t in tasks if t.get("state")
        )
        if names.count(("plan", "Cached")) == 3 or time.monotonic() > deadline:
            break
        time.sleep(0.5)
    assert names.count(("plan", "Completed")) == 3 and names.count(("plan", "Cached")) == 3
    assert ("score", "Completed") in names and ("progress", "Completed") in names


@pytest.mark.integration
def test_two_job_sweep_on_a_local_dask_cluster(
    shared: dict[str, Path], tmp_path: Path, prefect_server: str
) -> None:
    from distributed import Client, LocalCluster

    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster, Client(cluster) as client:  # fmt: skip
        done = subprocess.run(
            [
                str(TWOSTEP), "-m", "method=sa", "domain=blocksworld", "task=1,2",
                f"data.root={shared['data']}", f"output.root={tmp_path}",
                "orchestration.task_runner=dask", f"orchestration.dask_address={cluster.scheduler_address}",
                f"orchestration.prefect_api_url={prefect_server}", "mlflow.enabled=false",
            ],
            capture_output=True, text=True, timeout=300,
        )  # fmt: skip
        assert done.returncode == 0, done.stdout + done.stderr
        executed = client.run(lambda dask_worker: dask_worker.state.executed_count)
    assert "[2/2: 2 ok, 0 failed, 0 timed out" in done.stdout
    (summary_path,) = tmp_path.glob("multiruns/*/*/.twostep/summary.json")
    summary = json.loads(summary_path.read_text())
    assert summary["prefect_flow_runs"] == {"COMPLETED": 2}
    assert summary["planner_calls_run"] == 2
    assert sum(executed.values()) == 2  # both planner calls ran on the cluster's worker
