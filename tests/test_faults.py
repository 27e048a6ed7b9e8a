"""Issue 39, findings 6, 8 and 9: faults of the machine and the terminal while jobs run
(a full disk, a folder that cannot be written mid-sweep, an output root an address cannot
hold, a reader that goes away) are one line each, never a traceback; a sweep still
prints its summary, ends its MLflow parent run and says with its exit code what happened.
Every run goes through the ``twostep`` command as a user starts it."""

from __future__ import annotations

import shutil
import sqlite3
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.data import make_data

REPO = Path(__file__).resolve().parent.parent
TWOSTEP = Path(sys.executable).parent / "twostep"
FAST = ["orchestration.prefect=false", "planner.time_limit_s=20"]


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_data(tmp_path_factory.mktemp("faults") / "data")


def twostep(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(TWOSTEP), *args], capture_output=True, text=True, cwd=REPO, timeout=600
    )


def run_statuses(db: Path) -> list[str]:
    with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as connection:
        return [row[0] for row in connection.execute("select status from runs")]


def test_a_run_directory_that_cannot_be_made_is_one_failed_job_and_the_sweep_ends(
    data: Path, tmp_path: Path
) -> None:
    """Before: Hydra's traceback from its mkdir, the sweep stopped without its summary,
    its MLflow parent run left RUNNING. A regular file where job 1's folder goes makes
    the same fault for every user (permission bits do not stop root)."""
    out, sweep = tmp_path / "out", tmp_path / "sweep"
    sweep.mkdir()
    blocked = sweep / "1_blocksworld_p2_sa_n1_s0"  # job 1's folder (hydra.sweep.subdir)
    blocked.write_text("in the way")
    done = twostep("-m", "task=1,2,3", "method=sa", f"data.root={data}", f"output.root={out}",
                   f"hydra.sweep.dir={sweep}", *FAST)  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr
    assert "Traceback" not in done.stderr, done.stderr
    assert f"error: blocksworld-p02-sa-n1-s0: cannot write {blocked} (File exists)" in (
        done.stderr.splitlines()
    )
    assert "sweep finished: 3/3 jobs: 2 ok, 1 failed" in done.stdout
    assert "1 job(s) could not write their run directory" in done.stdout
    assert len(list((out / "jobs").glob("*/result.json"))) == 2  # the others are stored
    statuses = run_statuses(out / "mlflow.db")
    assert len(statuses) == 3 and "RUNNING" not in statuses  # 2 job runs and the parent


@pytest.mark.parametrize("launcher", [[], ["hydra/launcher=basic"]], ids=["twostep", "basic"])
def test_a_failed_job_whose_record_cannot_be_written_is_still_counted(
    data: Path, tmp_path: Path, launcher: list[str]
) -> None:
    """Before, on the default launcher: a job that met a fault in a worker process and could
    not write its sweep record either (a full disk) was lost from the summary (2/3 jobs, 0
    failed) and the sweep exited 0. Job 1's run folder and its record are both blocked (a
    file and a folder in the way: permission bits do not stop root)."""
    out, sweep = tmp_path / "out", tmp_path / "sweep"
    sweep.mkdir()
    blocked = sweep / "1_blocksworld_p2_sa_n1_s0"
    blocked.write_text("in the way")
    (sweep / ".twostep" / "jobs" / "1.json" / "x").mkdir(parents=True)  # its record
    done = twostep("-m", "task=1,2,3", "method=sa", f"data.root={data}", f"output.root={out}",
                   f"hydra.sweep.dir={sweep}", *launcher, *FAST)  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr
    assert "Traceback" not in done.stderr, done.stderr
    assert f"error: blocksworld-p02-sa-n1-s0: cannot write {blocked} (File exists)" in (
        done.stderr.splitlines()
    )
    assert "sweep finished: 3/3 jobs: 2 ok, 1 failed" in done.stdout, done.stdout
    assert "1 job(s) could not write their run directory" in done.stdout


