"""twostep.pddl.adl and twostep.pddl.origins: PDDL beyond STRIPS, as AlfWorld uses it.

The fixtures in ``tests/fixtures/adl_quirks`` are our own: a small ALFRED-style kitchen
with the features of AlfWorld's ``alfred.pddl`` (quantified goal, disjunctive and
existential preconditions, a conditional effect, action costs, an empty precondition, a
comma in a variable list, constants only the problem declares, a predicate applied to an
argument of another type) and a storage domain with ``(either ...)`` types. Expected
values are derived by hand in the comments; optimal costs are checked once more against
Fast Downward run on the original ADL files.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from twostep.benchmark import load_task
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.execution import parallel_length
from twostep.methods import (
    MethodRequest,
    check_run,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)
from twostep.multiagent import compile_multi_agent_problem, split_plan
from twostep.pddl import PDDLError, domain_to_pddl, parse_goal, parse_problem, problem_to_pddl
from twostep.pddl.origins import compiled_plan, original_plan
from twostep.planner import PlannerSettings, driver_path, plan
from twostep.progression import progress_state
from twostep.strips import Grounder, simulate
from twostep.validation import validate_plan

ROOT = Path(__file__).resolve().parent / "fixtures" / "adl_quirks"
AGENT_PREDICATES = ("atlocation", "holds", "holdsany")
OPTIMAL = PlannerSettings(alias="seq-opt-lmcut", search_time_limit_s=30)


def kitchen(task: int = 1):  # type: ignore[no-untyped-def]
    return load_task("kitchen", task, root=ROOT)


def cost(domain_costs: dict[str, int], plan_steps: list[str] | tuple[str, ...]) -> int:
    return sum(domain_costs.get(step.strip("()").split()[0], 0) for step in plan_steps)


# The hand-derived cheapest plan of kitchen p01 in the task's own terms (cost 16):
# goto fridge 2, open 1, pick up the egg 1, close 1, goto microwave 2, heat 5,
# goto counter 2, put 1, toggle the lamp 1.
P01_PLAN = [
    "(gotolocation alice lstart lfridge)",
    "(openobject alice fridge1)",
    "(pickupobject alice egg1 fridge1)",
    "(closeobject alice fridge1)",
    "(gotolocation alice lfridge lmicro)",
    "(heatobject alice microwave1 egg1)",
    "(gotolocation alice lmicro lcounter)",
    "(putobject alice egg1 counter1)",
    "(toggleobject alice lamp1 counter1)",
]


def test_kitchen_compiles_to_strips_variants() -> None:
    problem = kitchen().problem
    domain = problem.domain
    # when (isOn) -> off / when (not isOn) -> on: two consistent cases, two variants
    on_off = {name: domain.actions[name] for name in ("toggleobject-v1", "toggleobject-v2")}
    assert [str(a) for a in on_off["toggleobject-v1"].pre_positive][-1] == "(ison ?o)"
    assert [str(a) for a in on_off["toggleobject-v1"].delete] == ["(ison ?o)"]
    assert [str(a) for a in on_off["toggleobject-v2"].pre_negative] == ["(ison ?o)"]
    assert [str(a) for a in on_off["toggleobject-v2"].add] == ["(ison ?o)"]
    # (or (not (openable ?r)) (opened ?r)): one variant per disjunct
    assert "(openable ?r)" in [str(a) for a in domain.actions["pickupobject-v1"].pre_negative]
    assert "(opened ?r)" in [str(a) for a in domain.actions["pickupobject-v2"].pre_positive]
    # exists (?l - location) becomes a trailing parameter; the origin keeps the arity
    opening = domain.actions["openobject"]
    assert [t for _, t in opening.parameters] == ["agent", "receptacle", "location"]
    assert domain.origins["openobject"].arity == 2
    assert domain.origins["toggleobject-v2"].name == "toggleobject"
    # a comma-separated variable list: both variables lifted
    assert [t for _, t in domain.actions["heatobject"].parameters][3:] == [
        "location",
        "receptacle",
    ]
    # constants the actions use: one declared by the problem, one by nobody
    assert domain.constants == {"microwavetype": "rtype", "sinkbasintype": "rtype"}
    # (checked ?a) with ?a an agent: the predicate takes the common supertype
    assert domain.predicates["checked"] == ("object",)
    assert domain.action_costs["gotolocation"] == 2
    assert domain.action_costs["heatobject"] == 5
    assert "inventory" not in domain.action_costs  # no increase: cost 0
    # exists with a single witness (one egg, one counter) and forall over receptacles
    assert problem.goal.positive == {
        ("inreceptacle", "egg1", "counter1"),
        ("ishot", "egg1"),
        ("ison", "lamp1"),
    }
    assert problem.goal.negative == {
        ("opened", "fridge1"),
        ("opened", "microwave1"),
        ("opened", "counter1"),
    }


def test_hand_written_plan_progresses_to_the_goal() -> None:
    problem = kitchen().problem
    steps = compiled_plan(problem, P01_PLAN)
    # the fridge is openable, so picking up needs the "(opened ?r)" variant; the counter
    # is not, so putting down takes the "(not (openable ?r))" one; the lamp is off: v2
    assert steps[2].startswith("(pickupobject-v2 alice egg1 fridge1 lfridge")
    assert steps[7] == "(putobject-v1 alice egg1 counter1 lcounter)"
    assert steps[8] == "(toggleobject-v2 alice lamp1 counter1 lcounter)"
    assert original_plan(problem.domain.origins, steps) == P01_PLAN
    final = simulate(problem.init, Grounder(problem).ground_plan(steps))
    assert problem.goal.holds(final)
    assert cost(problem.domain.action_costs, steps) == 16
    environment = progress_state(
        problem.init, Grounder(problem).ground_plan(steps[:4]), AGENT_PREDICATES
    )
    assert ("inreceptacle", "egg1", "fridge1") not in environment
    assert not any(f[0] in AGENT_PREDICATES for f in environment)
    # toggling twice: the conditional effect switches the lamp back off
    twice = compiled_plan(problem, [*P01_PLAN, "(toggleobject alice lamp1 counter1)"])
    assert twice[-1] == "(toggleobject-v1 alice lamp1 counter1 lcounter)"
    assert ("ison", "lamp1") not in simulate(problem.init, Grounder(problem).ground_plan(twice))
    with pytest.raises(Exception, match="no compiled action"):
        compiled_plan(problem, ["(pickupobject alice egg1 fridge1)"])  # not there yet


def _fast_downward_on_original(tmp_path: Path) -> int:
    """Optimal cost of kitchen p01 by Fast Downward on the ADL files themselves.

    Fast Downward reads the ADL directly, but it rejects constants that only the problem
    declares and reads "location," as a type name: those two quirks are edited out.
    """
    domain = (ROOT / "kitchen" / "domain.pddl").read_text()
    domain = domain.replace(
        " (:predicates", " (:constants MicrowaveType SinkBasinType - rtype)\n (:predicates", 1
    ).replace("?l - location, ?x", "?l - location ?x")
    problem = (ROOT / "kitchen" / "p01.pddl").read_text()
    problem = problem.replace(
        "MicrowaveType FridgeType CounterTopType SinkBasinType - rtype",
        "FridgeType CounterTopType - rtype",
    )
    (tmp_path / "domain.pddl").write_text(domain)
    (tmp_path / "problem.pddl").write_text(problem)
    subprocess.run(
        [
            sys.executable,
            str(driver_path()),
            "domain.pddl",
            "problem.pddl",
            "--search",
            "astar(blind())",
        ],
        cwd=tmp_path,
        capture_output=True,
        timeout=120,
        check=False,
    )
    trailer = (tmp_path / "sas_plan").read_text().splitlines()[-1]
    return int(trailer.split("=")[1].split()[0])


def test_optimal_plan_matches_hand_and_fast_downward_on_the_original(tmp_path: Path) -> None:
    problem = kitchen().problem
    result = plan(problem, OPTIMAL)
    assert result.solved and result.plan is not None
    assert cost(problem.domain.action_costs, result.plan) == 16
    assert len(result.plan) == 9
    assert _fast_downward_on_original(tmp_path) == 16
    # unified-planning's validator agrees on the compiled task (costs included)
    assert validate_plan(problem, result.plan).valid
    assert (
        original_plan(problem.domain.origins, result.plan)[5]
        == "(heatobject alice microwave1 egg1)"
    )


def test_costs_are_written_for_the_planner_and_read_back() -> None:
    problem = kitchen().problem
    domain_text = domain_to_pddl(problem.domain)
    assert ":action-costs" in domain_text and "(increase (total-cost) 5)" in domain_text
    assert "(:metric minimize (total-cost))" in problem_to_pddl(problem)
    again = parse_problem(domain_text, problem_to_pddl(problem))
    assert again.domain.action_costs == problem.domain.action_costs
    assert again.goal == problem.goal and again.init == problem.init


def test_parallel_scoring_with_a_conditional_effect() -> None:
    problem = kitchen().problem
    # two agents (each with its own position) both walk to the counter and toggle the
    # lamp: the first toggle (off -> on) must precede the second (on -> off), so the
    # walks share step 1 and the toggles take steps 2 and 3. Goal: the lamp is off.
    first = ["(gotolocation alice lstart lcounter)", "(toggleobject alice lamp1 counter1)"]
    after_first = simulate(
        problem.init, Grounder(problem).ground_plan(compiled_plan(problem, first))
    )
    second = compiled_plan(
        problem,
        ["(gotolocation alice lstart lcounter)", "(toggleobject alice lamp1 counter1)"],
        state=[f for f in after_first if f[0] not in AGENT_PREDICATES]
        + [f for f in problem.init if f[0] in AGENT_PREDICATES],
    )
    plans = [compiled_plan(problem, first), second]
    assert plans[1][1].startswith("(toggleobject-v1")
    grounder = Grounder(problem)
    goal = parse_goal("(not (ison lamp1))", problem)
    for mode in ("exact", "paper"):
        execution = parallel_length(
            [grounder.ground_plan(p) for p in plans], problem.init, goal, AGENT_PREDICATES, mode
        )
        assert execution.length == 3


def test_multi_agent_compilation_adds_agents_as_objects() -> None:
    problem = kitchen().problem
    compiled, names = compile_multi_agent_problem(problem, 2, AGENT_PREDICATES)
    # no second agent parameter: the action schemas are the task's own
    assert compiled.domain.actions == problem.domain.actions
    assert {n: compiled.objects[n] for n in names} == {"agent0": "agent", "agent1": "agent"}
    assert "alice" not in compiled.objects
    assert {f for f in compiled.init if f[0] == "atlocation"} == {
        ("atlocation", "agent0", "lstart"),
        ("atlocation", "agent1", "lstart"),
    }
    sequential = [
        "(gotolocation agent1 lstart lcounter)",
        "(toggleobject-v2 agent1 lamp1 counter1 lcounter)",
        "(inventory agent0)",
    ]
    assert split_plan(sequential, names) == [
        ["(inventory alice)"],
        ["(gotolocation alice lstart lcounter)", "(toggleobject-v2 alice lamp1 counter1 lcounter)"],
    ]


def test_sa_ma_twostep_run_on_the_adl_kitchen() -> None:
    task = kitchen()
    sa = run_single_agent(MethodRequest(task, planner=OPTIMAL))
    assert sa.success and sa.exec_length == 9
    ma = run_multi_agent(
        MethodRequest(task, 2, OPTIMAL, AGENT_PREDICATES, sa_length=sa.exec_length)
    )
    assert ma.success
    check_run(task.problem, ma, AGENT_PREDICATES)
    assert all(step.split()[1] == "alice" for p in ma.plans.values() for step in p)
    twostep = run_twostep(MethodRequest(task, 2, OPTIMAL, AGENT_PREDICATES, GoalSplitDecomposer(AGENT_PREDICATES), sa_length=sa.exec_length))  # fmt: skip
    check_run(task.problem, twostep, AGENT_PREDICATES)
    # goal-split gives the lamp to the helper (walk + toggle: 2 steps); the main agent's
    # cheapest plan for the rest is the 8 other steps of P01_PLAN, which never touch
    # the lamp, so both run side by side: 8 steps.
    assert [s["pddl"] for s in twostep.to_dict()["subgoals"]] == ["(and (ison lamp1))"]
    assert twostep.plans["agent1"] == [
        "(gotolocation alice lstart lcounter)",
        "(toggleobject-v2 alice lamp1 counter1 lcounter)",
    ]
    assert len(twostep.plans["agent0"]) == 8
    assert twostep.exec_length == 8


def test_ambiguous_quantified_goal_becomes_a_goal_action() -> None:
    problem = kitchen(2).problem
    assert problem.goal.positive == {("goal-reached",)}
    assert problem.domain.origins["reach-goal"].name is None
    # every action takes the agent, so the goal action does too (for the MA compilation)
    assert problem.domain.actions["reach-goal"].parameters[-1] == ("?goal-agent", "agent")
    result = plan(problem, OPTIMAL)
    assert result.solved and result.plan is not None
    # egg2 is on the counter already: fetch it, heat it, bring it back (2+1+2+5+2+1 = 13)
    # beats egg1 in the fridge (2+1+1+2+5+2+1 = 14)
    assert cost(problem.domain.action_costs, result.plan) == 13
    assert result.plan[-1] == "(reach-goal egg2 counter1 alice)"
    own_terms = original_plan(problem.domain.origins, result.plan)
    assert len(own_terms) == 6 and own_terms[1] == "(pickupobject alice egg2 counter1)"


def test_quantified_subgoals_are_grounded_by_static_facts() -> None:
    one_egg = kitchen().problem
    goal = parse_goal("(exists (?o - object) (and (objecttype ?o eggtype) (ishot ?o)))", one_egg)
    assert goal.positive == {("ishot", "egg1")} and not goal.negative
    closed = parse_goal("(forall (?r - receptacle) (not (opened ?r)))", one_egg)
    assert closed.negative == {
        ("opened", "fridge1"),
        ("opened", "microwave1"),
        ("opened", "counter1"),
    }
    with pytest.raises(PDDLError, match="2 different ways"):
        parse_goal(
            "(exists (?o - object) (and (objecttype ?o eggtype) (ishot ?o)))", kitchen(2).problem
        )
    with pytest.raises(PDDLError, match="unknown object 'egg9'"):
        parse_goal("(or (ishot egg9) (ishot egg1))", one_egg)


def test_either_types_storage() -> None:
    from pyparsing.exceptions import ParseBaseException
    from unified_planning.io import PDDLReader

    folder = ROOT / "storage"
    with pytest.raises(ParseBaseException, match="Expected '\\)'"):  # UP alone rejects either
        PDDLReader().parse_problem(str(folder / "domain.pddl"), str(folder / "p01.pddl"))
    problem = load_task("storage", 1, root=ROOT).problem
    domain = problem.domain
    # ?from - (either storearea transitarea): one variant per type
    assert {a.parameters[1][1] for a in domain.actions.values()} == {"storearea", "transitarea"}
    assert domain.predicates["in"] == ("object", "place")  # storearea, crate: only object
    assert domain.predicates["clear"] == ("area",)
    result = plan(problem, OPTIMAL)
    assert result.solved and result.plan is not None
    # crate2 must leave s2 (for s1) before crate1 can enter it: 2 steps, in that order
    assert original_plan(domain.origins, result.plan) == [
        "(move crate2 s2 s1 depot1)",
        "(move crate1 t1 s2 depot1)",
    ]


@pytest.mark.parametrize(
    ("extra", "effect", "line", "fragment"),
    [
        ("(:derived (q ?x) (p ?x))", "(q ?x)", 4, "derived predicates are not supported"),
        ("", "(and (q ?x) (increase (total-cost) (dist ?x)))", 7, "costs from functions"),
        ("", "(and (q ?x) (decrease (fuel) 1))", 7, "numeric effects (decrease"),
        ("", "(when (p ?x) (when (p ?x) (q ?x)))", 7, "nested conditional effects"),
        ("", "(and (r ?x) (forall (?y) (q ?y)))", 7, "unknown predicate 'r'"),
    ],
)
def test_unsupported_constructs_name_the_construct_file_and_line(
    extra: str, effect: str, line: int, fragment: str
) -> None:
    domain = (
        "(define (domain d)\n (:requirements :adl)\n (:predicates (p ?x) (q ?x))\n"
        f" {extra}\n (:action a :parameters (?x)\n   :precondition (p ?x)\n"
        f"   :effect {effect}))"
    )
    problem = "(define (problem x) (:domain d) (:objects o) (:init (p o)) (:goal (q o)))"
    with pytest.raises(PDDLError) as info:
        parse_problem(domain, problem, "dom.pddl", "prob.pddl")
    assert info.value.source == "dom.pddl"
    assert info.value.line == line
    assert fragment in str(info.value)


ALFRED = Path("/tmp/alfred-data/alfred.pddl")

# Our own small kitchen task in AlfWorld's problem format (mangled object and location
# names, types declared as problem objects, a nested-exists goal).
ALFWORLD_STYLE_PROBLEM = """
(define (problem plan_twostep_kitchen)
(:domain alfred)
(:objects
agent1 - agent
AppleType EggType KnifeType ButterKnifeType - otype
SinkBasinType MicrowaveType FridgeType DiningTableType CounterTopType - rtype
Apple_bar__minus_01_dot_00_bar__plus_00_dot_80_bar__minus_00_dot_20 - object
Egg_bar__plus_00_dot_20_bar__plus_00_dot_90_bar__minus_01_dot_50 - object
DiningTable_bar__minus_01_dot_80_bar__plus_00_dot_00_bar__minus_00_dot_30 - receptacle
CounterTop_bar__plus_00_dot_20_bar__plus_00_dot_95_bar__minus_01_dot_60 - receptacle
Microwave_bar__plus_00_dot_90_bar__plus_01_dot_70_bar__minus_02_dot_50 - receptacle
Fridge_bar__minus_02_dot_50_bar__plus_00_dot_00_bar__minus_02_dot_00 - receptacle
loc_bar__minus_4_bar__minus_1_bar_3_bar_45 - location
loc_bar_1_bar__minus_4_bar_2_bar_30 - location
loc_bar_3_bar__minus_8_bar_2_bar__minus_15 - location
loc_bar__minus_8_bar__minus_6_bar_2_bar_30 - location
loc_bar_0_bar_0_bar_0_bar_30 - location
)
(:init
(atLocation agent1 loc_bar_0_bar_0_bar_0_bar_30)
(receptacleType DiningTable_bar__minus_01_dot_80_bar__plus_00_dot_00_bar__minus_00_dot_30 DiningTableType)
(receptacleType CounterTop_bar__plus_00_dot_20_bar__plus_00_dot_95_bar__minus_01_dot_60 CounterTopType)
(receptacleType Microwave_bar__plus_00_dot_90_bar__plus_01_dot_70_bar__minus_02_dot_50 MicrowaveType)
(receptacleType Fridge_bar__minus_02_dot_50_bar__plus_00_dot_00_bar__minus_02_dot_00 FridgeType)
(receptacleAtLocation DiningTable_bar__minus_01_dot_80_bar__plus_00_dot_00_bar__minus_00_dot_30 loc_bar__minus_4_bar__minus_1_bar_3_bar_45)
(receptacleAtLocation CounterTop_bar__plus_00_dot_20_bar__plus_00_dot_95_bar__minus_01_dot_60 loc_bar_1_bar__minus_4_bar_2_bar_30)
(receptacleAtLocation Microwave_bar__plus_00_dot_90_bar__plus_01_dot_70_bar__minus_02_dot_50 loc_bar_3_bar__minus_8_bar_2_bar__minus_15)
(receptacleAtLocation Fridge_bar__minus_02_dot_50_bar__plus_00_dot_00_bar__minus_02_dot_00 loc_bar__minus_8_bar__minus_6_bar_2_bar_30)
(openable Microwave_bar__plus_00_dot_90_bar__plus_01_dot_70_bar__minus_02_dot_50)
(openable Fridge_bar__minus_02_dot_50_bar__plus_00_dot_00_bar__minus_02_dot_00)
(objectType Apple_bar__minus_01_dot_00_bar__plus_00_dot_80_bar__minus_00_dot_20 AppleType)
(objectType Egg_bar__plus_00_dot_20_bar__plus_00_dot_90_bar__minus_01_dot_50 EggType)
(pickupable Apple_bar__minus_01_dot_00_bar__plus_00_dot_80_bar__minus_00_dot_20)
(pickupable Egg_bar__plus_00_dot_20_bar__plus_00_dot_90_bar__minus_01_dot_50)
(heatable Egg_bar__plus_00_dot_20_bar__plus_00_dot_90_bar__minus_01_dot_50)
(inReceptacle Apple_bar__minus_01_dot_00_bar__plus_00_dot_80_bar__minus_00_dot_20 Fridge_bar__minus_02_dot_50_bar__plus_00_dot_00_bar__minus_02_dot_00)
(inReceptacle Egg_bar__plus_00_dot_20_bar__plus_00_dot_90_bar__minus_01_dot_50 CounterTop_bar__plus_00_dot_20_bar__plus_00_dot_95_bar__minus_01_dot_60)
(canContain DiningTableType AppleType)
(canContain DiningTableType EggType)
)
(:goal
(and
 (exists (?r - receptacle) (exists (?o - object)
   (and (inReceptacle ?o ?r) (objectType ?o AppleType) (receptacleType ?r DiningTableType))))
 (exists (?r - receptacle) (exists (?o - object)
   (and (inReceptacle ?o ?r) (objectType ?o EggType) (receptacleType ?r DiningTableType) (isHot ?o))))
)
)
)
"""


@pytest.mark.slow
def test_alfworld_own_domain_runs_sa_ma_twostep(tmp_path: Path) -> None:
    if not ALFRED.is_file():
        pytest.skip("AlfWorld's alfred.pddl is not in /tmp/alfred-data")
    folder = tmp_path / "alfred"
    folder.mkdir()
    shutil.copy(ALFRED, folder / "domain.pddl")
    (folder / "p01.pddl").write_text(ALFWORLD_STYLE_PROBLEM)
    task = load_task("alfred", 1, root=tmp_path)
    problem = task.problem
    # the nested exists have one witness each (one apple, one egg, one dining table)
    assert sorted(f[0] for f in problem.goal.positive) == ["inreceptacle", "inreceptacle", "ishot"]
    agents = (*AGENT_PREDICATES, "holdsanyreceptacleobject")
    settings = PlannerSettings(search_time_limit_s=60)
    sa = run_single_agent(MethodRequest(task, planner=settings))
    assert sa.success
    ma = run_multi_agent(MethodRequest(task, 2, settings, agents, sa_length=sa.exec_length))
    assert ma.success
    check_run(problem, ma, agents)
    twostep = run_twostep(MethodRequest(task, 2, settings, agents, GoalSplitDecomposer(agents)))
    assert twostep.success
    check_run(problem, twostep, agents)
    assert twostep.exec_length is not None and sa.exec_length is not None
    assert twostep.exec_length <= sa.exec_length


def _model(problem):  # type: ignore[no-untyped-def]
    actions = {
        name: (
            {str(a) for a in s.pre_positive},
            {str(a) for a in s.pre_negative},
            {str(a) for a in s.add},
            {str(a) for a in s.delete},
            s.equal,
            s.not_equal,
            tuple(t for _, t in s.parameters),
        )
        for name, s in problem.domain.actions.items()
    }
    domain = problem.domain
    return (
        problem.init,
        problem.goal,
        problem.all_objects,
        domain.types,
        domain.predicates,
        actions,
    )


@pytest.mark.parametrize("folder", ["llmp_quirks/tyreworld", "data/blocksworld", "data/barman"])
def test_strips_tasks_compile_to_the_same_model(folder: str, data_root: Path) -> None:
    # Declaring :adl sends a STRIPS task through the compilation: it must change nothing.
    base = ROOT.parent / folder if folder.startswith("llmp") else data_root / folder.split("/")[1]
    domain_text = (base / "domain.pddl").read_text()
    problem_text = (base / "p01.pddl").read_text()
    as_adl = domain_text.replace("(:requirements", "(:requirements :adl", 1)
    assert as_adl != domain_text
    plain = parse_problem(domain_text, problem_text)
    compiled = parse_problem(as_adl, problem_text)
    assert set(compiled.domain.origins) == set(compiled.domain.actions)
    assert _model(compiled) == _model(plain)
