"""The twostep launcher's parts, against Hydra's own (fast: no server, no planner).

* :class:`flows.compose.SweepComposer` derives most job configs of a sweep from the first
  of their group set: every derived config must equal what Hydra composes for the job
  (Hydra's ``load_sweep_config`` is the oracle), and a job Hydra refuses is refused too.
* :func:`flows.run_job.run_job` copies less than Hydra's ``run_job``: the task function
  must get the same config, see the same ``HydraConfig``, and the job directory must hold
  the same ``.hydra`` files (credentials inside URLs masked, as the sweep callback masks
  what Hydra writes).
* the job records' reader, the sweep's timing line, the worker count.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hydra.core.global_hydra import GlobalHydra
from hydra.core.hydra_config import HydraConfig
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.utils import JobStatus, setup_globals
from hydra.core.utils import run_job as hydra_run_job
from hydra.errors import ConfigCompositionException
from hydra.types import HydraContext, RunMode
from omegaconf import DictConfig, OmegaConf, open_dict

from flows.compose import SweepComposer
from flows.config import register
from flows.launcher import register_plugins, worker_count
from flows.run_job import run_job
from flows.sweep_callback import mask_credentials
from flows.sweep_state import job_records, record_job
from flows.sweep_timing import sweep_timing, timing_line

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def loader() -> Iterator[Any]:
    from hydra import initialize_config_dir

    register()
    register_plugins()
    with initialize_config_dir(config_dir=str(REPO / "conf"), version_base="1.3"):
        yield GlobalHydra.instance().config_loader()


def master(loader: Any, overrides: list[str], tmp_path: Path) -> DictConfig:
    setup_globals()
    config = loader.load_configuration(
        "config", [*overrides, f"output.root={tmp_path}"], RunMode.MULTIRUN
    )
    HydraConfig.instance().set_config(config)
    return config


def grid(command: list[str], params: dict[str, str] | None = None) -> list[list[str]]:
    """The jobs of a command line, as Hydra's basic sweeper lists them."""
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

    arguments = [f"{k}={v}" for k, v in (params or {}).items()] + command
    parsed = OverridesParser.create().parse_overrides(arguments)
    (batch,) = BasicSweeper.split_arguments(parsed, None)
    return batch


def plain(config: DictConfig) -> Any:
    return OmegaConf.to_container(config, resolve=False, enum_to_str=True)


# ----------------------------------------------------------------- composition


COMMANDS = [
    # values only, after one group set
    ["domain=blocksworld", "method=sa", "task=1,2,3", "seed=0,1"],
    # group sets crossed with values; an experiment's own grid; a value of a nested key
    ["domain=blocksworld,grippers", "method=sa,twostep", "task=1,2", "agents=2,3"],
    ["experiment=smoke", "planner.time_limit_s=7,9"],
    # overrides the shortcut leaves to Hydra: a dict value, an added key, a group option
    ["domain=grippers", "task=1,2", "llm={model:x,temperature:0.5}"],
    ["task=1,2", "+orchestration.extra=1,2", "decomposer=goal-split,expert"],
]


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: " ".join(c))
def test_every_derived_job_config_is_the_one_hydra_composes(
    loader: Any, command: list[str], tmp_path: Path
) -> None:
    experiment = [c for c in command if c.startswith("experiment=")]
    config = master(loader, command, tmp_path)
    params = dict(config.hydra.sweeper.params or {}) if experiment else None
    jobs = grid(command, params)
    composer = SweepComposer(loader)
    for overrides in jobs:  # the sweeper's check first, as in a sweep
        composer.validate(config, overrides)
    for overrides in jobs:
        expected = loader.load_sweep_config(config, overrides)
        assert plain(composer.compose(config, overrides)) == plain(expected), overrides
    if "llm={model:x,temperature:0.5}" not in command and "+orchestration.extra=1,2" not in command:
        assert composer.derived >= len(jobs) - 2 * composer.full  # the shortcut was taken
    # a worker gets the composer once, with the configs composed while validating
    worker = SweepComposer.__new__(SweepComposer)
    worker.__setstate__(composer.__getstate__())
    for overrides in jobs:
        assert plain(worker.compose(config, overrides)) == plain(
            loader.load_sweep_config(config, overrides)
        )


def test_a_job_hydra_refuses_is_refused(loader: Any, tmp_path: Path) -> None:
    config = master(loader, ["task=1,2"], tmp_path)
    composer = SweepComposer(loader)
    composer.validate(config, ["task=1"])
    composer.validate(config, ["task=2"])
    for bad in (["task=many"], ["tsak=1"]):
        with pytest.raises(ConfigCompositionException):
            loader.load_sweep_config(config, bad)
        with pytest.raises(ConfigCompositionException):
            composer.validate(config, bad)


# ----------------------------------------------------------------- run_job


def job_config(loader: Any, tmp_path: Path, sweep_dir: Path, num: int) -> DictConfig:
    secret = "https://user:hunter2@example.org/v1"
    config = master(
        loader,
        ["task=1,2", f"hydra.sweep.dir={sweep_dir}", f"llm.api_base={secret}"],
        tmp_path,
    )
    job = loader.load_sweep_config(config, ["task=2", "method=sa"])
    with open_dict(job):
        job.hydra.job.id = num
        job.hydra.job.num = num
    return job