def test_a_parent_run_left_running_is_ended_by_a_rerun_that_reuses_every_job(
    data: Path, tmp_path: Path
) -> None:
    """Before: a sweep whose parent run could not be ended (the disk filled as it ended)
    left it RUNNING, and a re-run whose jobs were all stored never touched MLflow: it
    stayed RUNNING for good. The run is set RUNNING here through MLflow's client."""
    from mlflow.tracking import MlflowClient

    out = tmp_path / "out"
    args = ["-m", "task=1,3", "method=sa", f"data.root={data}", f"output.root={out}", *FAST]
    assert twostep(*args).returncode == 0
    client = MlflowClient(f"sqlite:///{out / 'mlflow.db'}")
    runs = client.search_runs(
        [e.experiment_id for e in client.search_experiments()],
        filter_string="tags.`twostep.kind` = 'sweep'",
    )
    assert len(runs) == 1
    client.update_run(runs[0].info.run_id, status="RUNNING")
    again = twostep(*args)
    assert again.returncode == 0 and "Traceback" not in again.stderr, again.stderr
    assert "2 reused" in again.stdout
    statuses = run_statuses(out / "mlflow.db")
    assert len(statuses) == 3 and "RUNNING" not in statuses  # 2 job runs and the parent


@pytest.mark.parametrize("folder", ["q?mode=ro", "run#1"])
def test_an_output_root_an_address_cannot_hold_is_one_line(
    data: Path, tmp_path: Path, folder: str
) -> None:
    """Before (`?`): about 100 s of MLflow retries and 40 warning lines, never logged,
    exit 0; (`#`): a stray folder beside it."""
    out, char = tmp_path / folder / "out", "?" if "?" in folder else "#"
    for mode in ([], ["-m"]):
        done = twostep(*mode, "task=1", "method=sa", f"data.root={data}",
                       f"output.root='{out}'", *FAST)  # fmt: skip
        assert done.returncode == 2, done.stdout + done.stderr
        assert done.stderr.splitlines() == [
            f"error: output.root {out} holds '{char}', which "
            "MLflow's address (mlflow.tracking_uri) cannot hold (the address ends there: what "
            "follows is read as options or a fragment); choose a folder without it, or set "
            "mlflow.tracking_uri and mlflow.artifact_location yourself (or mlflow.enabled=false)"
        ]
        assert not (tmp_path / folder).exists() and not list(tmp_path.glob("run*"))
    done = twostep("task=1", "method=sa", f"data.root={data}", f"output.root='{out}'",
                   "mlflow.enabled=false", *FAST)  # fmt: skip
    assert done.returncode == 0, done.stderr  # the folder itself is fine without MLflow


def test_a_closed_stdout_is_no_traceback_and_keeps_the_exit_code(
    data: Path, tmp_path: Path
) -> None:
    """Before: `twostep ... | true` was a BrokenPipeError traceback and exit 1 after the
    job was recorded; a sweep piped to `head -1`, 4 tracebacks."""
    out = tmp_path / "out"
    single = subprocess.Popen(
        [str(TWOSTEP), "task=3", "method=sa", f"data.root={data}", f"output.root={out}", *FAST],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO,
    )  # fmt: skip
    assert single.stdout is not None
    single.stdout.close()  # the reader is gone before the first line
    _, err = single.communicate(timeout=300)
    assert single.returncode == 0 and "Traceback" not in err, err
    assert len(list((out / "jobs").glob("*/result.json"))) == 1
    assert run_statuses(out / "mlflow.db") == ["FINISHED"]
    sweep = subprocess.Popen(
        [str(TWOSTEP), "-m", "task=1,2", "method=sa", f"data.root={data}",
         f"output.root={out}", f"hydra.sweep.dir={tmp_path / 'sweep'}", *FAST],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO,
    )  # fmt: skip
    assert sweep.stdout is not None
    assert sweep.stdout.readline().startswith("sweep: 2 jobs")  # `| head -1`
    sweep.stdout.close()
    _, err = sweep.communicate(timeout=300)
    assert sweep.returncode == 0 and "Traceback" not in err and "Logging error" not in err, err
    assert (tmp_path / "sweep" / ".twostep" / "summary.json").is_file()  # it ended
    assert "RUNNING" not in run_statuses(out / "mlflow.db")


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 5 MB tmpfs (root only: skipped elsewhere)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=5m", "tmpfs", str(disk)],
                             capture_output=True)  # fmt: skip
    if mounted.returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    yield disk
    for _ in range(20):  # a process of the run may still be ending
        if subprocess.run(["umount", str(disk)], capture_output=True).returncode == 0:
            return
        time.sleep(0.5)
    subprocess.run(["umount", "-l", str(disk)], check=True)


