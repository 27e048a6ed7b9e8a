"""Real AlfWorld problems on the AI2-THOR layouts the alfworld wheel ships.

The fixture ``tests/fixtures/alfred_scene/alfred/p01.pddl`` is our own four-part kitchen
task in AlfWorld's problem format on FloorPlan14 (receptacle ids and interaction points of
the scene, our objects and facts); the domain is the wheel's own ``alfred.pddl``, copied
beside it at test time. Expected values come from the layout file itself (read here with
numpy, apart from the code under test) and from the fixture's names.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from checkers.trace_check import alfworld_layouts_folder, check_trace
from tests.support.data import alfred_root
from tests.support.skips import needs_alfworld, skip_without_alfworld_engine
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.embodied import (
    ExecutorSettings,
    FloorPlanError,
    execute_plans,
    find_scene,
    floor_plan_for_task,
    task_floor_plan,
)
from twostep.embodied.layouts import display_names, layouts_folder, object_point
from twostep.embodied.run import TRACE_KEY, embodied_fields
from twostep.methods import (
    MethodRequest,
    RunResult,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)
from twostep.methods.plan_deal import run_plan_deal
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import BenchmarkTask, load_task

AGENT_PREDICATES = ("atlocation", "holds", "holdsany", "holdsanyreceptacleobject")
FAST = PlannerSettings(alias="lama-first", search_time_limit_s=60)

pytestmark = needs_alfworld


@pytest.fixture(scope="module")
def task(tmp_path_factory: pytest.TempPathFactory) -> BenchmarkTask:
    return load_task("alfred", 1, alfred_root(tmp_path_factory.mktemp("data")))


def _points(scene: str) -> set[tuple[int, int]]:
    raw = np.load(Path(str(alfworld_layouts_folder())) / f"{scene}-layout.npy")
    return {(round(x * 4), round(z * 4)) for x, z in raw.tolist()}


def test_the_problem_sits_on_floorplan14(task: BenchmarkTask) -> None:
    floor = task_floor_plan(task.problem, task.problem_path.parent)
    assert floor.name == "FloorPlan14" and floor.origin is not None
    x0, z0 = floor.origin
    points = _points("FloorPlan14")
    assert len(points) == 118
    free = set(floor.free_cells())
    assert {(x0 + x, z0 - y) for x, y in free} == points  # free = reachable, nothing else
    # every location on its own grid point: loc_bar_4_bar__minus_3_... is (4, -3)
    assert floor.cell_of("loc_bar_4_bar__minus_3_bar_1_bar_30") == (4 - x0, z0 + 3)
    assert floor.cell_of("loc_bar__minus_3_bar_10_bar_2_bar_30") == (-3 - x0, z0 - 10)
    # the microwave and the sink are both reached from point (4, -3): one cell, two locations
    assert floor.cell_of("loc_bar_4_bar__minus_3_bar_2_bar_30") == (4 - x0, z0 + 3)
    # the kitchen island (point (3, 5)) is not reachable; the fridge is drawn at its
    # own position (-0.53 m, -1.55 m) -> point (-2, -6), out of the walkable area
    assert not floor.free((3 - x0, z0 - 5))
    fridge = "fridge_bar__minus_00_dot_53_bar__plus_00_dot_00_bar__minus_01_dot_55"
    assert floor.fixtures[fridge] == (-2 - x0, z0 + 6)
    assert object_point("Fridge|-00.53|+00.00|-01.55") == (-2, -6)
    assert len(floor.fixtures) == 9
    names = display_names(floor.fixtures)
    assert names[fridge] == "fridge1"
    assert sorted(n for n in names.values() if n.startswith("cabinet")) == [
        "cabinet1", "cabinet2", "cabinet3", "cabinet4",
    ]  # fmt: skip
    assert (
        names["sink_bar__plus_01_dot_10_bar__plus_00_dot_91_bar__minus_01_dot_60_bar_sinkbasin"]
        == "sinkbasin1"
    )


def test_the_scene_is_found_four_ways(task: BenchmarkTask, tmp_path: Path) -> None:
    problem = task.problem
    locations = [o for o, t in problem.objects.items() if t == "location"]
    receptacles = [o for o, t in problem.objects.items() if t == "receptacle"]
    # ALFRED's traj_data.json beside the problem names the scene
    (tmp_path / "traj_data.json").write_text(json.dumps({"scene": {"floor_plan": "FloorPlan7"}}))
    assert find_scene(locations, receptacles, tmp_path, "x") == "FloorPlan7"
    # the problem's name, then its receptacle ids, then its location points
    assert find_scene(locations, receptacles, None, "trial_FloorPlan14_x") == "FloorPlan14"
    assert find_scene(locations, receptacles, None, "x") == "FloorPlan14"
    assert find_scene(locations, [], None, "x") == "FloorPlan14"
    with pytest.raises(FloorPlanError, match=r"choose one with layout=FloorPlanN"):
        find_scene(["loc|0|0|0|30"], [], None, "x")  # the centre point: many scenes
    # an explicit layout wins; a wrong one names the locations it cannot place
    chosen = floor_plan_for_task(locations, None, "FloorPlan14", receptacles)
    assert chosen.name == "FloorPlan14"
    with pytest.raises(FloorPlanError, match="not on a reachable point"):
        floor_plan_for_task(locations, None, "FloorPlan1", receptacles)
    assert floor_plan_for_task(locations, None, "open").origin is None
    assert len(list(layouts_folder().glob("FloorPlan*-layout.npy"))) == 120


def _runs(task: BenchmarkTask) -> dict[str, RunResult]:
    runs = {"sa": run_single_agent(MethodRequest(task, 1, FAST))}
    for n in (2, 3):
        request = MethodRequest(task, n, FAST, AGENT_PREDICATES)
        runs[f"ma{n}"] = run_multi_agent(request)
        runs[f"twostep{n}"] = run_plan_deal(request)
        goal_split = GoalSplitDecomposer(AGENT_PREDICATES)
        runs[f"goal-split{n}"] = run_twostep(
            MethodRequest(task, n, FAST, AGENT_PREDICATES, goal_split)
        )
    return runs


def test_sa_ma_and_twostep_run_on_the_real_layout(task: BenchmarkTask) -> None:
    """Every run reaches the goal on FloorPlan14 and every trace replays in the checker,
    which reads the layout and alfred.pddl itself; SA has no variance."""
    floor = task_floor_plan(task.problem, task.problem_path.parent)
    domain, problem = task.domain_path.read_text(), task.problem_path.read_text()
    lengths: dict[str, list[int]] = {}
    for name, run in _runs(task).items():
        assert run.success, (name, run.message)
        for seed in (0, 1):
            result = execute_plans(
                task.problem,
                run.plans,
                run.agent_order,
                floor,
                ExecutorSettings(seed=seed),
            )
            assert result.success, (name, seed, result.message)
            record = embodied_fields(result, floor)[TRACE_KEY]
            assert record["floor_plan"]["layout"] == "FloorPlan14"
            report = check_trace(record, run.plans, domain, problem)
            assert report.ok, (name, seed, report.violations)
            assert report.out_of_reach == 0
            assert report.interactions + report.navigations == sum(
                len(p) for p in run.plans.values()
            )
            lengths.setdefault(name, []).append(result.embodied_length or 0)
    assert len(set(lengths["sa"])) == 1  # one body starts where the problem says


def test_a_real_run_is_drawn_with_its_furniture(task: BenchmarkTask, tmp_path: Path) -> None:
    """The picture of a run on FloorPlan14: the island is drawn as unreachable space, the
    nine receptacles are labelled (without overlaps) at their own positions."""
    from PIL import Image

    from twostep.embodied.render import DPI, UNREACHABLE_COLOR, _KitchenFigure, save_frame

    floor = task_floor_plan(task.problem, task.problem_path.parent)
    run = run_single_agent(MethodRequest(task, 1, FAST))
    result = execute_plans(task.problem, run.plans, run.agent_order, floor)
    figure = _KitchenFigure(result, floor, DPI)
    labels = sorted(text for text, _ in figure.labels)
    assert labels == sorted(display_names(floor.fixtures).values()) and len(labels) == 9
    boxes = [box for _, box in figure.labels]
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])
    png = save_frame(result, floor, tmp_path / "frame.png", 0, dpi=DPI)
    assert floor.origin is not None
    x0, z0 = floor.origin
    x, y = figure.ax.transData.transform((3 - x0, z0 - 5))  # the island's point (3, 5)
    with Image.open(png) as image:
        pixel = image.convert("RGB").getpixel((round(x), round(figure.fig.bbox.height - y)))
    assert pixel == tuple(int(UNREACHABLE_COLOR[i : i + 2], 16) for i in (1, 3, 5))


@pytest.mark.slow  # AlfWorld's engine (make alfworld-engine) in a subprocess per replay: ~1 min
def test_alfworlds_own_engine_accepts_the_plans_and_traces(task: BenchmarkTask) -> None:
    """The SA plan and every trace's actions in step order are played in AlfWorld's own
    game (TextWorld's PDDL engine with alfred.pddl and alfred.twl2): every step applicable,
    the goal won; a plan with two steps swapped is refused."""
    from checkers.alfworld_engine import replay, replay_trace
    from checkers.trace_check import who_plays

    skip_without_alfworld_engine()
    problem = task.problem_path.read_text()
    runs = _runs(task)
    (sa_plan,) = runs["sa"].plans.values()
    assert replay(problem, sa_plan).ok
    swapped = list(sa_plan)
    swapped[2], swapped[3] = swapped[3], swapped[2]
    refused = replay(problem, swapped)
    assert not refused.ok and refused.applied < len(swapped) and "not applicable" in refused.failure
    floor = task_floor_plan(task.problem, task.problem_path.parent)
    for name, run in runs.items():
        plays = who_plays(task.domain_path.read_text(), problem, run.plans)
        for seed in (0, 1):
            result = execute_plans(
                task.problem, run.plans, run.agent_order, floor, ExecutorSettings(seed=seed)
            )
            record = embodied_fields(result, floor)[TRACE_KEY]
            judged = replay_trace(record, problem, plays)
            assert judged.ok, (name, seed, judged)
