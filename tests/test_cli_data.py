"""``twostep-data`` on the embodied kitchen domain: generate, check and scale ``alfworld``."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest

from twostep.cli.data import main
from twostep.embodied import load_floor_plan, task_floor_plan
from twostep.tasks.benchmark import load_problem

DATA = Path(__file__).resolve().parent.parent / "data"


def test_generate_rebuilds_the_committed_kitchen(tmp_path: Path) -> None:
    assert main(["generate", "--out", str(tmp_path), "--domain", "alfworld"]) == 0
    written = {p.name for p in (tmp_path / "alfworld").iterdir()}
    committed = {p.name for p in (DATA / "alfworld").iterdir()}
    assert written == committed - {"expert.yaml"}  # hand-written files are never generated
    for name in written:
        assert (tmp_path / "alfworld" / name).read_text() == (DATA / "alfworld" / name).read_text()


def test_check_covers_the_kitchen(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", "--data", str(DATA), "--domain", "alfworld"]) == 0
    main(["generate", "--out", str(tmp_path), "--domain", "alfworld"])
    plan = tmp_path / "alfworld" / "kitchen.yaml"
    plan.write_text(plan.read_text().replace("width: 13", "width: 14"))
    capsys.readouterr()
    assert main(["check", "--data", str(tmp_path)]) == 1  # every domain, the kitchen included
    err = capsys.readouterr().err
    assert "alfworld/kitchen.yaml:5: expected 'width: 13', found 'width: 14'" in err
    assert "blocksworld/domain.pddl: missing" in err  # the default covers every domain


def test_scale_writes_a_kitchen_with_its_floor_plan(tmp_path: Path) -> None:
    out = tmp_path / "kitchen-12"
    assert main(["scale", "--domain", "alfworld", "--size", "12", "--out", str(out)]) == 0
    problem = load_problem(out / "domain.pddl", out / "p01.pddl")
    assert Counter(problem.objects.values())["item"] == 12
    floor = task_floor_plan(problem, out)
    assert floor == load_floor_plan(out / "kitchen.yaml")
    locations = {o for o, t in problem.objects.items() if t == "location"}
    assert locations <= set(floor.locations)  # every location of the task has a cell
