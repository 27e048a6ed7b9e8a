"""Issue 39, finding 4: a job-store or task-cache entry is used only when it is the job's
own. Each tampering of the reliability probes (rows 89-95) is made on a real store; the
re-run must compute the job again with one warning line, count it in the sweep's summary,
and end with the same results as the untampered sweep (its ``results.csv`` is the
reference: computed before any tampering, by the same command)."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.examples import task_files
from tests.support.data import make_data
from twostep.pddl import load_problem, problem_to_pddl

REPO = Path(__file__).resolve().parent.parent
TWOSTEP = Path(sys.executable).parent / "twostep"


def sweep(data: Path, out: Path, name: str) -> subprocess.CompletedProcess[str]:
    args = ["-m", "domain=blocksworld", "task=1,2,3", "method=sa,twostep", "agents=2",
            f"data.root={data}", f"output.root={out}", "mlflow.enabled=false",
            "orchestration.prefect=false", "planner.time_limit_s=20",
            f"hydra.sweep.dir={out}/multiruns/{name}"]  # fmt: skip
    return subprocess.run(
        [str(TWOSTEP), *args], capture_output=True, text=True, cwd=REPO, timeout=600
    )


def results(out: Path, name: str) -> list[tuple[str, ...]]:
    """results.csv without its timing column: (domain, method, N, jobs, successes, mean
    length) per row."""
    with (out / "multiruns" / name / "results.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    return [
        (r["domain"], r["method"], r["agents"], r["jobs"], r["successes"], r["mean_exec_length"])
        for r in rows
    ]


def entries(out: Path) -> dict[tuple[str, int], Path]:
    """(method, task) -> the entry's folder, read from the config.json beside each result."""
    found = {}
    for folder in (out / "jobs").iterdir():
        if (folder / "config.json").is_file():
            config = json.loads((folder / "config.json").read_text())
            found[(config["method"]["name"], int(config["task"]))] = folder
    return found


@pytest.fixture(scope="module")
def first(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    base = tmp_path_factory.mktemp("store_checks")
    data, out = make_data(base / "data"), base / "out"
    done = sweep(data, out, "first")
    assert done.returncode == 0, done.stderr
    return data, out


def test_a_tampered_job_store_is_computed_again_and_counted(
    first: tuple[Path, Path], tmp_path: Path
) -> None:
    data, original = first
    out = tmp_path / "out"
    shutil.copytree(original, out, symlinks=True)
    entry = entries(out)
    assert len(entry) == 6
    # row 89: an execution length edited
    path = entry["sa", 1] / "result.json"
    result = json.loads(path.read_text())
    path.write_text(json.dumps({**result, "exec_length": 1}))
    # row 90: a success whose status says unsolvable, and no plans
    path = entry["twostep", 1] / "result.json"
    result = json.loads(path.read_text())
    path.write_text(json.dumps({**result, "status": "unsolvable", "plans": None}))
    # row 92: only the six required keys
    path = entry["sa", 2] / "result.json"
    path.write_text(json.dumps({"domain": "blocksworld", "task": 2, "method": "sa",
                                "agents": 1, "success": True, "status": "solved"}))  # fmt: skip
    # row 91: another job's result (and its seal) copied over sa p03's
    for name in ("result.json", "seal.json"):
        shutil.copy(entry["twostep", 3] / name, entry["sa", 3] / name)
    # row 94: twostep p03's folder is a link to twostep p02's
    shutil.rmtree(entry["twostep", 3])
    entry["twostep", 3].symlink_to(entry["twostep", 2])
    kept = (entry["twostep", 2] / "result.json").read_text()

    again = sweep(data, out, "again")
    assert again.returncode == 0, again.stderr
    assert "Traceback" not in again.stderr
    warnings = [line for line in again.stderr.splitlines() if "job store entry" in line]
    assert len(warnings) == 5, again.stderr
    assert all(line.endswith("computing the job again") for line in warnings)
    assert any("symlink" in line and str(entry["twostep", 3]) in line for line in warnings)
    assert any("not this job's" in line and str(entry["sa", 3]) in line for line in warnings)
    assert "1 reused" in again.stdout  # only twostep p02's entry was its own
    assert "job store: 5 stored entries not this job's or not whole" in again.stdout
    assert results(out, "again") == results(original, "first")
    # every job line names its own job
    for method, task in entry:
        assert any(f"blocksworld-p0{task}-{method}" in line for line in again.stdout.splitlines())
    # the entries are whole again; the link is a folder of its own, p02's untouched
    assert not entry["twostep", 3].is_symlink()
    assert (entry["twostep", 2] / "result.json").read_text() == kept
    third = sweep(data, out, "third")
    assert third.returncode == 0, third.stderr
    assert "6 reused" in third.stdout and "job store entry" not in third.stderr
    assert results(out, "third") == results(original, "first")


def test_another_tasks_cache_entry_is_parsed_again(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Row 95: task 2's cache entry copied over task 1's was used as task 1."""
    one, two = tmp_path / "one", tmp_path / "two"
    one.mkdir(), two.mkdir()
    d1, p1 = task_files(one)
    d2, p2 = task_files(two, goal="(on b a)")
    cache = tmp_path / "cache"
    load_problem(d1, p1, cache)
    (entry1,) = cache.glob("*.pickle")
    load_problem(d2, p2, cache)
    (entry2,) = set(cache.glob("*.pickle")) - {entry1}
    entry1.write_bytes(entry2.read_bytes())
    loaded = load_problem(d1, p1, cache)
    assert problem_to_pddl(loaded) == problem_to_pddl(load_problem(d1, p1))
    assert loaded.goal.positive == {("on", "a", "b")}
    err = capsys.readouterr().err
    assert f"warning: task cache entry {entry1} is another task's entry" in err
    # replaced by the task's own: read back silently
    assert load_problem(d1, p1, cache).goal.positive == {("on", "a", "b")}
    assert capsys.readouterr().err == ""
    # an entry edited after the header was written
    data = entry1.read_bytes()
    entry1.write_bytes(data[:-10] + bytes(10))
    assert load_problem(d1, p1, cache).goal.positive == {("on", "a", "b")}
    assert "has changed since it was written" in capsys.readouterr().err