def test_run_job_gives_the_task_and_the_job_directory_what_hydras_run_job_gives(
    loader: Any, tmp_path: Path
) -> None:
    seen: dict[str, Any] = {}

    def task(cfg: DictConfig) -> str:
        hydra = HydraConfig.get()
        seen[hydra.runtime.output_dir] = {
            "task": plain(cfg),
            "hydra": OmegaConf.to_container(hydra, resolve=False),
            "cwd": os.getcwd(),
            "output_root": cfg.output.root,  # resolved through ${hydra:runtime.cwd}
        }
        return "done"

    from hydra._internal.callbacks import Callbacks

    returns = {}
    for name, runner in (("hydra", hydra_run_job), ("ours", run_job)):
        config = job_config(loader, tmp_path / name, tmp_path / name / "sweep", 3)
        context = HydraContext(config_loader=loader, callbacks=Callbacks())
        returns[name] = runner(
            hydra_context=context,
            task_function=task,
            config=config,
            job_dir_key="hydra.sweep.dir",
            job_subdir_key="hydra.sweep.subdir",
        )
    job_dirs = {name: Path(r.hydra_cfg.hydra.runtime.output_dir) for name, r in returns.items()}
    assert job_dirs["ours"] == tmp_path / "ours" / "sweep" / "3_blocksworld_p2_sa_n1_s0"
    for ret in returns.values():
        assert ret.status is JobStatus.COMPLETED and ret.return_value == "done"
        assert ret.overrides == ["task=2", "method=sa"]
    # Hydra's files, masked as the sweep callback masks them, against ours
    hydra_files = [job_dirs["hydra"] / ".hydra" / n for n in ("config.yaml", "hydra.yaml", "overrides.yaml")]  # fmt: skip
    mask_credentials(hydra_files)
    for path in hydra_files:
        ours = (job_dirs["ours"] / ".hydra" / path.name).read_text()
        assert "hunter2" not in ours
        assert ours == path.read_text().replace(str(tmp_path / "hydra"), str(tmp_path / "ours"))
    seen_hydra, seen_ours = seen[str(job_dirs["hydra"])], seen[str(job_dirs["ours"])]
    assert json.dumps(seen_ours, sort_keys=True) == json.dumps(seen_hydra, sort_keys=True).replace(
        str(tmp_path / "hydra"), str(tmp_path / "ours")
    )


def test_run_job_records_a_task_that_raises_as_hydra_does(loader: Any, tmp_path: Path) -> None:
    from hydra._internal.callbacks import Callbacks

    def task(cfg: DictConfig) -> None:
        raise ValueError("no plan")

    config = job_config(loader, tmp_path, tmp_path / "sweep", 0)
    ret = run_job(HydraContext(loader, Callbacks()), task, config)
    assert ret.status is JobStatus.FAILED and isinstance(ret._return_value, ValueError)
    assert (Path(ret.hydra_cfg.hydra.runtime.output_dir) / ".hydra" / "hydra.yaml").is_file()


# ----------------------------------------------------------------- records, timing, workers


def test_job_records_reads_new_and_rewritten_records(tmp_path: Path) -> None:
    record_job(tmp_path, 0, {"num": 0, "status": "success"})
    assert [r["status"] for r in job_records(tmp_path)] == ["success"]
    record_job(tmp_path, 1, {"num": 1, "status": "failed"})
    time.sleep(0.01)
    record_job(tmp_path, 0, {"num": 0, "status": "timeout", "reused": True})  # rewritten
    assert [(r["num"], r["status"]) for r in job_records(tmp_path)] == [
        (0, "timeout"),
        (1, "failed"),
    ]


def test_the_timing_line_of_a_sweep() -> None:
    # 2 workers for 10 s = 20 s of workers' time; 6 s planner + 2 s LLM: 12 s beyond, 3 jobs
    records = [
        {"planner_wall_s": 1.0, "llm_wall_s": 2.0, "launch": {"worker": 11}},
        {"planner_wall_s": 2.0, "llm_wall_s": 0.0, "launch": {"worker": 12}},
        {"planner_wall_s": 3.0, "launch": {"worker": 11}},
    ]
    timing = sweep_timing(records, 10.0)["timing"]
    assert timing["workers"] == 2 and timing["planner_s"] == 6.0 and timing["llm_s"] == 2.0
    assert timing["beyond_per_job_s"] == 4.0 and timing["overhead_share"] == 0.6
    assert timing_line({"timing": timing}) == (
        "time: 0:10 wall, 2 workers | planner 6.0 s, LLM 2.0 s over 3 jobs"
        " | beyond them 4.00 s per job (60 % of the workers' time)"
    )


def test_worker_count() -> None:
    cores = len(os.sched_getaffinity(0))
    assert worker_count(None) == cores and worker_count(0) == cores
    assert worker_count(1) == 1 and worker_count(3) == 3
    assert worker_count(-1) == cores and worker_count(-cores - 5) == 1
    assert worker_count(8, jobs=2) == 2 and worker_count(None, jobs=1) == 1


def test_the_estimate_leaves_out_a_workers_first_job_once_a_later_one_finished(
    tmp_path: Path,
) -> None:
    """A worker's first job also paid its process's start (25 s here): with a later job of
    2 s finished, 4 jobs left on 2 workers are 2 x 2 s, not 2 x 13.5 s."""
    from flows.console import progress_line
    from flows.sweep_state import SweepState

    state = SweepState(str(tmp_path), time.time() - 30, os.getpid(), total_jobs=6, parallel=2)
    first = {"status": "success", "job_wall_time_s": 25.0, "launch": {"worker": 1, "worker_job": 0}}
    record_job(tmp_path, 0, first)
    assert progress_line(state, state.started_at + 30).endswith("~1:15 left]")  # 3 x 25 s
    record_job(tmp_path, 1, {**first, "launch": {"worker": 2, "worker_job": 0}})
    later = {"status": "success", "job_wall_time_s": 2.0, "launch": {"worker": 1, "worker_job": 1}}
    record_job(tmp_path, 2, later)
    assert (
        progress_line(state, state.started_at + 30)
        == "[3/6: 3 ok, 0 failed, 0 timed out | 0:30 elapsed, ~0:04 left]"
    )
