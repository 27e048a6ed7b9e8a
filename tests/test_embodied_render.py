"""Pictures of an embodied run: the GIF's frames (routes along the grid path, doors open
or closed, labels that do not overlap, text at least 10 px) and the timeline's rows."""

from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

from twostep.embodied import (
    EmbodiedResult,
    ExecutorSettings,
    FloorPlan,
    build_floor_plan,
    execute,
)
from twostep.embodied.render import (
    CLOSED_COLOR,
    DPI,
    OPEN_COLOR,
    TEXT_PX,
    _font,
    _frames,
    _KitchenFigure,
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


def test_frames_follow_the_grid_path_and_the_scene() -> None:
    """a walks (2,0) -> (1,0) -> (0,0) and opens the cabinet at step 3, when b takes the
    mug: the route at the start is the two cells a will walk; the scene changes at step 3."""
    result, _ = _run()
    frames = _frames(result)
    assert [f.step for f in frames] == [0, 1, 2, 3]
    assert frames[0].routes["a"] == ((1, 0), (0, 0))
    assert frames[1].routes["a"] == ((0, 0),)
    assert frames[2].routes["a"] == () and frames[0].routes["b"] == ()
    assert frames[2].scene.is_open("cabinet1") is False
    assert frames[2].scene.contents["cabinet1"] == ("mug1",)
    assert frames[3].scene.is_open("cabinet1") is True
    assert "cabinet1" not in frames[3].scene.contents  # b holds the mug
    assert frames[3].holding["b"] == ("mug1",)


def _rgb(hex_color: str) -> tuple[int, int, int]:
    return tuple(int(hex_color[i : i + 2], 16) for i in (1, 3, 5))  # type: ignore[return-value]


def test_doors_labels_and_text_size_in_the_gif(tmp_path: Path) -> None:
    """The cabinet is drawn closed in the first frame and open in the last; labels do not
    overlap and are at least 10 px high."""
    result, floor = _run()
    gif = save_animation(result, floor, tmp_path / "run.gif")
    figure = _KitchenFigure(result, floor, DPI)
    # a point inside the cabinet (cells x 1..3, y 1), left of its centred label
    x, y = figure.ax.transData.transform((0.65, 1.0))
    pixel = (round(x), round(figure.fig.bbox.height - y))
    with Image.open(gif) as image:
        image.seek(0)
        first = image.convert("RGB").getpixel(pixel)
        image.seek(image.n_frames - 1)
        last = image.convert("RGB").getpixel(pixel)
    assert first == _rgb(CLOSED_COLOR) and last == _rgb(OPEN_COLOR)
    boxes = [box for _, box in figure.labels]
    assert [text for text, _ in figure.labels] == ["cabinet1"]
    assert all(box.height >= 10 for box in boxes)
    assert TEXT_PX >= 10 and _font(TEXT_PX).size >= 10


@pytest.mark.parametrize("dpi", [DPI, 200])  # the GIF's, and save_frame's PNG
def test_labels_never_overlap_on_the_kitchen(dpi: float) -> None:
    """The labels' boxes hold the text as PIL draws it at the picture's size (a box made
    for smaller text let "microwave1" and "stoveburner1" run into each other in a PNG
    frame), and no two boxes overlap."""
    from twostep.embodied import load_floor_plan

    floor = load_floor_plan(
        Path(__file__).resolve().parent.parent / "data" / "alfworld" / "kitchen.yaml"
    )
    result, _ = _run()
    figure = _KitchenFigure(result, floor, dpi)
    boxes = [box for _, box in figure.labels]
    assert len(boxes) == len(floor.furniture) == 10
    font = _font(TEXT_PX * dpi / DPI)
    for i, (text, box) in enumerate(figure.labels):
        left, top, right, bottom = font.getbbox(text)
        assert box.width >= right - left and box.height >= max(10, bottom - top), text
        assert not any(box.overlaps(other) for other in boxes[i + 1 :])
