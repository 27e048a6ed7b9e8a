"""Failure is failure: plans that do not execute on the kitchen make a failed run.

Two kitchens built here from ``data/alfworld``'s task 1 and a floor plan of our own: one
whose every location is on its one free cell (two agents cannot both stand: ``boxed_in``)
and one with the fridge's cell walled off (the egg is in the fridge: ``unreachable``). MA
with two agents starting on their PDDL start location plans task 1 as usual (the floor
plan plays no part in planning); the execution then fails. Each run goes through the job
(result.json, the job store, the sweep's report) and the command (its exit code), and
what they say is compared with the executor's own verdict, worked out by hand here.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from hydra import compose, initialize_config_dir

from flows.config import register
from flows.job import JobStatus, execute_job
from flows.report_cli import load_runs_from_mlflow
from flows.report_cli import main as report_main
from flows.report_sources import load_runs_from_sweep_dir
from flows.store import JobStore
from tests.support.commands import REPO, run_cli

KITCHEN = REPO / "data" / "alfworld"
FRIDGE_CELL = (1, 2)  # loc-fridge1 in kitchen.yaml


def _kitchen(root: Path, floor: dict[str, Any]) -> Path:
    folder = root / "alfworld"
    folder.mkdir(parents=True)
    for name in ("domain.pddl", "p01.pddl", "titles.yaml"):
        shutil.copy(KITCHEN / name, folder / name)
    (folder / "kitchen.yaml").write_text(yaml.safe_dump(floor))
    return root


def boxed_in_kitchen(root: Path) -> Path:
    """A 3 x 3 room walled all round: one free cell, every location on it."""
    locations = yaml.safe_load((KITCHEN / "kitchen.yaml").read_text())["locations"]
    floor = {
        "name": "one-cell",
        "width": 3,
        "height": 3,
        "walls": [[0, 0, 3, 1], [0, 2, 3, 1], [0, 1, 1, 1], [2, 1, 1, 1]],
        "locations": {name: [1, 1] for name in locations},
    }
    return _kitchen(root, floor)


def walled_off_kitchen(root: Path) -> Path:
    """Our kitchen with the fridge's access cell walled in (its two open sides closed)."""
    floor = yaml.safe_load((KITCHEN / "kitchen.yaml").read_text())
    assert floor["locations"]["loc-fridge1"] == list(FRIDGE_CELL)
    x, y = FRIDGE_CELL
    floor["walls"] += [[x + 1, y, 1, 1], [x, y + 1, 1, 1]]
    floor["name"] = "walled-fridge"
    return _kitchen(root, floor)


KITCHENS = {"boxed_in": boxed_in_kitchen, "unreachable": walled_off_kitchen}
MA_ON_ITS_START = ["task=1", "method=ma", "agents=2", "executor.random_start=false"]


@pytest.fixture(scope="module", autouse=True)
def hydra_conf() -> Iterator[None]:
    register()
    with initialize_config_dir(config_dir=str(REPO / "conf"), version_base="1.3"):
        yield


def _job(data: Path, out: Path, job_dir: Path) -> tuple[Any, dict[str, Any]]:
    cfg = compose("config", overrides=[
        f"data.root={data}", f"output.root={out}", "domain=alfworld", *MA_ON_ITS_START,
        "orchestration.prefect=false", "mlflow.enabled=false", "executor.render=false",
    ])  # fmt: skip
    outcome = execute_job(cfg, job_dir)
    return outcome, json.loads((job_dir / "result.json").read_text())


@pytest.mark.parametrize("kind", sorted(KITCHENS))
def test_a_failed_execution_is_a_failed_run(kind: str, tmp_path: Path) -> None:
    data, out = KITCHENS[kind](tmp_path / "data"), tmp_path / "out"
    outcome, result = _job(data, out, tmp_path / "sweep" / "0")
    # the plans were found: two agents' plans, a symbolic schedule
    assert result["status"] != "error" and len(result["plans"]) == 2
    assert result["exec_length"] is not None
    embodied = result["embodied"]
    assert result["embodied_status"] == embodied["status"] == kind
    if kind == "boxed_in":  # the second body has nowhere to stand, before any step
        assert (embodied["agent"], embodied["step"]) == ("agent1", 0)
    else:  # the first walk to the fridge: the body at the door cannot get there
        assert "cannot be reached" in embodied["reason"]
        assert embodied["step"] >= 1 and embodied["agent"] in result["plans"]
    verdict = f"embodied_failed: {kind} at step {embodied['step']}, {embodied['agent']}"
    assert result["success"] is False and result["status"] == "embodied_failed"
    assert result["message"] == verdict and result["embodied_length"] is None
    assert outcome.status is JobStatus.FAILED and outcome.error == verdict
    # the job store keeps no success: a failure, or nothing
    stored = JobStore(out / "jobs").load(outcome.key)
    assert stored is None or stored["success"] is False
    # reused, it fails again
    again, reread = _job(data, out, tmp_path / "sweep" / "1")
    assert again.status is JobStatus.FAILED and reread["message"] == verdict
    # the report counts both jobs as failed, with no length
    runs = load_runs_from_sweep_dir(tmp_path / "sweep")
    assert list(runs["status"]) == ["failed", "failed"]
    assert list(runs["error"]) == [verdict, verdict]
    assert runs["embodied_length"].isna().all()


def test_the_report_counts_failed_kitchens_as_failures(tmp_path: Path) -> None:
    """``twostep-report --sweep-dir`` on the two kitchens' jobs and one on our own kitchen
    that succeeds: Table II's cell is the successful run's embodied length alone, with
    the two failures counted beside it."""
    sweep = tmp_path / "sweep"
    _, ok = _job(REPO / "data", tmp_path / "out", sweep / "0_ok")
    assert ok["success"] and ok["embodied_length"] is not None
    for number, (kind, build) in enumerate(sorted(KITCHENS.items()), start=1):
        _job(build(tmp_path / kind), tmp_path / "out", sweep / f"{number}_{kind}")
    report = tmp_path / "report"
    assert report_main(["--sweep-dir", str(sweep), "--out", str(report), "--no-log"]) == 0
    status = {r["run_id"]: (r["status"], r["embodied_length"]) for r in _csv(report / "runs.csv")}
    length = float(ok["embodied_length"])
    assert status == {
        "0_ok": ("success", str(length)),
        "1_boxed_in": ("failed", ""),
        "2_unreachable": ("failed", ""),
    }
    table = (report / "report.md").read_text().split("## Embodied execution", 1)[1]
    ma = next(line for line in table.splitlines() if line.startswith("| MA "))
    assert ma.split("|")[3].strip() == f"{length:.1f} (2 failed)"


def _csv(path: Path) -> list[dict[str, str]]:
    import csv

    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.mark.slow  # one process of the command with MLflow: ~20 s
def test_the_command_exits_1_and_mlflow_records_a_failure(tmp_path: Path) -> None:
    data, out = boxed_in_kitchen(tmp_path / "data"), tmp_path / "out"
    proc = run_cli(
        f"data.root={data}", f"output.root={out}", "domain=alfworld", *MA_ON_ITS_START,
        "mlflow.enabled=true",
    )  # fmt: skip
    assert proc.returncode == 1, proc.stderr
    verdict = "embodied_failed: boxed_in at step 0, agent1"
    assert f"FAILED ({verdict})" in proc.stdout
    assert "Traceback" not in proc.stderr
    runs = load_runs_from_mlflow(f"sqlite:///{out / 'mlflow.db'}", "twostep")
    assert list(runs["status"]) == ["failed"] and list(runs["error"]) == [verdict]
    assert runs["embodied_length"].isna().all()
