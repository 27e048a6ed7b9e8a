"""The ``twostep`` command wired to the embodied executor, the new decomposers and ADL naming.

Each test runs the real command (Prefect and MLflow off) and checks what it wrote against
something it did not compute itself: the trace's own steps, the images' headers, the task
files' action names, the lengths of the SA plan.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import DictConfig
from PIL import Image

from flows.build import run_config
from flows.checks import JobError
from flows.config import register, typed
from tests.conftest import BLOCKS_DOMAIN, FIXTURES, blocks_problem
from tests.support.commands import REPO, run_cli
from tests.support.skips import needs_alfworld

OUTPUT: list[Path] = []  # the module's output.root (set by the fixture below)


@pytest.fixture(scope="module", autouse=True)
def hydra_conf(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    register()
    OUTPUT[:] = [tmp_path_factory.mktemp("out")]
    with initialize_config_dir(config_dir=str(REPO / "conf"), version_base="1.3"):
        yield


def make(*overrides: str) -> DictConfig:
    base = [f"data.root={REPO / 'data'}", f"output.root={OUTPUT[0]}"]
    return compose("config", overrides=[*base, *overrides])


def _result(out: Path) -> tuple[Path, dict[str, Any]]:
    (path,) = list((out / "runs").rglob("result.json"))
    data: dict[str, Any] = json.loads(path.read_text())
    return path.parent, data


@pytest.mark.slow  # a GIF of ~60 steps and a process start: ~20-40 s
def test_alfworld_twostep_runs_embodied_with_pictures(tmp_path: Path) -> None:
    proc = run_cli(f"output.root={tmp_path}", "domain=alfworld", "task=1", "method=twostep")
    assert proc.returncode == 0, proc.stderr
    job_dir, result = _result(tmp_path)
    assert result["executor"] == "embodied" and result["embodied_status"] == "success"
    trace = json.loads((job_dir / "embodied" / "trace.json").read_text())["trace"]
    assert "embodied_trace" not in result  # the trace is an artifact, not in result.json
    # the summary fields agree with the trace they summarise
    assert result["embodied_length"] == max(t["step"] for t in trace)
    assert result["waits"] == sum(t["primitive"] == "wait" for t in trace)
    # a backoff is one or more moves: each run of backoff moves is at least one backoff
    backing = {(t["agent"], t["step"]) for t in trace if t["primitive"] == "backoff"}
    runs = sum(1 for agent, step in backing if (agent, step - 1) not in backing)
    assert runs <= result["backoffs"] and (result["backoffs"] > 0 or not backing)
    # every plan action is applied exactly once by the body that plans it
    for agent, plan in result["plans"].items():
        applied = [t["action"] for t in trace if t["agent"] == agent and t.get("applied")]
        assert applied == plan
    # the summary line and the picture paths
    assert f"embodied_length={result['embodied_length']}" in proc.stdout
    timeline = job_dir / "embodied" / "timeline.png"
    assert f"timeline: {timeline}" in proc.stdout
    with Image.open(timeline) as image:
        assert image.format == "PNG" and image.width > 100
    with Image.open(job_dir / "embodied" / "kitchen.gif") as image:
        assert image.format == "GIF" and image.n_frames > 2


def test_executor_config_alfworld_embodied_by_default() -> None:
    assert make().executor.name == "symbolic"
    assert make("domain=alfworld").executor.name == "embodied"
    assert make("domain=alfworld", "executor=symbolic").executor.name == "symbolic"
    table2 = make("experiment=table2", "method=twostep")
    assert (table2.domain.name, table2.executor.name, table2.planner.alias) == (
        "alfworld",
        "embodied",
        "lama",
    )
    assert table2.method.fallback_if_longer is False
    assert make("experiment=paper").method.fallback_if_longer is False
    assert make().method.fallback_if_longer is True


@pytest.mark.parametrize(
    ("method", "agents"), [("sa", 1), ("ma", 2), ("ma", 3), ("twostep", 2), ("twostep", 3)]
)
@needs_alfworld
def test_domain_alfred_runs_a_real_problem_on_its_scene(
    tmp_path: Path, method: str, agents: int
) -> None:
    """``domain=alfred``: the wheel's alfred.pddl beside our FloorPlan14 problem, each
    method through the command's front end (no domain.* overrides needed), executed on the
    scene's layout; the trace checker, which reads the layout and the PDDL itself, replays
    the trace: no violation, no interaction out of reach."""
    from checkers.trace_check import check_trace
    from tests.support.data import alfred_root

    root = alfred_root(tmp_path)
    cfg = make(f"data.root={root}", "domain=alfred", "task=1", f"method={method}",
               f"agents={agents}", "executor.render=false")  # fmt: skip
    assert list(cfg.domain.agent_predicates) == [
        "atlocation", "holds", "holdsany", "holdsanyreceptacleobject",
    ]  # fmt: skip
    result = run_config(typed(cfg)).to_dict()
    assert result["success"] and result["agents"] == agents
    assert result["embodied_status"] == "success", result["embodied"]
    assert result["embodied"]["floor_plan"] == "FloorPlan14"
    record = result["embodied_trace"]
    assert record["floor_plan"]["layout"] == "FloorPlan14"
    folder = root / "alfred"
    domain, problem = (folder / "domain.pddl").read_text(), (folder / "p01.pddl").read_text()
    report = check_trace(record, result["plans"], domain, problem)
    assert report.ok and report.out_of_reach == 0, report.violations
    bodies = {t["agent"] for t in record["trace"]}
    assert bodies <= set(result["plans"]) and len(result["plans"]) <= agents


def test_pictures_in_single_runs_and_for_a_sweeps_seed_0(tmp_path: Path) -> None:
    """``executor.render`` unset: a single run draws its GIF and timeline, a sweep's job
    only for seed 0; ``true`` or ``false`` decide for every job. Drawing is no part of
    what a job computes: the same job, asked again with another render setting, is
    reused from the job store."""
    import os
    import time

    from flows.job import execute_job
    from flows.sweep_state import SweepState

    sweep = SweepState(str(tmp_path / "sweep"), time.time(), os.getpid())
    cases = [  # (seed, in a sweep, executor.render) -> drawn, reused
        (1, True, None, False, False),
        (1, False, None, True, True),
        (1, True, "true", True, True),
        (1, False, "false", False, True),
        (0, True, None, True, False),
    ]
    for number, (seed, in_sweep, render, drawn, reused) in enumerate(cases):
        extra = [] if render is None else [f"executor.render={render}"]
        cfg = make("domain=alfworld", "task=4", "method=sa", f"seed={seed}",
                   f"output.root={tmp_path / 'out'}", "mlflow.enabled=false",
                   "orchestration.prefect=false", *extra)  # fmt: skip
        job_dir = tmp_path / "jobs" / str(number)
        outcome = execute_job(cfg, job_dir, sweep if in_sweep else None)
        assert outcome.status == "success" and outcome.reused is reused
        pictures = {p.name for p in (job_dir / "embodied").iterdir()}
        expected = {"trace.json", "kitchen.gif", "timeline.png"} if drawn else {"trace.json"}
        assert pictures == expected, (seed, in_sweep, render)


@needs_alfworld
def test_executor_layout_chooses_the_scene(tmp_path: Path) -> None:
    """``executor.layout``: the problem's own scene is found without it; a scene that does
    not hold the problem's locations is refused with their names; ``open`` places them on
    an open grid."""
    from tests.support.data import alfred_root

    root = alfred_root(tmp_path)
    base = [f"data.root={root}", "domain=alfred", "task=1", "method=sa"]
    found = run_config(typed(make(*base))).to_dict()["embodied_trace"]["floor_plan"]
    chosen = run_config(typed(make(*base, "executor.layout=FloorPlan14"))).to_dict()
    assert found["layout"] == chosen["embodied_trace"]["floor_plan"]["layout"] == "FloorPlan14"
    opened = run_config(typed(make(*base, "executor.layout=open"))).to_dict()
    assert opened["embodied"]["floor_plan"] == "alfworld-locations"
    assert "layout" not in opened["embodied_trace"]["floor_plan"]
    # refused before any work (an input error, exit 2), with the key and the locations
    with pytest.raises(JobError, match=r"executor\.layout=FloorPlan1: .*not on a reachable point"):
        run_config(typed(make(*base, "executor.layout=FloorPlan1")))


def test_alfworld_symbolic_executor_has_no_embodied_fields() -> None:
    cfg = typed(make("domain=alfworld", "task=1", "method=sa", "executor=symbolic"))
    result = run_config(cfg).to_dict()
    assert result["success"]
    embodied = {"executor", "embodied_status", "embodied_length", "waits", "backoffs", "embodied"}
    assert not embodied & set(result)
    # the same job embodied: the fields appear and the execution replays the SA plan
    embodied_run = run_config(typed(make("domain=alfworld", "task=1", "method=sa"))).to_dict()
    assert embodied <= set(embodied_run) and embodied_run["embodied_status"] == "success"
    steps = embodied_run["embodied_trace"]["trace"]
    assert [t["action"] for t in steps if t.get("applied")] == result["plans"]["agent0"]


@pytest.mark.slow
def test_adl_task_result_names_the_tasks_own_actions(tmp_path: Path) -> None:
    root = FIXTURES / "adl_quirks"
    proc = run_cli(
        f"output.root={tmp_path}", f"data.root={root}", "domain.name=kitchen",
        "domain.agent_predicates=[atlocation,holds,holdsany]", "task=1", "method=ma",
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    job_dir, result = _result(tmp_path)
    text = (root / "kitchen" / "domain.pddl").read_text().lower()
    arity = {
        name: len(re.findall(r"\?[\w-]+", params.split(")")[0]))
        for name, params in re.findall(r"\(:action\s+([\w-]+)\s+:parameters\s*\(([^)]*\))", text)
    }
    steps = [s for plan in result["plans"].values() for s in plan]
    assert steps
    for step in steps:
        name, *args = step.strip("()").split()
        assert arity.get(name) == len(args), step  # the domain file's own action and arity
    for step in (a for pairs in result["schedule"] for _, a in pairs):
        assert step.strip("()").split()[0] in arity
    # nothing is compiled: no plans in other terms to keep (issue 17)
    assert "compiled_plans" not in result
    assert (job_dir / "plans").is_dir()


@pytest.mark.slow
def test_plan_split_and_portfolio_from_the_command(tmp_path: Path) -> None:
    for name in ("plan-split", "portfolio"):
        out = tmp_path / name
        proc = run_cli(
            f"output.root={out}", "domain=blocksworld", "task=3", "agents=3",
            f"decomposer={name}",
        )  # fmt: skip
        assert proc.returncode == 0, proc.stderr
        _, result = _result(out)
        assert result["success"] and result["decomposer"].startswith(name)
        assert result["fallback_if_longer"] is True
        if name == "portfolio":
            candidates = result["candidates"]
            lengths = [c["exec_length"] for c in candidates if c.get("exec_length") is not None]
            # the winner is the shortest candidate (or SA, when every candidate is longer)
            assert result["exec_length"] == min([*lengths, result["sa_length"]])
            assert {c["agents"] for c in candidates} == {3, 2}


def _wasteful_task(root: Path) -> None:
    """SA needs 2 steps (pickup a, stack a b); the expert's helper first builds b on a,
    which the main agent must undo: the joint schedule is longer than SA."""
    folder = root / "blocks"
    folder.mkdir(parents=True)
    (folder / "domain.pddl").write_text(BLOCKS_DOMAIN)
    init = "(clear a) (clear b) (on-table a) (on-table b) (arm-empty)"
    (folder / "p01.pddl").write_text(blocks_problem(init, "(on a b)", objects="a b"))
    (folder / "expert.yaml").write_text('p01:\n  2:\n    - "(on b a)"\n')


def test_fallback_if_longer_true_and_false(tmp_path: Path) -> None:
    _wasteful_task(tmp_path / "data")
    results = {}
    for flag in ("true", "false"):
        cfg = compose("config", overrides=[
            f"data.root={tmp_path / 'data'}", f"output.root={tmp_path / 'out'}", "domain.name=blocks",
            "domain.agent_predicates=[arm-empty,holding]", "task=1", "decomposer=expert",
            f"method.fallback_if_longer={flag}",
        ])  # fmt: skip
        results[flag] = run_config(typed(cfg)).to_dict()
    kept, fell_back = results["false"], results["true"]
    assert kept["sa_length"] == fell_back["sa_length"] == 2
    assert kept["fallback"] is None and kept["exec_length"] > 2
    assert [s["status"] for s in kept["subgoals"]] == ["accepted"]
    assert fell_back["exec_length"] == 2 and fell_back["plans"] == {
        "agent0": ["(pickup a)", "(stack a b)"]
    }
    assert "longer than SA" in fell_back["fallback"]
    assert fell_back["fallback_if_longer"] is True and kept["fallback_if_longer"] is False
