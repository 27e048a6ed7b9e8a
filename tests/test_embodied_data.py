"""data/alfworld: the committed files are what the kitchen generator writes, and they fit
together (floor plan, tasks, example plan, expert subgoals)."""

from __future__ import annotations

import re
from pathlib import Path
from random import Random

import pytest
import yaml

from twostep.decomposers.expert import load_expert_subgoals
from twostep.embodied import ExecutorSettings, execute, floor_plan_from_dict, load_floor_plan
from twostep.generators.alfworld import PAPER_TASKS, data_files, scaled_task
from twostep.pddl import parse_goal, parse_problem
from twostep.planner import PlannerSettings, plan
from twostep.plans.simulate import read_plan
from twostep.tasks.benchmark import load_task, task_titles
from twostep.verify.validation import validate_plan

DATA = Path(__file__).resolve().parent.parent / "data"
FOLDER = DATA / "alfworld"


def test_committed_files_are_what_the_generator_writes() -> None:
    for name, text in data_files().items():
        assert (FOLDER / name).read_text() == text, name


def test_every_location_of_every_task_has_a_free_cell() -> None:
    floor = load_floor_plan(FOLDER / "kitchen.yaml")
    for index in range(1, len(PAPER_TASKS) + 1):
        problem = load_task("alfworld", index, DATA).problem
        locations = [o for o, t in problem.objects.items() if t == "location"]
        assert locations and all(floor.free(floor.cell_of(loc) or (-1, -1)) for loc in locations)


def test_task_titles_name_what_each_goal_asks() -> None:
    """Table II's task descriptions: each title names the goal's objects (read from the
    goal section of each task file, apart from the loaders)."""
    titles = task_titles("alfworld", DATA)
    assert sorted(titles) == [1, 2, 3, 4]
    for index, title in titles.items():
        text = (FOLDER / f"p{index:02d}.pddl").read_text()
        goal = text[text.index("(:goal") :]
        objects = set(re.findall(r"\b([a-z]+)\d\b", goal)) - {"diningtable", "sinkbasin"}
        objects -= {"fridge"} if index == 3 else set()
        words = title.lower().replace("wine bottle", "winebottle")
        assert objects and all(o in words for o in objects), (index, objects, title)
    assert task_titles("blocksworld", DATA) == {}


def test_every_drawn_receptacle_is_next_to_the_cell_it_is_reached_from() -> None:
    """Read apart from the loaders: kitchen.yaml's rectangles and p01's reached-from facts.
    An agent on a location's cell touches (4-neighbour) every piece of furniture reached
    from there (loc-door and the garbage can were 2 cells apart)."""
    plan = yaml.safe_load((FOLDER / "kitchen.yaml").read_text())
    facts = re.findall(r"\(reached-from (\S+) (\S+)\)", (FOLDER / "p01.pddl").read_text())
    assert len(facts) == 15
    checked = 0
    for receptacle, location in facts:
        if receptacle not in plan["furniture"]:
            continue  # a cabinet or drawer inside a counter's footprint
        x, y, w, h = plan["furniture"][receptacle]
        lx, ly = plan["locations"][location]
        gap = max(x - lx, lx - (x + w - 1), 0) + max(y - ly, ly - (y + h - 1), 0)
        assert gap == 1, (receptacle, location, gap)
        checked += 1
    assert checked == 10


def test_objects_start_inside_closed_containers_where_the_paper_says() -> None:
    closed_at_start = {
        1: {"egg1": "fridge1", "fork1": "drawer1"},
        3: {"egg1": "cabinet2", "winebottle1": "cabinet4"},
    }
    for index, where in closed_at_start.items():
        init = load_task("alfworld", index, DATA).problem.init
        for item, container in where.items():
            assert ("in", item, container) in init
            assert ("openable", container) in init and ("accessible", container) not in init


def test_the_example_plan_is_valid() -> None:
    task = load_task("alfworld", 1, DATA)
    example = parse_problem(task.domain_path.read_text(), task.example_pddl)
    steps = read_plan((FOLDER / "p_example.sol").read_text())
    assert validate_plan(example, steps).valid


def test_expert_subgoals_are_valid_and_not_already_true() -> None:
    table = load_expert_subgoals(FOLDER / "expert.yaml")
    assert sorted(table) == ["p01", "p02", "p03", "p04"]
    for key, per_n in table.items():
        problem = load_task("alfworld", int(key[1:]), DATA).problem
        (subgoal,) = per_n[2]
        goal = parse_goal(subgoal, problem)
        assert not goal.holds(problem.init)


def test_scaled_kitchens_grow_and_their_tasks_execute() -> None:
    small, small_kitchen = scaled_task("s6", 6, Random(0))
    large, large_kitchen = scaled_task("s30", 30, Random(0))
    assert sum(t == "item" for _, t in small.objects) == 6
    assert sum(t == "item" for _, t in large.objects) == 30
    assert large_kitchen.width > small_kitchen.width
    assert len(large_kitchen.receptacles) > len(small_kitchen.receptacles)
    floor = floor_plan_from_dict(yaml.safe_load(small_kitchen.floor_plan_yaml()))
    problem = parse_problem((FOLDER / "domain.pddl").read_text(), small.to_pddl())
    result = plan(problem, PlannerSettings(alias="lama-first", search_time_limit_s=60))
    assert result.plan is not None
    run = execute(problem, [result.plan], floor, settings=ExecutorSettings(seed=1))
    assert run.status == "success", run.message


@pytest.mark.parametrize("size", [3, 12])
def test_scaled_task_is_reproducible(size: int) -> None:
    first, _ = scaled_task("s", size, Random("0:alfworld:1"))
    again, _ = scaled_task("s", size, Random("0:alfworld:1"))
    assert first == again
