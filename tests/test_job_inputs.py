"""Content-addressed jobs: an edited input file is computed again, an unchanged one reused;
unfinished results (``llm_error``) are never reused; a default single run needs no Prefect."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import DictConfig

from flows import job as runner
from flows.build import Job
from flows.config import register
from flows.job import execute_job
from tests.conftest import blocks_problem
from tests.support.data import make_data

REPO = Path(__file__).resolve().parent.parent
CONF = REPO / "conf"


@pytest.fixture(scope="module", autouse=True)
def hydra_conf() -> Iterator[None]:
    register()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        yield


def job_cfg(data: Path, out: Path, *overrides: str) -> DictConfig:
    return compose(
        "config",
        overrides=[
            f"data.root={data}",
            f"output.root={out}",
            "orchestration.prefect=false",
            "mlflow.enabled=false",
            "domain=blocksworld",
            "method=sa",
            "planner.time_limit_s=20",
            *overrides,
        ],
    )


def test_editing_the_problem_recomputes_and_unchanged_inputs_are_reused(
    tmp_path: Path,
) -> None:
    source = make_data(tmp_path / "source")
    data = tmp_path / "data"
    shutil.copytree(source, data)  # a copied data root: the edit stays in this test
    problem = data / "blocksworld" / "p02.pddl"
    cfg = job_cfg(data, tmp_path / "out", "task=2")

    first = execute_job(cfg, tmp_path / "run1")
    assert first.status == "success" and not first.reused
    # Two towers of three from six blocks on the table: at least 4 pick-ups and 4 stacks.
    assert first.result["exec_length"] >= 8

    # One block on another: pickup a, stack a b (the same config, another problem file).
    problem.write_text(
        blocks_problem(
            " ".join(f"(on-table {b}) (clear {b})" for b in "abcdef") + " (arm-empty)",
            "(on a b)",
            "a b c d e f",
        )
    )
    edited = execute_job(cfg, tmp_path / "run2")
    assert not edited.reused and edited.key != first.key
    assert edited.stats.plan_calls == 1
    assert edited.result["exec_length"] == 2

    again = execute_job(cfg, tmp_path / "run3")
    assert again.reused and again.key == edited.key and again.stats.plan_calls == 0
    assert again.result["exec_length"] == 2


def test_expert_file_is_an_input_of_expert_jobs_only(tmp_path: Path) -> None:
    data = make_data(tmp_path / "data")
    expert = data / "blocksworld" / "expert.yaml"
    expert.write_text("2:\n  1: ['(on a b)']\n")
    out = tmp_path / "out"
    twostep = job_cfg(data, out, "task=2", "method=twostep", "decomposer=expert")
    sa = job_cfg(data, out, "task=2")
    keys = (runner.job_key(runner.job_config(twostep), runner.job_inputs(runner.job_config(twostep))),
            runner.job_key(runner.job_config(sa), runner.job_inputs(runner.job_config(sa))))  # fmt: skip
    expert.write_text("2:\n  1: ['(on d e)']\n")
    after = (runner.job_key(runner.job_config(twostep), runner.job_inputs(runner.job_config(twostep))),
             runner.job_key(runner.job_config(sa), runner.job_inputs(runner.job_config(sa))))  # fmt: skip
    assert keys[0] != after[0]  # the expert job reads the file
    assert keys[1] == after[1]  # SA does not


class LLMFailure:
    """What the library returns when the LLM call failed after its retries."""

    calls = 0

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        LLMFailure.calls += 1
        result = {
            "domain": "blocksworld", "task": 2, "method": "twostep", "agents": 2, "seed": 0,
            "success": False, "status": "llm_error", "message": "RateLimitError after 4 tries",
        }  # fmt: skip

        class Result:
            def to_dict(self) -> dict[str, Any]:
                return dict(result)

        return Result()


def test_llm_error_is_a_failed_job_that_a_rerun_tries_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    data = make_data(tmp_path / "data")
    cfg = job_cfg(data, tmp_path / "out", "task=2", "method=twostep")
    monkeypatch.setattr(Job, "run", LLMFailure())
    LLMFailure.calls = 0
    first = execute_job(cfg, tmp_path / "run1")
    assert first.status == "failed" and "RateLimitError" in str(first.error)
    assert not (tmp_path / "out" / "jobs" / first.key).exists()  # not stored
    second = execute_job(cfg, tmp_path / "run2")
    assert not second.reused and LLMFailure.calls == 2  # tried again
    written = json.loads((tmp_path / "run2" / "result.json").read_text())
    assert written["status"] == "llm_error" and written["success"] is False


def run_reporting_imports(
    argv: list[str], modules: tuple[str, ...]
) -> subprocess.CompletedProcess[str]:
    """The command on ``argv``, printing ``<module> imported: <bool>`` for each of
    ``modules`` just before the single run exits (it ends with os._exit: look first)."""
    script = (
        "import os, sys\n"
        "import flows.cli\n"
        "def report(code):\n"
        f"    for name in {modules!r}:\n"
        "        print(name, 'imported:', name in sys.modules)\n"
        "    sys.stdout.flush()\n"
        "    os._exit(code)\n"
        "flows.cli._fast_exit = report\n"
        "flows.cli.main()\n"
    )
    return subprocess.run(
        [sys.executable, "-c", script, *argv],
        capture_output=True, text=True, cwd=REPO, timeout=240,
    )  # fmt: skip


def test_default_single_run_starts_no_prefect_server(tmp_path: Path) -> None:
    """orchestration.prefect is left at its default (auto) and no services are up."""
    data, out = make_data(tmp_path / "data"), tmp_path / "out"
    argv = [f"data.root={data}", f"output.root={out}", "domain=blocksworld", "task=1"]
    argv += ["method=sa", "mlflow.enabled=false"]
    done = run_reporting_imports(argv, ("prefect", "litellm"))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "blocksworld-p01-sa-n1-s0" in done.stdout and "success" in done.stdout
    assert "prefect imported: False" in done.stdout
    assert "litellm imported: False" in done.stdout
    assert not (out / "prefect").exists()  # no server database was created
    (result,) = out.glob("runs/*/*/result.json")
    assert json.loads(result.read_text())["orchestration"]["prefect"] is False


def test_a_logged_single_run_imports_nothing_of_the_reports(tmp_path: Path) -> None:
    """The run's MLflow record counts the planner calls a time limit stopped; before, that
    count was read from the reports' Table II module, which imported pandas and matplotlib
    (1.2 s, and matplotlib's font cache in a fresh container) on the logged run's path."""
    data, out = make_data(tmp_path / "data"), tmp_path / "out"
    argv = [f"data.root={data}", f"output.root={out}", "domain=blocksworld", "task=1"]
    argv += ["method=sa", "orchestration.prefect=false"]
    heavy = ("pandas", "matplotlib", "twostep.report")
    done = run_reporting_imports(argv, heavy)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "blocksworld-p01-sa-n1-s0" in done.stdout
    for name in heavy:
        assert f"{name} imported: False" in done.stdout
    from mlflow.tracking import MlflowClient  # the run was logged, with the counts

    client = MlflowClient(f"sqlite:///{out}/mlflow.db")
    experiment = client.get_experiment_by_name("twostep")
    assert experiment is not None
    (run,) = client.search_runs([experiment.experiment_id])
    assert run.data.metrics["planner_timeouts"] == 0 == run.data.metrics["planner_guard_stops"]


def test_single_run_logs_to_mlflow_through_its_worker(tmp_path: Path) -> None:
    """The command's MLflow logging runs in a helper process: the run is there when the
    command returns, found again (not duplicated) by a second run that reuses the job."""
    data, out = make_data(tmp_path / "data"), tmp_path / "out"
    argv = [f"data.root={data}", f"output.root={out}", "domain=blocksworld", "task=1"]
    argv += ["method=sa", "orchestration.prefect=false"]
    for _ in range(2):
        done = subprocess.run(
            [sys.executable, "-m", "flows.cli", *argv],
            capture_output=True, text=True, cwd=REPO, timeout=240,
        )  # fmt: skip
        assert done.returncode == 0, done.stdout + done.stderr
        assert "warning" not in done.stderr
    from mlflow.tracking import MlflowClient

    client = MlflowClient(f"sqlite:///{out}/mlflow.db")
    experiment = client.get_experiment_by_name("twostep")
    assert experiment is not None
    (run,) = client.search_runs([experiment.experiment_id])
    results = sorted(out.glob("runs/*/*/result.json"))
    first = json.loads(results[0].read_text())
    assert run.data.tags["twostep.job_key"] == first["job_key"]
    assert run.data.tags["twostep.status"] == "success"
    assert run.data.metrics["exec_length"] == first["exec_length"]
    assert {a.path for a in client.list_artifacts(run.info.run_id)} >= {"result.json"}


def test_an_embodied_jobs_key_holds_its_kitchen(tmp_path: Path) -> None:
    """Issue 39: the floor plan an embodied job reads (its task folder's kitchen.yaml) is
    one of its inputs; a symbolic job, or one on a named scene, does not read it."""
    from flows.store import job_config, job_inputs, job_key

    data = tmp_path / "data"
    shutil.copytree(REPO / "data" / "alfworld", data / "alfworld")
    kitchen = data / "alfworld" / "kitchen.yaml"

    def key(*overrides: str) -> tuple[str, dict[str, str]]:
        config = job_config(job_cfg(data, tmp_path / "out", "domain=alfworld", "task=4",
                                    *overrides))  # fmt: skip
        inputs = job_inputs(config)
        return job_key(config, inputs), inputs

    embodied, inputs = key("executor=embodied")
    symbolic, symbolic_inputs = key("executor=symbolic")
    scene, scene_inputs = key("executor=embodied", "executor.layout=open")
    assert "kitchen" in inputs and "kitchen" not in symbolic_inputs | scene_inputs
    kitchen.write_text(kitchen.read_text().replace("width: 13", "width: 14"))
    assert key("executor=embodied")[0] != embodied  # an edited kitchen is another job
    assert (
        key("executor=symbolic")[0] == symbolic
        and key("executor=embodied", "executor.layout=open")[0] == scene
    )