@pytest.mark.slow
@pytest.mark.parametrize("launcher", [[], ["hydra/launcher=basic"]], ids=["twostep", "basic"])
def test_a_full_disk_mid_sweep_is_lines_and_a_summary(
    data: Path, small_disk: Path, launcher: list[str]
) -> None:
    """Before: 5-6 tracebacks (SQLAlchemy, `--- Logging error ---`, Hydra's config files),
    exit 1 with no summary, an MLflow job run and the parent left RUNNING; then, on the
    default launcher, the summary lost the jobs that failed in a worker (5/12, exit 0), and
    the report process of the basic launcher's sweep ended in a BrokenPipeError traceback.
    The disk is filled to 440 KB after a first sweep, as in the probe; then a re-run on a
    disk with room finishes every job, with one MLflow run per job."""
    out = small_disk / "out"
    first = twostep("-m", "task=1,2", "method=sa,twostep", "agents=2", f"data.root={data}",
                    f"output.root={out}", *FAST)  # fmt: skip
    assert first.returncode == 0, first.stderr
    free = subprocess.run(["df", "-k", "--output=avail", str(small_disk)], capture_output=True,
                          text=True, check=True).stdout.split()[-1]  # fmt: skip
    filler = small_disk / "filler"
    filler.write_bytes(bytes((int(free) - 440) * 1024))
    args = ["-m", "task=1,2,3", "method=sa,twostep", "agents=2,3", f"data.root={data}",
            f"output.root={out}", *launcher, *FAST]  # fmt: skip
    full = twostep(*args)
    assert "Traceback" not in full.stderr and "Logging error" not in full.stderr, full.stderr
    assert "sweep finished: 12/12 jobs" in full.stdout, full.stdout + full.stderr
    for line in full.stderr.splitlines():  # every line says what it is
        assert line.startswith(("warning: ", "error: ")), line
    failed = [line for line in full.stderr.splitlines() if line.startswith("error: ")]
    # one line per failed job, and the exit code says whether there was one
    assert f"{len(failed)} failed" in full.stdout.split("sweep finished: ")[1].splitlines()[0]
    assert full.returncode == (1 if failed else 0), full.stdout + full.stderr
    filler.unlink()
    again = twostep(*args)
    assert again.returncode == 0, again.stderr
    assert "sweep finished: 12/12 jobs: 12 ok" in again.stdout
    assert "RUNNING" not in run_statuses(out / "mlflow.db")
    with sqlite3.connect(f"file:{out / 'mlflow.db'}?mode=ro", uri=True) as connection:
        runs = connection.execute(
            "select runs.experiment_id, key.value, grid.value from runs"
            " join tags key on key.run_uuid = runs.run_uuid and key.key = 'twostep.job_key'"
            " join tags grid on grid.run_uuid = runs.run_uuid"
            " and grid.key = 'twostep.grid_agents'"
        ).fetchall()
    assert len(runs) == len(set(runs))  # no job logged twice in an experiment
    # the 12-job sweep's experiment (its re-run's too) holds a run for each of its jobs
    assert max(Counter(experiment for experiment, _, _ in runs).values()) == 12


def test_deleted_mlflow_artifacts_are_logged_again_with_a_line(data: Path, tmp_path: Path) -> None:
    """Finding 5. Before: after `rm -rf outputs/mlruns` a re-run said `reused` and the
    runs kept pointing at the deleted files, for good."""
    out = tmp_path / "out"
    args = ["-m", "task=1,3", "method=sa", f"data.root={data}", f"output.root={out}", *FAST]
    assert twostep(*args).returncode == 0
    mlruns = out / "mlruns"
    before = {p.relative_to(mlruns): p.read_bytes() for p in mlruns.rglob("*.plan")}
    files = {p.relative_to(mlruns) for p in mlruns.rglob("*") if p.is_file()}
    assert len(before) == 2  # one plan per job
    shutil.rmtree(mlruns)
    again = twostep(*args)
    assert again.returncode == 0 and "Traceback" not in again.stderr, again.stderr
    gone = [line for line in again.stderr.splitlines() if "files of its MLflow run" in line]
    assert len(gone) == 2 and all(line.startswith("warning: blocksworld-p0") for line in gone)
    after = {p.relative_to(mlruns): p.read_bytes() for p in mlruns.rglob("*.plan")}
    assert after == before  # the same files, where the runs say they are
    restored = {p.relative_to(mlruns) for p in mlruns.rglob("*") if p.is_file()}
    job_files = {p for p in files if "result.json" in p.name or p.suffix in (".plan", ".txt")}
    assert job_files <= restored
    assert len([s for s in run_statuses(out / "mlflow.db")]) == 3  # 2 jobs + 1 parent, still
    third = twostep(*args)
    assert "files of its MLflow run" not in third.stderr  # nothing missing any more
