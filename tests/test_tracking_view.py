"""MLflow is a view of the job store (issue 20, findings 1 and 2): a store that lost runs
is filled again by the next run of the same command, ``twostep-report`` says when it holds
fewer job runs than the sweep's records, and every job has exactly one run, also when
two processes hold the same job at once.

Asserted on what the tracking store holds, read with MLflow's own client (never on how
the runs were written), and on the commands' output.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from hydra import compose, initialize_config_dir

from flows.config import register
from flows.job import execute_job
from flows.tracking.runs import JobRunLog
from tests.support.data import make_data

REPO = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
FAST = ["orchestration.prefect=false", "planner.time_limit_s=20"]
RESTORED = "twostep.restored_from_job_store"


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_data(tmp_path_factory.mktemp("view") / "data")


def command(name: str, *args: str, timeout: float = 240) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(BIN / name), *args], capture_output=True, text=True, cwd=REPO, timeout=timeout
    )


READER = """
import json, sys
from mlflow.tracking import MlflowClient
client = MlflowClient(sys.argv[1])
runs = []
for experiment in client.search_experiments():
    for run in client.search_runs([experiment.experiment_id]):
        if run.data.tags.get("twostep.kind") != "job":
            continue
        found, folders = [], [None]
        while folders:
            for item in client.list_artifacts(run.info.run_id, folders.pop()):
                folders.append(item.path) if item.is_dir else found.append(item.path)
        runs.append({"run_id": run.info.run_id, "params": run.data.params,
                     "metrics": run.data.metrics, "tags": run.data.tags,
                     "artifacts": sorted(found)})
