"""conf/ and flows/config.py: the config tree composes, typos fail, experiments expand.

Composed with Hydra's compose API (no process, no planner): fast.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from hydra.errors import ConfigCompositionException
from omegaconf import DictConfig, OmegaConf

from flows.config import TaskRunner, register
from flows.sweep_state import count_jobs, sweep_overrides

CONF = Path(__file__).resolve().parent.parent / "conf"
PLACES = ["output.root=/tmp/twostep-out", "data.root=/tmp/twostep-data"]


@pytest.fixture(scope="module", autouse=True)
def hydra_conf() -> Iterator[None]:
    register()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        yield


def make(*overrides: str, hydra: bool = False) -> DictConfig:
    return compose("config", overrides=[*PLACES, *overrides], return_hydra_config=hydra)


def test_defaults() -> None:
    cfg = make()
    # issue 11: the offline method that wins the methods bench is the default; issue 40:
    # composed by its name, plan-deal, recorded as before (method twostep, decomposer
    # plan-deal: the same job key and name).
    from flows.store import job_config

    assert (cfg.domain.name, cfg.method.name, cfg.decomposer.name) == (
        "blocksworld",
        "plan-deal",
        None,
    )
    config = job_config(cfg)
    assert (config["domain"]["name"], config["method"]["name"], config["decomposer"]["name"]) == (
        "blocksworld",
        "twostep",
        "plan-deal",
    )
    assert cfg.planner.alias == "lama-first" and cfg.task == 5 and cfg.agents == 2
    assert cfg.domain.agent_predicates == ["arm-empty", "holding"]
    # Everything lives under output.root unless configured otherwise.
    assert cfg.mlflow.tracking_uri == "sqlite:////tmp/twostep-out/mlflow.db"
    assert cfg.mlflow.artifact_location == "/tmp/twostep-out/mlruns"
    assert cfg.orchestration.prefect_home == "/tmp/twostep-out/prefect"
    assert cfg.orchestration.result_storage == "/tmp/twostep-out/prefect/results"
    assert cfg.orchestration.job_store == "/tmp/twostep-out/jobs"
    assert cfg.orchestration.task_runner == TaskRunner.default
    # Prefect "auto" (null): sweeps use it, a single run only when a server is up.
    assert cfg.orchestration.prefect is None and cfg.mlflow.enabled is True


def test_overrides_reach_their_keys() -> None:
    cfg = make(
        "method=ma",
        "agents=3",
        "domain=grippers",
        "task=7",
        "planner=lama",
        "orchestration.task_runner=dask",
        "orchestration.dask_address=tcp://10.0.0.1:8786",
        "mlflow.tracking_uri=http://127.0.0.1:5000",
    )
    assert (cfg.method.name, cfg.agents, cfg.task) == ("ma", 3, 7)
    assert cfg.domain.agent_predicates == ["at-robby", "free", "carry"]
    assert (cfg.planner.alias, cfg.planner.time_limit_s) == ("lama", 1000)
    assert cfg.orchestration.task_runner == "dask"
    assert cfg.orchestration.dask_address == "tcp://10.0.0.1:8786"
    assert cfg.mlflow.tracking_uri == "http://127.0.0.1:5000"


@pytest.mark.parametrize(
    "override, named",
    [
        ("tsak=3", "tsak"),
        ("orchestration.task_runer=dask", "task_runer"),
        ("mlflow.trackinguri=sqlite:///x.db", "trackinguri"),
        ("planner.time_limit=5", "time_limit"),
    ],
)
def test_unknown_key_fails_at_once(override: str, named: str) -> None:
    with pytest.raises(ConfigCompositionException) as info:
        make(override)
    assert named in str(info.value)


@pytest.mark.parametrize(
    "override, named",
    [
        ("agents=two", "agents"),
        ("orchestration.task_runner=spark", "task_runner"),
        ("orchestration.prefect=maybe", "prefect"),
    ],
)
def test_wrong_type_fails_at_once(override: str, named: str) -> None:
    with pytest.raises(ConfigCompositionException) as info:
        make(override)
    text = str(info.value) + str(info.value.__cause__)
    assert named in text


def test_unknown_group_option_names_the_choices() -> None:
    with pytest.raises(Exception) as info:
        make("method=twostepp")
    assert "twostep" in str(info.value) and "sa" in str(info.value)


def test_paper_experiment_expands_to_the_grid() -> None:
    cfg = make("experiment=paper", hydra=True)
    params = cfg.hydra.sweeper.params
    assert params.domain.split(",") == ["barman", "blocksworld", "termes", "tyreworld", "grippers"]
    assert params.task == "range(1,21)"
    assert (
        params.agents == "1,2,3,4" and params.method == "sa,ma,twostep" and params.seed == "0,1,2"
    )
    assert (cfg.planner.alias, cfg.planner.time_limit_s) == ("lama", 1000)
    assert cfg.decomposer.name == "llm"
    assert count_jobs(cfg) == 5 * 20 * 4 * 3 * 3
    assert sweep_overrides(cfg) == ["data.root=/tmp/twostep-data", "experiment=paper"]


def test_smoke_experiment_is_small_and_offline() -> None:
    cfg = make("experiment=smoke", hydra=True)
    assert count_jobs(cfg) == 12
    assert cfg.decomposer.name == "goal-split" and cfg.planner.alias == "lama-first"


def test_command_line_sweep_is_counted_and_named() -> None:
    # compose() refuses sweep syntax: give the callback what a multirun gives it.
    task = ["domain=blocksworld,grippers", "task=1,2", "agents=2", "orchestration.progress=false"]
    cfg = OmegaConf.create({"hydra": {"sweeper": {"params": None}, "overrides": {"task": task}}})
    assert count_jobs(cfg) == 4
    # Where and how a sweep runs is not part of its name.
    assert sweep_overrides(cfg) == ["agents=2", "domain=blocksworld,grippers", "task=1,2"]


@pytest.mark.parametrize(
    "launcher, target",
    [
        ("basic", "BasicLauncher"),
        ("joblib", "JoblibLauncher"),
        ("submitit_local", "LocalLauncher"),
        ("submitit_slurm", "SlurmLauncher"),
        ("slurm", "SlurmLauncher"),
    ],
)
def test_launchers_compose(launcher: str, target: str) -> None:
    cfg = make(f"hydra/launcher={launcher}", hydra=True)
    assert cfg.hydra.launcher._target_.endswith(target)


def test_slurm_launcher_settings() -> None:
    launcher = make("hydra/launcher=slurm", hydra=True).hydra.launcher
    assert launcher.timeout_min == 90 and launcher.cpus_per_task == 2 and launcher.mem_gb == 8
    assert launcher.array_parallelism == 64 and launcher.max_num_timeout == 0


def test_sweep_callback_is_configured() -> None:
    cfg = make(hydra=True)
    callback = OmegaConf.to_container(cfg.hydra.callbacks.twostep)
    assert callback == {"_target_": "flows.sweep_callback.SweepCallback"}


def test_every_registered_decomposer_has_a_config_and_composes() -> None:
    # conf/decomposer/<name>.yaml for each name the registry runs (portfolio-lite included),
    # and each composes with its own name; nothing in conf/decomposer that the registry
    # does not know.
    from flows.checks import value_problems
    from twostep.methods.registry import DECOMPOSERS, method_for

    files = {p.stem for p in (CONF / "decomposer").glob("*.yaml")}
    assert files == set(DECOMPOSERS)
    for name in DECOMPOSERS:
        cfg = make("method=twostep", f"decomposer={name}")
        assert cfg.decomposer.name == name and not value_problems(cfg), name
        assert callable(method_for("twostep", name)), name


@pytest.mark.parametrize(
    ("method", "agents", "named"),
    [("sa", 3, "_sa_n1"), ("sa", 1, "_sa_n1"), ("ma", 3, "_ma_n3"), ("twostep", 2, "_twostep_n2")],
)
def test_run_and_sweep_directories_name_the_agents_the_job_runs(
    method: str, agents: int, named: str
) -> None:
    # SA plans for one agent whatever ``agents`` says: its directories say n1, as the
    # sweep's job records do; the other methods run the N they are given.
    overrides = (f"method={method}", f"agents={agents}", "domain=grippers", "task=7")
    cfg = make(*overrides, "hydra.job.num=4", hydra=True)
    assert cfg.hydra.run.dir.endswith(f"_grippers_p7{named}")
    assert cfg.hydra.sweep.subdir == f"4_grippers_p7{named}_s0"


@pytest.mark.parametrize("switch", ["rebind", "owner_search"])
def test_plan_deal_switches_reach_the_method(switch: str, data_root: Path) -> None:
    # conf/decomposer/plan-deal.yaml turns both on; an override turns one off, and the
    # job's method (run_plan_deal with its options) gets exactly that.
    from flows.build import build_job

    for value in (True, False):
        cfg = make("method=twostep", "decomposer=plan-deal", f"decomposer.{switch}={value}",
                   f"data.root={data_root}")  # fmt: skip
        with build_job(cfg) as job:  # type: ignore[arg-type]
            options = job.method.keywords  # type: ignore[attr-defined]
        assert options == {"cut": "best", "rebind": True, "owner_search": True, switch: value}
