"""Methods by name (issue 40, item 3): ``method=plan-deal|portfolio|portfolio-lite``, the
old spelling ``method=twostep decomposer=plan-deal`` respelled with a one-line notice and
recorded as before (same job key, name, stored config), and a method added with one
module, one registry line and one config file, run through the ``twostep`` entry.

The old spelling's own tests stay where they were (test_config, test_value_ranges,
test_result_shape, ...): they are the compatibility check. The reference for "recorded as
before" is the old spelling's composed config as Hydra composes it, untouched by
:mod:`flows.spelling`.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra
from omegaconf import OmegaConf

from flows.config import register
from flows.identity import job_name
from flows.spelling import notice, respell, sweep_notice
from flows.store import job_config, job_inputs, job_key
from flows.tracking.contents import config_tags, job_params
from twostep.methods.registry import METHODS, MethodEntry, UnknownMethod, method_for

REPO = Path(__file__).resolve().parent.parent
CONF = REPO / "conf"
PLACES = ["output.root=/tmp/twostep-out"]
TWOSTEP = Path(sys.executable).parent / "twostep"

# (old spelling, new spelling) of the same job
SPELLINGS = [
    (["method=twostep"], ["method=plan-deal"]),
    (["method=twostep", "decomposer=plan-deal"], ["method=plan-deal"]),
    (
        [
            "method=twostep",
            "decomposer=plan-deal",
            "decomposer.cut=free",
            "decomposer.rebind=false",
        ],
        ["method=plan-deal", "method.cut=free", "method.rebind=false"],
    ),
    (["method=twostep", "decomposer=portfolio"], ["method=portfolio"]),
    (
        ["method=twostep", "decomposer=portfolio-lite", "decomposer.link_degree=3"],
        ["method=portfolio-lite", "method.link_degree=3"],
    ),
    (
        ["experiment=paper", "method=twostep", "decomposer=plan-deal", "agents=3"],
        ["experiment=paper", "method=plan-deal", "agents=3"],
    ),
]


@pytest.fixture
def conf() -> Iterator[None]:
    register()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        yield


def _raw(*overrides: str) -> dict[str, object]:
    """The composed config as plain data, as Hydra composes it (nothing respelled)."""
    cfg = compose("config", overrides=[*PLACES, *overrides])
    data = OmegaConf.to_container(cfg, resolve=True, enum_to_str=True)
    assert isinstance(data, dict)
    return {str(k): v for k, v in data.items()}


@pytest.mark.parametrize(("old", "new"), SPELLINGS)
def test_the_new_spelling_is_recorded_as_the_old_one(
    conf: None, old: list[str], new: list[str]
) -> None:
    reference = _raw(*old)  # the old spelling, as it was always recorded
    assert reference["method"] == {"name": "twostep", "fallback_if_longer": reference["method"]["fallback_if_longer"]}  # type: ignore[index]  # fmt: skip
    if old == ["method=twostep"]:
        reference["decomposer"] = _raw("method=twostep", "decomposer=plan-deal")["decomposer"]
    for spelling in (old, new):
        config = job_config(compose("config", overrides=[*PLACES, *spelling]))
        assert config == reference, spelling
        assert job_key(config, job_inputs(config)) == job_key(reference, job_inputs(reference))
        name = str(reference["decomposer"]["name"])  # type: ignore[index]
        assert job_name(config) == f"blocksworld-p05-twostep-{name}-n{config['agents']}-s0"


def _record(*overrides: str) -> tuple[object, ...]:
    """What a job of ``overrides`` is recorded as: its key, name, MLflow params and tags."""
    config = job_config(compose("config", overrides=[*PLACES, *overrides]))
    return (job_key(config, job_inputs(config)), job_name(config), job_params(config),
            config_tags(config), config)  # fmt: skip


def test_the_default_method_is_plan_deal_by_name_recorded_as_before(conf: None) -> None:
    """With no method given the config composes ``method: plan-deal`` (what runs), and the
    job is recorded exactly as ``method=plan-deal`` and as the old spellings were: the
    old default ``method=twostep`` without a decomposer, and ``decomposer=plan-deal``."""
    for extra in ([], ["agents=3"], ["domain=grippers", "task=2"]):
        cfg = compose("config", overrides=[*PLACES, *extra])
        assert (cfg.method.name, cfg.decomposer.name) == ("plan-deal", None)
        default = _record(*extra)
        assert default == _record("method=plan-deal", *extra)
        assert default == _record("method=twostep", *extra)
        assert default == _record("method=twostep", "decomposer=plan-deal", *extra)
        agents = 3 if extra == ["agents=3"] else 2
        assert default[1] == f"{cfg.domain.name}-p{cfg.task:02d}-twostep-plan-deal-n{agents}-s0"
    # The default method's options given the old way (decomposer.<option>, which
    # method=twostep without a decomposer read) still count, silently, as they did.
    old_way = ["decomposer.cut=free", "decomposer.rebind=false"]
    assert _record(*old_way) == _record(
        "method=plan-deal", "method.cut=free", "method.rebind=false"
    )
    assert _record(*old_way) == _record("method=twostep", *old_way)
    cfg = compose("config", overrides=[*PLACES, *old_way])
    assert respell(cfg) is None and (cfg.method.cut, cfg.method.rebind) == ("free", False)
    assert _record("method=portfolio", "decomposer.rebind=false") == _record("method=portfolio")
    # The run folder names the method, as method=plan-deal's always did (make demo).
    with_hydra = compose("config", overrides=PLACES, return_hydra_config=True)
    assert str(with_hydra.hydra.run.dir).endswith("_blocksworld_p5_plan-deal_n2")


@pytest.mark.parametrize(
    ("overrides", "method"),
    [
        (["decomposer=llm"], "twostep"),
        (["decomposer=goal-split", "agents=3"], "twostep"),
        (["experiment=paper"], "twostep"),  # its subgoal source is llm
        (["method=sa", "decomposer=goal-split"], "sa"),
        (["method=plan-deal", "decomposer=goal-split"], "plan-deal"),
        (["decomposer=plan-deal", "decomposer.cut=free"], "twostep"),  # the old spelling
    ],
)
def test_a_decomposer_given_without_a_method_runs_twostep(
    conf: None, overrides: list[str], method: str
) -> None:
    """A subgoal source is TwoStep's: given without a method it composes method=twostep
    (conf/decomposer/*.yaml), as when twostep was the default; a method given wins."""
    cfg = compose("config", overrides=[*PLACES, *overrides])
    assert cfg.method.name == method
    if method == "twostep":
        assert _record(*overrides) == _record("method=twostep", *overrides)


@pytest.mark.parametrize("portfolio", ["portfolio", "portfolio-lite"])
def test_the_old_spelling_of_a_portfolio_with_a_cut_is_recorded_as_before(
    conf: None, portfolio: str
) -> None:
    """The portfolios read no ``cut``; the old spelling that set one anyway
    (``decomposer.cut=free``) keeps the record, hence the job key, it always had: the
    composed config, cut included, not the new spelling's (whose plan-deal cut is
    ``best``: the portfolios have no cut option)."""
    old = ["method=twostep", f"decomposer={portfolio}", "decomposer.cut=free"]
    reference = _raw(*old)
    assert reference["decomposer"]["cut"] == "free"  # type: ignore[index]
    config = job_config(compose("config", overrides=[*PLACES, *old]))
    assert config == reference
    assert job_key(config, job_inputs(config)) == job_key(reference, job_inputs(reference))
    new = job_config(compose("config", overrides=[*PLACES, f"method={portfolio}"]))
    assert new["decomposer"]["cut"] == "best"
    assert job_key(new, job_inputs(new)) != job_key(config, job_inputs(config))


def test_the_new_spelling_names_the_method_and_its_options(conf: None) -> None:
    cfg = compose("config", overrides=[*PLACES, "method=plan-deal", "method.cut=holding"])
    assert cfg.method.name == "plan-deal" and cfg.decomposer.name is None
    assert respell(cfg) is None  # nothing to respell
    assert {k: cfg.method[k] for k in ("cut", "rebind", "owner_search")} == {
        "cut": "holding",
        "rebind": True,
        "owner_search": True,
    }
    old = compose("config", overrides=[*PLACES, "method=twostep", "decomposer=portfolio"])
    said = respell(old)
    assert said is not None and "method=portfolio" in said and "\n" not in said
    assert old.method.name == "portfolio" and old.method.link_degree == 2


def test_the_old_spelling_builds_the_same_method(conf: None, data_root: Path) -> None:
    from flows.build import build_job

    root = f"data.root={data_root}"
    for old, new in SPELLINGS[:5]:
        built = []
        for spelling in (old, new):
            cfg = compose("config", overrides=[*PLACES, root, "task=1", *spelling])
            with build_job(cfg) as job:  # type: ignore[arg-type]
                method = job.method
            function = getattr(method, "func", method)
            built.append((function, getattr(method, "keywords", {}), job.method_name))
        assert built[0] == built[1], old


def test_every_method_has_one_config_file_named_after_it() -> None:
    files = {p.stem for p in (CONF / "method").glob("*.yaml")}
    assert files == set(METHODS)
    for name in METHODS:
        text = (CONF / "method" / f"{name}.yaml").read_text()
        assert f"name: {name}\n" in text


def test_method_for_by_name_and_by_the_old_spelling() -> None:
    from twostep.methods.plan_deal import run_plan_deal
    from twostep.methods.portfolio import run_portfolio_lite

    deal = method_for("plan-deal", cut="free")
    assert deal.func is run_plan_deal and deal.keywords == {"cut": "free"}  # type: ignore[attr-defined]
    old = method_for("twostep", "plan-deal", cut="free", link_degree=2)  # the old keywords
    assert old.func is run_plan_deal and old.keywords == {"cut": "free"}  # type: ignore[attr-defined]
    assert method_for("twostep", "portfolio-lite") is run_portfolio_lite
    with pytest.raises(UnknownMethod, match="method plan-deal has no option colour"):
        method_for("plan-deal", colour="red")
    with pytest.raises(ValueError, match="cut='sideways' is not one of free, holding, mover, best"):
        method_for("plan-deal", cut="sideways")
    with pytest.raises(ValueError, match="rebind='yes' is not bool"):
        method_for("plan-deal", rebind="yes")
    with pytest.raises(UnknownMethod, match="unknown decomposer 'plan-deals'"):
        method_for("twostep", "plan-deals")


def test_the_notice_names_the_new_spelling_in_one_line() -> None:
    assert notice("twostep", "goal-split") is None and notice("plan-deal", None) is None
    text = notice("twostep", "plan-deal")
    assert text is not None and "write method=plan-deal" in text and "\n" not in text
    assert notice("twostep", None) is None  # the old default: runs plan-deal, says nothing


def test_a_sweep_says_the_notice_once_for_its_old_spelling(conf: None) -> None:
    def sweep(*overrides: str) -> object:
        cfg = compose("config", overrides=PLACES, return_hydra_config=True)
        OmegaConf.update(cfg, "hydra.overrides.task", list(overrides))
        return cfg

    assert sweep_notice(sweep("method=twostep", "decomposer=goal-split,llm")) is None
    assert sweep_notice(sweep("method=sa,ma,plan-deal")) is None
    said = sweep_notice(sweep("method=twostep", "decomposer=goal-split,portfolio"))
    assert said is not None and "write method=portfolio" in said
    assert sweep_notice(sweep("method=sa,twostep")) is None  # the old default, silent


def test_the_old_spelling_runs_with_a_notice_and_reuses_what_the_new_stored(
    data_root: Path, tmp_path: Path
) -> None:
    """Through the command: the old spelling's job is the stored job of the new one."""
    common = ["domain=blocksworld", "task=1", "agents=2", f"data.root={data_root}",
              f"output.root={tmp_path}", "orchestration.prefect=false", "mlflow.enabled=false"]  # fmt: skip
    new = subprocess.run([str(TWOSTEP), "method=plan-deal", *common],
                         capture_output=True, text=True, timeout=300)  # fmt: skip
    assert new.returncode == 0, new.stderr
    assert "note:" not in new.stderr
    old = subprocess.run([str(TWOSTEP), "method=twostep", "decomposer=plan-deal", *common],
                         capture_output=True, text=True, timeout=300)  # fmt: skip
    assert old.returncode == 0, old.stderr
    notes = [line for line in old.stderr.splitlines() if line.startswith("note: method=")]
    assert len(notes) == 1 and "write method=plan-deal" in notes[0]
    assert "Traceback" not in old.stderr
    first, second = new.stdout.splitlines()[0], old.stdout.splitlines()[0]
    assert first.startswith("blocksworld-p01-twostep-plan-deal-n2-s0 | success")
    assert second == f"{first} | reused (job store)"


# ------------------------------------------------------------- a method added by a user

TOY_MODULE = '''
from twostep.methods import MethodRequest, RunResult, run_single_agent


def run_toy(request: MethodRequest, label: str = "plain", rounds: int = 1) -> RunResult:
    """The SA plan, recorded as method "toy" with its options."""
    run = run_single_agent(request)
    run.method = "toy"
    run.extra["toy"] = {"label": label, "rounds": rounds}
    return run
'''


@pytest.fixture
def toy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The toy method added the way a user adds one; returns the folder of its config
    file, ``method/toy.yaml``, which a test writes (a ``--config-dir`` of the user's own)."""
    # 1. one module
    (tmp_path / "toy_method.py").write_text(TOY_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    # 2. one registry line
    monkeypatch.setitem(METHODS, "toy", MethodEntry("toy_method:run_toy"))
    # 3. one config file, in a folder of the user's own
    configs = tmp_path / "configs"
    (configs / "method").mkdir(parents=True)
    return configs


def test_a_method_is_one_module_one_registry_line_and_one_config_file(
    toy: Path, data_root: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    configs = toy
    (configs / "method" / "toy.yaml").write_text("name: toy\nlabel: plain\nrounds: 1\n")
    out = tmp_path / "out"
    arguments = ["--config-dir", str(configs), "method=toy", "method.label=shiny",
                 "domain=blocksworld", "task=1", "agents=2", f"data.root={data_root}",
                 f"output.root={out}", "orchestration.prefect=false", "mlflow.enabled=false"]  # fmt: skip
    from flows.config import override_problem

    assert override_problem(arguments) is None  # the command knows the option
    assert override_problem([*arguments[:2], "method=toys"]) == (
        "unknown method 'toys' (choices: ma, plan-deal, portfolio, portfolio-lite, sa, toy, "
        "twostep)"
    )
    from flows.cli import app

    monkeypatch.setattr(sys, "argv", ["twostep", *arguments])
    GlobalHydra.instance().clear()
    try:
        app()
    finally:
        GlobalHydra.instance().clear()
    (result_file,) = out.glob("runs/*/*_toy_n2/result.json")
    result = json.loads(result_file.read_text())
    # The SA plan of blocksworld p01 (tests/test_pipeline.py checks its length by hand),
    # under the new method's own name, with the option the command line set.
    assert result["method"] == "toy" and result["success"] is True
    assert result["toy"] == {"label": "shiny", "rounds": 1}
    assert result["exec_length"] == result["sa_length"] == len(result["plans"]["agent0"])
    (stored,) = (p for p in (out / "jobs").iterdir() if not p.name.startswith("."))
    config = json.loads((stored / "config.json").read_text())
    assert config["method"] == {"name": "toy", "fallback_if_longer": True, "label": "shiny",
                                "rounds": 1}  # fmt: skip
    assert job_name(config) == "blocksworld-p01-toy-n2-s0"


def test_a_wrong_option_of_an_added_method_is_one_line(toy: Path, data_root: Path) -> None:
    configs = toy
    (configs / "method" / "toy.yaml").write_text("name: toy\nrounds: many\n")
    from flows.build import build_job
    from flows.checks import JobError

    register()
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF), version_base="1.3"):
        cfg = compose("config", overrides=[*PLACES, f"data.root={data_root}", "task=1",
                      f"hydra.searchpath=[file://{configs}]", "method=toy"])  # fmt: skip
    GlobalHydra.instance().clear()
    assert cfg.method.rounds == "many"
    wrong = r"^method toy: option rounds='many' is not int$"
    with pytest.raises(JobError, match=wrong), build_job(cfg):  # type: ignore[arg-type]
        pass