print(json.dumps(runs))
"""


def job_runs(out: Path) -> list[dict[str, Any]]:
    """Every job run (tag twostep.kind=job) in the store: its params, metrics, tags and
    artifacts, read by MLflow's client in a process of its own (MLflow keeps a store's
    connection per process: a store replaced on disk would be read through the old one)."""
    done = subprocess.run(
        [sys.executable, "-c", READER, f"sqlite:///{out}/mlflow.db"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    runs: list[dict[str, Any]] = json.loads(done.stdout.splitlines()[-1])
    return runs


# ----------------------------------------------------------------- finding 1


def test_a_deleted_store_is_filled_again_by_the_next_run(data: Path, tmp_path: Path) -> None:
    """Before: `rm outputs/mlflow.db`, and the re-run printed `reused (job store)`, logged
    nothing and did not even create the store again."""
    out = tmp_path / "out"
    args = ["method=twostep", "decomposer=goal-split", "task=2", f"data.root={data}",
            f"output.root={out}", *FAST]  # fmt: skip
    assert command("twostep", *args).returncode == 0
    (first,) = job_runs(out)
    (out / "mlflow.db").unlink()

    again = command("twostep", *args)
    assert again.returncode == 0 and "reused (job store)" in again.stdout
    (restored,) = job_runs(out)
    assert restored["run_id"] != first["run_id"]  # a new run, in a new store
    assert restored["params"] == first["params"]
    assert restored["metrics"] == first["metrics"]
    assert restored["artifacts"] == first["artifacts"] != []
    assert restored["tags"].pop(RESTORED) == "true"
    same_tags = {k: v for k, v in first["tags"].items() if not k.startswith("mlflow.")}
    assert {k: restored["tags"][k] for k in same_tags} == same_tags

    third = command("twostep", *args)  # the store has it now: nothing logged again
    assert third.returncode == 0
    (still,) = job_runs(out)
    assert still["run_id"] == restored["run_id"]


def test_an_emptied_store_gets_every_job_of_the_sweep_back(data: Path, tmp_path: Path) -> None:
    """Before: a 6-job sweep re-run after truncating the store logged 1 of 6 jobs."""
    out = tmp_path / "out"
    sweep = ["-m", "task=1,2,3", "method=sa", f"data.root={data}", f"output.root={out}", *FAST]
    assert command("twostep", *sweep).returncode == 0
    keys = sorted(r["tags"]["twostep.job_key"] for r in job_runs(out))
    assert len(keys) == 3
    (out / "mlflow.db").write_bytes(b"")  # truncated to nothing

    again = command("twostep", *sweep)
    assert again.returncode == 0, again.stdout + again.stderr
    restored = job_runs(out)
    assert sorted(r["tags"]["twostep.job_key"] for r in restored) == keys
    assert all(r["tags"][RESTORED] == "true" for r in restored)


def test_report_warns_when_the_store_holds_fewer_job_runs_than_the_sweep(
    data: Path, tmp_path: Path
) -> None:
    """Before: `twostep-report --experiment` read 1 run of 6 without a word."""
    from mlflow.tracking import MlflowClient

    out = tmp_path / "out"
    sweep = ["-m", "task=1,3", "method=sa", f"data.root={data}", f"output.root={out}",
             "mlflow.experiment=view", *FAST]  # fmt: skip
    assert command("twostep", *sweep).returncode == 0
    report = ["--experiment", "view", "--tracking-uri", f"sqlite:///{out}/mlflow.db",
              "--out", str(tmp_path / "report"), "--no-log"]  # fmt: skip
    complete = command("twostep-report", *report)
    assert complete.returncode == 0, complete.stderr
    assert "warning" not in complete.stderr

    lost = job_runs(out)[0]
    MlflowClient(f"sqlite:///{out}/mlflow.db").delete_run(lost["run_id"])
    partial = command("twostep-report", *report)
    assert "read 1 job run(s)" in partial.stdout
    warning = [line for line in partial.stderr.splitlines() if "warning" in line]
    assert len(warning) == 1 and "1 job run(s)" in warning[0] and "2 job(s)" in warning[0]

    assert command("twostep", *sweep).returncode == 0  # the same command fills it again
    assert len(job_runs(out)) == 2
    assert "warning" not in command("twostep-report", *report).stderr


# ----------------------------------------------------------------- finding 2


def test_one_run_per_job_when_two_processes_hold_the_job_at_once(
    data: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Before: the second process waited for the first one's computation, then logged the
    job itself while the first was still logging it: two runs for one job when both
    looked for the job's run before either created it (two sweeps at once logged 5 runs
    for 4 jobs). Now the job's lock covers its logging: the second one finds the run
    logged and asks the tracking interface for nothing. The first log is slowed down to
    make the window wide; two threads stand for the two processes (a file lock)."""
    original = JobRunLog.log
    calls: list[float] = []

    def slow_first_log(self: JobRunLog, record: Any) -> str:
        calls.append(time.monotonic())
        if len(calls) == 1:
            time.sleep(2.0)
        return original(self, record)

    monkeypatch.setattr(JobRunLog, "log", slow_first_log)
    register()
    with initialize_config_dir(config_dir=str(REPO / "conf"), version_base="1.3"):
        cfg = compose(
            "config",
            overrides=["method=sa", "task=1", f"data.root={data}",
                       f"output.root={tmp_path / 'out'}", "mlflow.experiment=race", *FAST],
        )  # fmt: skip
    outcomes: list[Any] = []

    def job(folder: str) -> None:
        outcomes.append(execute_job(cfg, tmp_path / folder))

    first = threading.Thread(target=job, args=("a",))
    first.start()
    time.sleep(0.5)  # the second one starts while the first computes
    second = threading.Thread(target=job, args=("b",))
    second.start()
    first.join(timeout=200)
    second.join(timeout=200)
    assert sorted(o.reused for o in outcomes) == [False, True]  # computed once
    assert len(calls) == 1  # logged by one of them only (before: by both, one after the other)
    runs = job_runs(tmp_path / "out")
    assert Counter(r["tags"]["twostep.job_key"] for r in runs) == {outcomes[0].key: 1}
    assert {o.mlflow_run_id for o in outcomes} == {runs[0]["run_id"]}


@pytest.mark.slow
def test_two_identical_sweeps_on_the_services_log_one_run_per_job(
    data: Path, tmp_path: Path
) -> None:
    """Before: two identical sweeps with `twostep-services up` logged 6 job runs for 4
    jobs. Both run their jobs as Prefect flows on the services' server here."""
    out = tmp_path / "out"
    up = command("twostep-services", "up", "--root", str(out))
    try:
        assert up.returncode == 0, up.stderr
        sweep = [str(BIN / "twostep"), "-m", "task=1,2,3", "method=sa", f"data.root={data}",
                 f"output.root={out}", "planner.time_limit_s=20"]  # fmt: skip
        processes = [
            subprocess.Popen(sweep, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for _ in range(2)
        ]
        outputs = [p.communicate(timeout=600) for p in processes]
    finally:
        command("twostep-services", "down", "--root", str(out))
    for process, (stdout, stderr) in zip(processes, outputs, strict=True):
        assert process.returncode == 0, stdout + stderr
        assert "prefect http://127.0.0.1:" in stdout  # the services' server, not one of its own
    keys = Counter(r["tags"]["twostep.job_key"] for r in job_runs(out))
    assert len(keys) == 3 and set(keys.values()) == {1}
