"""Pictures of an embodied run: the GIF's frames and the timeline's rows."""

from __future__ import annotations

from pathlib import Path

from PIL import Image

from twostep.embodied import (
    EmbodiedResult,
    ExecutorSettings,
    FloorPlan,
    build_floor_plan,
    execute,
)
from twostep.embodied.render import (
    save_animation,
    save_timeline,
    schedule_timeline,
    timeline_rows,
)
from twostep.pddl import parse_problem

DOMAIN = (Path(__file__).resolve().parent.parent / "data" / "alfworld" / "domain.pddl").read_text()


def _run() -> tuple[EmbodiedResult, FloorPlan]:
    """a walks 2 cells and opens the cabinet; b waits for it, then takes the mug."""
    problem = parse_problem(
        DOMAIN,
        """(define (problem t) (:domain alfworld)
        (:objects a b - agent sa la lb - location cabinet1 - receptacle mug1 - item)
        (:init (at a sa) (at b lb) (handempty a) (handempty b) (openable cabinet1)
               (reached-from cabinet1 la) (reached-from cabinet1 lb) (in mug1 cabinet1))
        (:goal (holding b mug1)))""",
    )
    floor = build_floor_plan(
        "strip",
        5,
        2,
        {"la": (0, 0), "sa": (2, 0), "lb": (4, 0)},
        furniture={"cabinet1": (1, 1, 3, 1)},
    )
    plans = [["(goto a sa la)", "(open a cabinet1 la)"], ["(pickup b mug1 cabinet1 lb)"]]
    return execute(problem, plans, floor, ["a", "b"], ExecutorSettings(random_start=False)), floor


def test_timeline_rows_follow_the_trace() -> None:
    result, _ = _run()
    assert timeline_rows(result) == {
        "a": ["move", "move", "interact"],
        "b": ["wait", "wait", "interact"],
    }


def test_pictures_are_written(tmp_path: Path) -> None:
    result, floor = _run()
    gif = save_animation(result, floor, tmp_path / "run.gif")
    with Image.open(gif) as image:
        assert image.n_frames == result.steps + 1  # the start and one frame per step
    png = save_timeline(result, tmp_path / "timeline.png")
    assert png.stat().st_size > 0
    schedule = [[("agent1", "(x)"), ("agent0", "(y)")], [("agent0", "(z)")]]
    assert schedule_timeline(schedule, ["agent1", "agent0"], tmp_path / "s.png").is_file()