def test_plan_deals_cut_choices_are_the_dealers_cuts_and_best() -> None:
    from typing import get_args

    from twostep.dealing import CUTS
    from twostep.methods.plan_deal import BEST, DealCut

    (choices,) = DealCut.__metadata__
    assert get_args(choices) == (*CUTS, BEST)


def test_a_sweep_dir_of_both_spellings_is_one_series(conf: None, tmp_path: Path) -> None:
    """A report over job directories of both spellings (``.hydra/config.yaml`` as Hydra
    wrote it) gives their runs the same params, so they are one series, as in MLflow."""
    import yaml

    from flows.report_sources import load_runs_from_sweep_dir

    for task, spelling in (
        (1, ["method=twostep", "decomposer=plan-deal"]),
        (2, ["method=plan-deal"]),
    ):
        job = tmp_path / f"{task}_job"
        (job / ".hydra").mkdir(parents=True)
        config = _raw(*spelling, f"task={task}")
        (job / ".hydra" / "config.yaml").write_text(yaml.safe_dump(config))
        result = {"domain": "blocksworld", "task": task, "method": "twostep", "agents": 2,
                  "seed": 0, "decomposer": "plan-deal", "success": True, "status": "solved",
                  "exec_length": 5, "sa_length": 8, "planning_time_s": 0.1}  # fmt: skip
        (job / "result.json").write_text(json.dumps(result))
    runs = load_runs_from_sweep_dir(tmp_path)
    params = runs.filter(like="param.").drop(columns=["param.task"], errors="ignore")
    assert not [
        c
        for c in params.columns
        if c.startswith("param.method.") and c != "param.method.fallback_if_longer"
    ]
    first, second = (params.iloc[i].to_dict() for i in range(2))
    assert first == second
    assert list(runs["decomposer"]) == ["plan-deal", "plan-deal"]
