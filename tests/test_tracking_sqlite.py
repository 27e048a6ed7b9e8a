"""flows/tracking/sqlite.py: a single run's rows written directly equal MLflow's own.

The reference is MLflow: the same record is logged once through
:func:`flows.tracking.client.log_job_run` (MLflow's client and SQLAlchemy store) and once through
:class:`flows.tracking.sqlite.SqliteJobLog`, into the same store; every row of the run
(runs, tags, params, metrics, latest_metrics) and every artifact file must be the same,
apart from the run id, the job key and the clock.
"""

from __future__ import annotations

import math
import shutil
import sqlite3
from pathlib import Path
from typing import Any

import pytest

from flows.tracking import template as store_template
from flows.tracking.client import Tracker, log_job_run
from flows.tracking.sqlite import SqliteJobLog
from flows.tracking.template import SCHEMA_VERSION, make_template, seed_store

EXPERIMENT = "twostep"


@pytest.fixture(scope="module")
def store(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A store and experiment created by MLflow (seconds: shared by the module), not a copy
    of the environment's template: it is the reference the copies are compared with."""
    base = tmp_path_factory.mktemp("light")
    uri = f"sqlite:///{base / 'mlflow.db'}"
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(store_template, "template_path", lambda: base / "no-template.db")
        tracker = Tracker(uri, str(base / "mlruns"))
        experiment_id = tracker.experiment_id(EXPERIMENT)
    files = base / "job"
    (files / "plans").mkdir(parents=True)
    (files / "result.json").write_text('{"success": true}')
    (files / "plans" / "agent0.plan").write_text("(pickup a)\n(stack a b)\n")
    return {"base": base, "uri": uri, "tracker": tracker, "experiment_id": experiment_id}


def record(key: str, base: Path, **changes: Any) -> dict[str, Any]:
    files = base / "job"
    data: dict[str, Any] = {
        "key": key,
        "name": "blocksworld-p02-twostep-n2-s0",
        "status": "failed",
        "error": "something: went wrong",
        "reused": False,
        "scripted": True,
        "params": {"domain.name": "blocksworld", "task": "2", "llm.api_key_env": "X"},
        "metrics": {
            "success": 0.0,
            "exec_length": 7.0,
            "planner_time_s": [0.5, 0.25, 0.5],  # one point per step; a repeated value
            "weird": float("nan"),
            "huge": float("inf"),
            "job_wall_time_s": 1.25,
        },
        "files": [[str(files / "result.json"), None], [str(files / "plans/agent0.plan"), "plans"]],
    }
    data.update(changes)
    return data


def run_rows(db_path: Path, run_id: str) -> dict[str, Any]:
    """Everything the store holds about a run, without its id, job key and times."""
    with sqlite3.connect(db_path) as db:
        (run,) = db.execute(
            "SELECT name, source_type, source_name, entry_point_name, user_id, status,"
            " end_time IS NULL, source_version, lifecycle_stage, artifact_uri, experiment_id,"
            " deleted_time FROM runs WHERE run_uuid = ?",
            (run_id,),
        ).fetchall()
        tags = db.execute(
            "SELECT key, value FROM tags WHERE run_uuid = ? AND key != 'twostep.job_key'",
            (run_id,),
        ).fetchall()
        params = db.execute("SELECT key, value FROM params WHERE run_uuid = ?", (run_id,))
        metrics = db.execute(
            "SELECT key, value, step, is_nan FROM metrics WHERE run_uuid = ?", (run_id,)
        ).fetchall()
        latest = db.execute(
            "SELECT key, value, step, is_nan FROM latest_metrics WHERE run_uuid = ?", (run_id,)
        ).fetchall()
        return {
            "run": tuple(str(v).replace(run_id, "<id>") for v in run),
            "tags": sorted(tags),
            "params": sorted(params.fetchall()),
            "metrics": sorted(metrics),
            "latest": sorted(latest),
        }


def artifact_files(store: dict[str, Any], run_id: str) -> dict[str, tuple[str, float]]:
    run = store["tracker"].client.get_run(run_id)
    root = Path(run.info.artifact_uri.removeprefix("file://"))
    return {
        str(p.relative_to(root)): (p.read_text(), p.stat().st_mtime)
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def test_a_store_mlflow_created_has_the_schema_this_module_writes(
    store: dict[str, Any],
) -> None:
    with sqlite3.connect(store["base"] / "mlflow.db") as db:
        assert db.execute("SELECT version_num FROM alembic_version").fetchall() == [
            (SCHEMA_VERSION,)
        ]
    light = SqliteJobLog.open(store["uri"], EXPERIMENT)
    assert light is not None and str(light.experiment_id) == store["experiment_id"]


@pytest.mark.parametrize("status", ["failed", "success"])
def test_the_rows_and_files_are_those_mlflow_writes(store: dict[str, Any], status: str) -> None:
    base, tracker = store["base"], store["tracker"]
    error = "something: went wrong" if status == "failed" else None
    by_mlflow = log_job_run(
        tracker,
        store["experiment_id"],
        None,
        record(f"m-{status}", base, status=status, error=error),
    )
    light = SqliteJobLog.open(store["uri"], EXPERIMENT)
    assert light is not None
    direct = light.log(record(f"d-{status}", base, status=status, error=error))
    assert direct is not None and direct != by_mlflow
    expected, got = run_rows(base / "mlflow.db", by_mlflow), run_rows(base / "mlflow.db", direct)
    assert got == expected
    assert ("twostep.status", status) in got["tags"]
    assert ("planner_time_s", 0.25, 1, 0) in got["metrics"]  # steps kept
    assert artifact_files(store, direct) == artifact_files(store, by_mlflow)
    # MLflow reads the run back as it reads its own.
    mine = tracker.client.get_run(direct).data
    theirs = tracker.client.get_run(by_mlflow).data
    assert mine.params == theirs.params and mine.tags.keys() == theirs.tags.keys()
    assert mine.metrics.keys() == theirs.metrics.keys()
    assert math.isnan(mine.metrics["weird"]) and mine.metrics["huge"] == theirs.metrics["huge"]
    # Found again by job key (as Tracker.find_run finds it), not duplicated.
    assert tracker.find_run(store["experiment_id"], "twostep.job_key", f"d-{status}") is not None


def test_a_complete_run_is_left_alone_and_an_incomplete_one_goes_to_mlflow(
    store: dict[str, Any],
) -> None:
    base = store["base"]
    light = SqliteJobLog.open(store["uri"], EXPERIMENT)
    assert light is not None
    done = light.log(record("again", base, status="success", error=None))
    assert done is not None
    before = run_rows(base / "mlflow.db", done)
    assert light.log(record("again", base, status="success", error=None)) == done
    assert run_rows(base / "mlflow.db", done) == before  # no second metric point
    failed = light.log(record("retry", base))
    assert failed is not None
    assert light.log(record("retry", base)) is None  # MLflow logs into it again


def test_what_mlflow_must_handle_is_left_to_it(store: dict[str, Any], tmp_path: Path) -> None:
    base = store["base"]
    light = SqliteJobLog.open(store["uri"], EXPERIMENT)
    assert light is not None
    with sqlite3.connect(base / "mlflow.db") as db:
        count = db.execute("SELECT count(*) FROM runs").fetchone()
    bad_key = record("bad", base, params={"a/../b": "1"})  # MLflow rejects such a name
    assert light.log(bad_key) is None
    assert light.log(record("long", base, params={"p": "x" * 6001})) is None
    assert light.log(record("gone", base, files=[[str(tmp_path / "missing"), None]])) is None
    with sqlite3.connect(base / "mlflow.db") as db:
        assert db.execute("SELECT count(*) FROM runs").fetchone() == count  # nothing written
    assert SqliteJobLog.open(store["uri"], "no such experiment") is None
    assert SqliteJobLog.open(f"sqlite:///{tmp_path / 'none.db'}", EXPERIMENT) is None
    assert SqliteJobLog.open("http://127.0.0.1:9", EXPERIMENT) is None
    other = tmp_path / "other.db"
    shutil.copy(base / "mlflow.db", other)
    with sqlite3.connect(other) as db:
        db.execute("UPDATE alembic_version SET version_num = 'somethingelse'")
    assert SqliteJobLog.open(f"sqlite:///{other}", EXPERIMENT) is None


@pytest.fixture(scope="module")
def template(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An empty store made by MLflow as `make setup` makes it (seconds: once per module)."""
    return make_template(tmp_path_factory.mktemp("template") / "template.db")


def schema(db_path: Path) -> list[tuple[str, list[str]]]:
    """Every table and index; a statement's lines sorted, since MLflow's own migrations
    write a table's CHECK constraints in varying order from one store to the next."""
    with sqlite3.connect(db_path) as db:
        rows = db.execute("SELECT name, sql FROM sqlite_master WHERE sql IS NOT NULL")
        return sorted((name, sorted(sql.splitlines())) for name, sql in rows)


def test_a_seeded_store_is_the_store_mlflow_creates(
    store: dict[str, Any], template: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(store_template, "template_path", lambda: template)
    monkeypatch.chdir(tmp_path)
    seeded = tmp_path / "out" / "mlflow.db"
    assert seed_store(seeded)
    assert schema(seeded) == schema(store["base"] / "mlflow.db")  # tables, indexes, version
    with sqlite3.connect(seeded) as db:
        assert db.execute("SELECT version_num FROM alembic_version").fetchall() == [
            (SCHEMA_VERSION,)
        ]
        (default,) = db.execute(
            "SELECT name, artifact_location, lifecycle_stage FROM experiments"
        ).fetchall()
    # MLflow gives the Default experiment mlruns/0 under the working directory
    assert default == ("Default", str(tmp_path / "mlruns" / "0"), "active")
    before = seeded.stat().st_ino
    assert seed_store(seeded) and seeded.stat().st_ino == before  # never over a store


def test_the_experiment_is_added_as_mlflow_adds_it(
    store: dict[str, Any], template: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(store_template, "template_path", lambda: template)
    base = tmp_path / "out"
    uri = f"sqlite:///{base / 'mlflow.db'}"
    light = SqliteJobLog.open(uri, EXPERIMENT, str(base / "mlruns"))  # seeds, then adds
    assert light is not None

    def experiment(db_path: Path, root: Path) -> tuple[Any, ...]:
        with sqlite3.connect(db_path) as db:
            (row,) = db.execute(
                "SELECT experiment_id, name, artifact_location, lifecycle_stage, workspace,"
                " creation_time = last_update_time FROM experiments WHERE name = ?",
                (EXPERIMENT,),
            ).fetchall()
            tags = db.execute("SELECT * FROM experiment_tags").fetchall()
        return (*row[:2], row[2].replace(root.as_uri(), "<root>"), *row[3:], tags)

    assert experiment(base / "mlflow.db", base) == experiment(
        store["base"] / "mlflow.db", store["base"]
    )
    # MLflow reads the store, the experiment and a run logged into it as its own
    run_id = light.log(record("seeded", store["base"], status="success", error=None))
    assert run_id is not None
    client = Tracker(uri).client
    found = client.get_experiment_by_name(EXPERIMENT)
    assert found is not None and str(found.experiment_id) == str(light.experiment_id)
    assert client.get_run(run_id).info.status == "FINISHED"
    # without a local artifact root the experiment is left to MLflow
    assert SqliteJobLog.open(uri, "another", None) is None
