"""The embodied executor on small hand-made floor plans, with hand-derived lengths.

Each scenario's expected numbers are worked out step by step in its docstring from the
rules (agents act one after another in every step; breadth-first paths around furniture
and the other agents' current cells; a wait when a precondition does not hold or the way
is blocked). The four kitchen tasks run end to end, and a trace is replayed independently
through unified-planning's sequential simulator. Every execution here is also replayed by
the independent trace checker (:mod:`checkers.trace_check`), from the test's own floor
plan literals and PDDL text.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pytest

from checkers.trace_check import Floor, read_kitchen, read_kitchen_file
from tests.embodied_checks import replay
from twostep.embodied import (
    EmbodiedResult,
    ExecutorSettings,
    FloorPlan,
    FloorPlanError,
    alfworld_position,
    build_floor_plan,
    embodied_failure,
    embodied_fields,
    embody,
    execute_plans,
    floor_plan_for_task,
    floor_plan_from_dict,
    floor_plan_from_locations,
    load_floor_plan,
)
from twostep.embodied import execute as execute_unchecked
from twostep.embodied.navigation import reachable_cells, shortest_path
from twostep.pddl import Problem, parse_problem
from twostep.planner import PlannerSettings, plan
from twostep.tasks.benchmark import BenchmarkTask, load_task
from twostep.verify.validation import validate_plan

DATA = Path(__file__).resolve().parent.parent / "data"
DOMAIN = (DATA / "alfworld" / "domain.pddl").read_text()
FIXED = ExecutorSettings(random_start=False)


# What the checker reads instead of our objects: each problem's PDDL text, each floor
# plan's literals (by object identity, for the test's lifetime).
PROBLEM_TEXT: dict[int, str] = {}
CHECKER_FLOOR: dict[int, Floor] = {}


def kitchen(objects: str, init: str, goal: str = "(and)") -> Problem:
    text = f"""(define (problem test) (:domain alfworld)
      (:objects {objects})
      (:init {init})
      (:goal {goal}))"""
    problem = parse_problem(DOMAIN, text)
    PROBLEM_TEXT[id(problem)] = text
    return problem


def corridor(
    width: int,
    height: int,
    locations: dict[str, tuple[int, int]],
    walls: Sequence[tuple[int, int, int, int]] = (),
) -> FloorPlan:
    floor = build_floor_plan("test", width, height, locations, walls)
    CHECKER_FLOOR[id(floor)] = read_kitchen(
        {"width": width, "height": height, "walls": walls, "locations": locations}
    )
    return floor


def execute(
    problem: Problem,
    plans: Sequence[Sequence[str]],
    floor: FloorPlan,
    names: Sequence[str] | None = None,
    settings: ExecutorSettings | None = None,
) -> EmbodiedResult:
    """The executor, with its trace replayed by the independent checker."""
    result = execute_unchecked(problem, plans, floor, names, settings)
    if result.start_positions:  # it started: bodies stood on the floor
        by_body = {body: list(p) for body, p in zip(result.agents, plans, strict=True)}
        report = replay(
            result, floor, by_body, DOMAIN, PROBLEM_TEXT[id(problem)], CHECKER_FLOOR[id(floor)]
        )
        assert report.ok, report.violations
    return result


# ------------------------------------------------------------------ navigation


def test_shortest_path_goes_around_furniture_and_agents() -> None:
    plan = corridor(3, 3, {}, walls=[(1, 1, 1, 1)])
    assert shortest_path(plan, (0, 0), (2, 2)) is not None
    assert len(shortest_path(plan, (0, 1), (2, 1)) or []) == 4  # around the middle block
    # the top way blocked by an agent: the bottom way, also 4 moves
    path = shortest_path(plan, (0, 1), (2, 1), obstacles={(1, 0)})
    assert path == [(0, 2), (1, 2), (2, 2), (2, 1)]
    assert shortest_path(plan, (0, 1), (2, 1), obstacles={(1, 0), (1, 2)}) is None
    assert reachable_cells(plan, (0, 0), obstacles={(1, 0), (0, 1)}) == {(0, 0): 0}


# ------------------------------------------------------------------ scenarios


def test_two_agents_pass_each_other_in_a_two_lane_corridor() -> None:
    """A 5 x 2 corridor. a walks (0,0) -> (3,0); b walks (4,0) -> (1,0).

    Step 1: a moves to (1,0); b's target (1,0) is now taken: b waits (1 wait).
    Step 2: a moves to (2,0); b's straight way is cut at (2,0): b turns into the other
    lane, (4,1) (5 moves: (4,1) (3,1) (2,1) (1,1) (1,0)). Step 3: a reaches (3,0), done.
    Steps 3..6: b walks on and arrives at step 6. Length 6, 1 wait, no backoff.
    """
    problem = kitchen(
        "a b - agent la lb sa sb - location",
        "(at a sa) (at b sb) (handempty a) (handempty b)",
        "(and (at a la) (at b lb))",
    )
    floor = corridor(5, 2, {"sa": (0, 0), "la": (3, 0), "sb": (4, 0), "lb": (1, 0)})
    plans = [["(goto a sa la)"], ["(goto b sb lb)"]]
    result = execute(problem, plans, floor, ["a", "b"], FIXED)
    assert result.status == "success", result.message
    assert (result.embodied_length, result.waits, result.backoffs) == (6, 1, 0)
    b_moves = [t.position for t in result.trace if t.agent == "b" and t.primitive == "move"]
    assert b_moves == [(4, 1), (3, 1), (2, 1), (1, 1), (1, 0)]


def test_head_on_in_a_one_lane_corridor_needs_one_backoff() -> None:
    """A 5-cell corridor with one side bay at (2,1); a goes (0,0) -> (4,0), b the other way.

    Step 1: each target is the other's cell: both blocked, nobody moves: a deadlock. Every
    cell of the corridor lies on the jammed paths, so whoever backs off goes to the bay
    (2,1), 3 moves away (steps 2-4). If a backs off, b walks to (3,0) at step 4 and on to
    (0,0), arriving at step 7 as a leaves the bay at 7 and arrives at 9. If b backs off, a
    is still cut off at step 4 (b leaves (2,0) after a's turn), walks from step 5 and
    arrives at step 8; b follows to (0,0) at step 9. Either way: length 9, one backoff.
    """
    problem = kitchen(
        "a b - agent wa ea - location",
        "(at a wa) (at b ea) (handempty a) (handempty b)",
        "(and (at a ea) (at b wa))",
    )
    floor = corridor(5, 2, {"wa": (0, 0), "ea": (4, 0)}, walls=[(0, 1, 2, 1), (3, 1, 2, 1)])
    plans = [["(goto a wa ea)"], ["(goto b ea wa)"]]
    chosen = set()
    for seed in range(6):
        settings = ExecutorSettings(seed=seed, random_start=False)
        result = execute(problem, plans, floor, ["a", "b"], settings)
        assert result.status == "success", result.message
        assert (result.embodied_length, result.backoffs) == (9, 1)
        backoff = [t for t in result.trace if t.primitive == "backoff"]
        assert [t.position for t in backoff][-1] == (2, 1)
        chosen.add(backoff[0].agent)
        assert result.waits == (6 if backoff[0].agent == "a" else 7)
    assert chosen == {"a", "b"}  # the seed decides who makes way


def test_an_idle_agent_in_the_way_steps_aside() -> None:
    """A 3-cell corridor with a bay at (1,1). a has nothing to do and stands at (1,0); b
    walks (0,0) -> (2,0).

    Step 1: a is done; b's way is cut at (1,0): b waits. a is idle in b's way, so it steps
    aside to the nearest cell off the way: the bay (1,1) (its other neighbour, (2,0), is
    b's goal). Step 2: a moves into the bay (a backoff), b to (1,0). Step 3: b arrives.
    Length 3, 1 wait, 1 backoff, no random choice (every seed gives the same run).
    """
    problem = kitchen(
        "a b - agent sa sb lb - location",
        "(at a sa) (at b sb) (handempty a) (handempty b)",
        "(at b lb)",
    )
    floor = corridor(3, 2, {"sb": (0, 0), "sa": (1, 0), "lb": (2, 0)},
                     walls=[(0, 1, 1, 1), (2, 1, 1, 1)])  # fmt: skip
    for seed in range(3):
        settings = ExecutorSettings(seed=seed, random_start=False)
        result = execute(problem, [[], ["(goto b sb lb)"]], floor, ["a", "b"], settings)
        assert result.status == "success", result.message
        assert (result.embodied_length, result.waits, result.backoffs) == (3, 1, 1)
        a_steps = [(t.step, t.primitive, t.position) for t in result.trace if t.agent == "a"]
        assert a_steps == [(2, "backoff", (1, 1))]


def _cabinet_problem() -> tuple[Problem, FloorPlan]:
    problem = kitchen(
        "a b - agent sa la lb - location cabinet1 - receptacle mug1 - item",
        "(at a sa) (at b lb) (handempty a) (handempty b) (openable cabinet1) "
        "(reached-from cabinet1 la) (reached-from cabinet1 lb) (in mug1 cabinet1)",
        "(holding b mug1)",
    )
    floor = corridor(5, 1, {"la": (0, 0), "sa": (2, 0), "lb": (4, 0)})
    return problem, floor


def test_an_agent_waits_for_another_agents_effect() -> None:
    """The cabinet opens from both ends of a 5-cell corridor; b must wait for a to open it.

    a: 2 moves to (0,0) (steps 1-2), opens at step 3. b, acting after a, waits at steps
    1-2 and picks the mug up at step 3: length 3, 2 waits. With b acting first, b's
    pick-up at step 3 comes before a opens: it waits once more and picks up at step 4.
    """
    problem, floor = _cabinet_problem()
    a_plan = ["(goto a sa la)", "(open a cabinet1 la)"]
    b_plan = ["(pickup b mug1 cabinet1 lb)"]
    result = execute(problem, [a_plan, b_plan], floor, ["a", "b"], FIXED)
    assert result.status == "success", result.message
    assert (result.embodied_length, result.waits) == (3, 2)
    waits = [t for t in result.trace if t.primitive == "wait"]
    assert {t.reason for t in waits} == {"precondition (accessible cabinet1)"}
    reverse = execute(problem, [b_plan, a_plan], floor, ["b", "a"], FIXED)
    assert (reverse.status, reverse.embodied_length, reverse.waits) == ("success", 4, 3)


def test_single_agent_plans_get_one_body_each() -> None:
    """Two plans naming the same agent (as SA/TwoStep plans do) become two bodies."""
    problem, _ = _cabinet_problem()
    embodiment = embody(
        problem, [["(goto a sa la)"], ["(goto a sa la)"], ["(goto agent9 sa la)"]], ["x", "y", "z"]
    )
    assert embodiment.bodies == ("x", "y", "z")
    assert embodiment.plans[1] == ("(goto y sa la)",)
    init = embodiment.problem.init
    assert {("at", "x", "sa"), ("at", "y", "sa"), ("handempty", "y")} <= init
    assert ("at", "z", "sa") in init  # an agent the task lacks starts as its first agent
    assert not any("a" in f[1:] for f in init)
    assert ("holding", "x", "mug1") in embodiment.problem.goal.positive  # every body


def test_a_body_off_its_location_walks_back_before_it_interacts() -> None:
    """Both bodies play alice, who stands at la (0,0) of a 3 x 2 room; a is placed on
    (0,0), b on the nearest free cell, (0,1) (distance 1, the smaller cell of the tie
    with (1,0)). a walks to lc (2,1); b opens the cabinet reached from la.

    Step 1: a moves to (1,0) (its first way east); b is not on la's cell: it walks to
    (0,0), now free (a move that applies nothing). Step 2: a moves on, b opens the
    cabinet from (0,0). Step 3: a reaches (2,1). Length 3, no wait. (Before the fix b
    opened the cabinet at step 1 from (0,1), out of reach.)
    """
    problem = kitchen(
        "alice - agent la lc - location cabinet1 - receptacle",
        "(at alice la) (handempty alice) (openable cabinet1) (reached-from cabinet1 la)",
        "(accessible cabinet1)",
    )
    floor = corridor(3, 2, {"la": (0, 0), "lc": (2, 1)})
    plans = [["(goto alice la lc)"], ["(open alice cabinet1 la)"]]
    result = execute(problem, plans, floor, ["a", "b"], FIXED)
    assert result.status == "success", result.message
    assert (result.embodied_length, result.waits) == (3, 0)
    assert result.start_positions == {"a": (0, 0), "b": (0, 1)}
    b_steps = [(t.step, t.primitive, t.position, t.applied) for t in result.trace if t.agent == "b"]
    assert b_steps == [
        (1, "move", (0, 0), None),
        (2, "interact", (0, 0), "(open b cabinet1 la)"),
    ]


def test_a_single_body_starts_on_its_start_location() -> None:
    """random_start spreads several bodies; one body (SA) starts where the task says:
    every seed gives the same execution."""
    _, floor = _cabinet_problem()
    problem = kitchen(
        "a - agent sa la - location cabinet1 - receptacle",
        "(at a sa) (handempty a) (openable cabinet1) (reached-from cabinet1 la)",
        "(accessible cabinet1)",
    )
    plan = [["(goto a sa la)", "(open a cabinet1 la)"]]
    runs = [execute(problem, plan, floor, ["a"], ExecutorSettings(seed=s)) for s in range(4)]
    assert {r.start_positions["a"] for r in runs} == {(2, 0)}  # sa's cell
    assert {r.embodied_length for r in runs} == {3}


# ------------------------------------------------------------------ bad input


def test_a_location_without_a_cell() -> None:
    problem, floor = _cabinet_problem()
    floor = corridor(5, 1, {"sa": (2, 0), "lb": (4, 0)})
    result = execute(problem, [["(goto a sa la)"]], floor, ["a"], FIXED)
    assert (result.status, result.agent, result.step) == ("no_cell", "a", 0)
    assert "la" in result.reason


def test_an_unreachable_location() -> None:
    problem, _ = _cabinet_problem()
    floor = corridor(5, 1, {"la": (0, 0), "sa": (2, 0), "lb": (4, 0)}, walls=[(1, 0, 1, 1)])
    result = execute(problem, [["(goto a sa la)"]], floor, ["a"], FIXED)
    assert (result.status, result.agent, result.step) == ("unreachable", "a", 1)
    assert "(goto a sa la)" in result.reason
    assert not result.success
    assert result.failure == "embodied_failed: unreachable at step 1, a"


def test_a_kitchen_with_one_free_cell_boxes_two_agents_in() -> None:
    """Every location on the one free cell of a 3 x 1 room: one body fits, two do not."""
    problem, _ = _cabinet_problem()
    floor = corridor(3, 1, {"la": (1, 0), "sa": (1, 0), "lb": (1, 0)},
                     walls=[(0, 0, 1, 1), (2, 0, 1, 1)])  # fmt: skip
    alone = execute(problem, [["(goto a sa la)"]], floor, ["a"], FIXED)
    assert alone.status == "goal_not_reached"  # it stands and walks; the mug is not taken
    both = execute(problem, [["(goto a sa la)"], []], floor, ["a", "b"], FIXED)
    assert (both.status, both.agent, both.step) == ("boxed_in", "b", 0)
    assert not both.success and both.embodied_length is None
    assert "2 agents but 1 free cells" in both.reason
    assert both.failure == "embodied_failed: boxed_in at step 0, b"
    assert both.to_dict()["status"] == "boxed_in"  # the string result.json holds
    # the verdict from the fields a result dict holds (what a stored run is judged by)
    assert embodied_failure(embodied_fields(both, floor)) == both.failure
    assert embodied_failure(embodied_fields(alone, floor)) == (
        "embodied_failed: goal_not_reached at step 1"
    )
    assert embodied_failure({"executor": "symbolic"}) is None


def test_an_agent_boxed_in_for_good() -> None:
    """a must reach b's cell in a 2-cell room; b is done and has nowhere to go."""
    problem, _ = _cabinet_problem()
    floor = corridor(2, 1, {"sa": (0, 0), "la": (1, 0), "lb": (1, 0)})
    result = execute(problem, [["(goto a sa la)"], []], floor, ["a", "b"], FIXED)
    assert (result.status, result.agent, result.step) == ("boxed_in", "a", 1)
    assert "b" in result.reason


def test_a_precondition_nobody_makes_true() -> None:
    """b waits for the cabinet to open, a never opens it: detected once a is done."""
    problem, floor = _cabinet_problem()
    plans = [["(goto a sa la)"], ["(pickup b mug1 cabinet1 lb)"]]
    result = execute(problem, plans, floor, ["a", "b"], FIXED)
    assert (result.status, result.agent, result.step) == ("deadlock", "b", 3)
    assert "(accessible cabinet1)" in result.reason


def test_the_step_budget_ends_an_execution() -> None:
    problem, floor = _cabinet_problem()
    settings = ExecutorSettings(random_start=False, max_steps=1)
    result = execute(problem, [["(goto a sa la)", "(open a cabinet1 la)"]], floor, ["a"], settings)
    assert (result.status, result.agent, result.step) == ("budget_exceeded", "a", 1)


def test_unknown_actions_and_goals_not_reached() -> None:
    problem, floor = _cabinet_problem()
    bad = execute(problem, [["(fly a sa la)"]], floor, ["a"], FIXED)
    assert (bad.status, bad.agent) == ("invalid_plan", "a")
    short = execute(problem, [["(goto a sa la)"]], floor, ["a"], FIXED)
    assert short.status == "goal_not_reached"
    assert short.unmet_goal == ["(holding a mug1)"]


# ------------------------------------------------------------------ floor plans


def test_floor_plan_files_and_errors(tmp_path: Path) -> None:
    plan = load_floor_plan(DATA / "alfworld" / "kitchen.yaml")
    assert plan.cell_of("loc-fridge1") == (1, 2)
    assert (1, 1) in plan.blocked and plan.free((1, 2))
    with pytest.raises(FloorPlanError, match="on a wall or furniture"):
        floor_plan_from_dict(
            {"width": 3, "height": 1, "walls": [[0, 0, 1, 1]], "locations": {"l": [0, 0]}}
        )
    with pytest.raises(FloorPlanError, match="off the grid"):
        floor_plan_from_dict({"width": 3, "height": 1, "locations": {"l": [5, 0]}})
    with pytest.raises(FloorPlanError, match="no such"):
        load_floor_plan(tmp_path / "missing.yaml")


def test_alfworld_location_names_place_themselves() -> None:
    names = ["loc_bar_4_bar__minus_3_bar_1_bar_45", "loc_bar__minus_2_bar_5_bar_0_bar_30"]
    assert alfworld_position(names[0]) == (4, -3)
    assert alfworld_position("loc|-2|5|0|30") == (-2, 5)
    assert alfworld_position("loc-fridge1") is None
    plan = floor_plan_from_locations(names)
    a, b = (plan.cell_of(n) for n in names)
    assert a is not None and b is not None
    assert (a[0] - b[0], a[1] - b[1]) == (6, -8)  # distances survive the shift
    with pytest.raises(FloorPlanError, match="loc-fridge1"):
        floor_plan_from_locations([*names, "loc-fridge1"])


# ------------------------------------------------------------------ the kitchen tasks


FAST = PlannerSettings(alias="lama-first", search_time_limit_s=60)


@pytest.fixture(scope="module")
def kitchen_plan() -> FloorPlan:
    path = DATA / "alfworld" / "kitchen.yaml"
    floor = load_floor_plan(path)
    CHECKER_FLOOR[id(floor)] = read_kitchen_file(path)
    return floor


def kitchen_task(task_id: int) -> BenchmarkTask:
    task = load_task("alfworld", task_id, DATA)
    PROBLEM_TEXT[id(task.problem)] = task.problem_path.read_text()
    return task


@pytest.mark.parametrize("task_id", [1, 2, 3, 4])
def test_single_agent_plans_of_the_four_tasks_execute(
    task_id: int, kitchen_plan: FloorPlan
) -> None:
    task = kitchen_task(task_id)
    result = plan(task.problem, FAST)
    assert result.plan is not None
    run = execute(task.problem, [result.plan], kitchen_plan, ["agent0"])
    assert run.status == "success", run.message
    interactions = [t for t in run.trace if t.applied is not None]
    assert [t.action for t in interactions] == list(result.plan)  # every action, in order
    assert run.embodied_length == len(run.trace)  # one agent: one command per step, no waits
    assert run.embodied_length >= len(result.plan)


def _expert_twostep_plans(task_id: int) -> tuple[Problem, list[list[str]]]:
    from twostep.decomposers.expert import ExpertDecomposer
    from twostep.methods import MethodRequest, run_twostep

    task = kitchen_task(task_id)
    run = run_twostep(
        MethodRequest(task, 2, FAST, ["at", "handempty", "holding"], ExpertDecomposer())
    )
    assert run.agent_order == ["agent1", "agent0"]
    return task.problem, [run.plans[a] for a in run.agent_order]


def test_same_seed_same_trace_and_the_trace_replays_in_unified_planning(
    kitchen_plan: FloorPlan,
) -> None:
    problem, plans = _expert_twostep_plans(1)
    names = ["agent1", "agent0"]
    first = execute(problem, plans, kitchen_plan, names, ExecutorSettings(seed=7))
    by_agent = dict(zip(names, plans, strict=True))  # as result.json holds them
    again = execute_plans(problem, by_agent, names, kitchen_plan, ExecutorSettings(seed=7))
    other = execute(problem, plans, kitchen_plan, names, ExecutorSettings(seed=8))
    assert first.status == "success", first.message
    assert first.trace == again.trace and first.to_dict() == again.to_dict()
    assert other.start_positions != first.start_positions
    # Every applied action, in trace order, is a valid plan of the task with one agent
    # object per body, by unified-planning's validator (independent of our STRIPS model).
    assert first.problem is not None
    applied = [t.applied for t in first.trace if t.applied is not None]
    assert len(applied) == sum(len(p) for p in plans)
    assert validate_plan(first.problem, applied).valid
    # ... and a trace with two interactions swapped is not
    broken = applied[:]
    k = next(i for i, a in enumerate(broken) if a.startswith("(pickup"))
    broken[k - 1], broken[k] = broken[k], broken[k - 1]
    assert not validate_plan(first.problem, broken).valid


def test_made_up_alfworld_locations_on_an_open_grid(tmp_path: Path) -> None:
    """Locations named as AlfWorld names them: (0,0) start, fridge at x=3 z=-2, on an open
    grid (layout 'open': no scene)."""
    start, fridge = "loc_bar_0_bar_0_bar_1_bar_45", "loc_bar_3_bar__minus_2_bar_2_bar_30"
    problem = kitchen(
        f"alice - agent {start} {fridge} - location fridge1 - receptacle egg1 - item",
        f"(at alice {start}) (handempty alice) (reached-from fridge1 {fridge}) "
        "(openable fridge1) (in egg1 fridge1)",
        "(holding alice egg1)",
    )
    floor = floor_plan_for_task([start, fridge], tmp_path, layout="open")
    # the open grid by hand: x -1..4, z -3..1 (a margin of one); y = z + 3
    CHECKER_FLOOR[id(floor)] = read_kitchen(
        {"width": 6, "height": 5, "locations": {start: (1, 3), fridge: (4, 1)}}
    )
    steps = [
        f"(goto alice {start} {fridge})",
        f"(open alice fridge1 {fridge})",
        f"(pickup alice egg1 fridge1 {fridge})",
    ]
    result = execute(problem, [steps], floor, ["alice"], FIXED)
    assert result.status == "success", result.message
    assert result.embodied_length == 5 + 2  # |3| + |-2| moves on an open grid, 2 interactions


def test_a_multi_agent_plan_gets_one_body_per_planning_agent(kitchen_plan: FloorPlan) -> None:
    """Task 1 planned for alice and an added agent bob, split per agent: both walk."""
    task = kitchen_task(1)
    problem = task.problem
    copies = {tuple("bob" if t == "alice" else t for t in f) for f in problem.init if "alice" in f}
    two = Problem(
        "two",
        problem.domain,
        {**problem.objects, "bob": "agent"},
        problem.init | copies,
        problem.goal,
    )
    result = plan(two, FAST)
    assert result.plan is not None
    per_agent: dict[str, list[str]] = {"alice": [], "bob": []}
    for step in result.plan:
        per_agent[step.split()[1]].append(step)
    run = execute(
        problem, [per_agent["alice"], per_agent["bob"]], kitchen_plan, ["agent0", "agent1"]
    )
    assert run.status == "success", run.message
    assert run.problem is not None
    applied = [t.applied for t in run.trace if t.applied is not None]
    assert {a.split()[1] for a in applied} == {"agent0", "agent1"} & {
        "agent0" if per_agent["alice"] else "",
        "agent1" if per_agent["bob"] else "",
    }
    assert validate_plan(run.problem, applied).valid
