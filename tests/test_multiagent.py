"""twostep.tasks.multiagent: the N-agent compilation and plan splitting."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from tests.examples import SHELF, SHELF_PROBLEM
from twostep.pddl import domain_to_pddl, parse_problem, problem_to_pddl
from twostep.planner import PlannerSettings, plan
from twostep.plans.simulate import Grounder
from twostep.tasks.multiagent import compile_multi_agent_problem, split_plan

AGENT_PREDICATES = ["arm-empty", "holding"]


def test_compilation_adds_agents_everywhere() -> None:
    p = parse_problem(
        BLOCKS_DOMAIN,
        blocks_problem(
            "(on-table a) (clear a) (on-table b) (clear b) (arm-empty)",
            "(on a b) (arm-empty)",
            "a b",
        ),
    )
    ma, names = compile_multi_agent_problem(p, 3, AGENT_PREDICATES)
    assert names == ["agent0", "agent1", "agent2"]
    assert ma.domain.predicates["holding"] == ("agent", "object")
    assert ma.domain.predicates["on"] == ("object", "object")
    pickup = ma.domain.actions["pickup"]
    assert pickup.parameters[0] == ("?agent", "agent")
    assert {str(a) for a in pickup.pre_positive} == {
        "(clear ?b)",
        "(on-table ?b)",
        "(arm-empty ?agent)",
    }
    assert {("arm-empty", n) for n in names} <= ma.init
    assert ("arm-empty",) not in ma.init
    assert ma.goal.positive == {("on", "a", "b")} | {("arm-empty", n) for n in names}
    # the compiled task is valid PDDL for unified-planning
    again = parse_problem(domain_to_pddl(ma.domain), problem_to_pddl(ma))
    assert again.all_objects == ma.all_objects


def test_compiled_plan_splits_into_single_agent_terms() -> None:
    p = parse_problem(
        BLOCKS_DOMAIN,
        blocks_problem(
            "(on-table a) (clear a) (on-table b) (clear b) (on-table c) (clear c) (arm-empty)",
            "(on a b) (on c a)",
            "a b c",
        ),
    )
    ma, names = compile_multi_agent_problem(p, 2, AGENT_PREDICATES)
    result = plan(ma, PlannerSettings("lama-first", 10))
    assert result.plan is not None
    per_agent = split_plan(result.plan, names)
    assert sum(len(x) for x in per_agent) == len(result.plan)
    grounder = Grounder(p)  # every step is an action of the ORIGINAL task
    for steps in per_agent:
        for step in steps:
            assert len(grounder.ground(step).args) == len(step.strip("()").split()) - 1


def test_agent_argument_reaches_quantifiers_conditions_and_derived_predicates() -> None:
    from twostep.makespan import check_schedule, parallel_length
    from twostep.pddl import planner_input
    from twostep.planner import plan as run_planner

    p = parse_problem(SHELF, SHELF_PROBLEM)
    ma, names = compile_multi_agent_problem(p, 2, ["holding"])
    domain_text, _ = planner_input(ma)
    assert "(:derived (busy ?agent - agent) (exists (?o) (holding ?agent ?o)))" in domain_text
    assert "(not (busy ?agent))" in domain_text
    assert "(when (holding ?agent ?o) (and (not (holding ?agent ?o)) (on-shelf ?o)))" in domain_text
    assert ma.domain.predicates["busy"] == ("agent",)
    # one hand each: the SA plan takes and bins one object after the other (4 steps); the
    # two agents each take one and bin it, side by side (2 steps)
    sa = run_planner(p, PlannerSettings("astar-blind", 20))
    assert sa.plan is not None and len(sa.plan) == 4
    result = run_planner(ma, PlannerSettings("astar-blind", 20))
    assert result.plan is not None and len(result.plan) == 4
    per_agent = split_plan(result.plan, names)
    grounder = Grounder(p)
    plans = [grounder.ground_plan(steps) for steps in per_agent]
    assert sorted(len(x) for x in plans) == [2, 2]
    execution = parallel_length(plans, p.init, p.goal, ["holding"])
    assert execution.length == 2
    check_schedule(execution.steps, plans, p.init, p.goal, ["holding"])


def test_costs_from_functions_survive_the_compilation() -> None:
    from tests.examples import ROAD_LENGTHS, ROAD_LENGTHS_PROBLEM
    from twostep.pddl import planner_input
    from twostep.planner import plan as run_planner

    p = parse_problem(ROAD_LENGTHS, ROAD_LENGTHS_PROBLEM)
    ma, names = compile_multi_agent_problem(p, 2, ["at"])
    _, problem_text = planner_input(ma)
    assert "(= (road-length a b) 5)" in problem_text
    assert {("at", n, "a") for n in names} <= ma.init
    # both cars must reach d (agent-specific goal literals hold for every agent): 2 x 10
    result = run_planner(ma, PlannerSettings("astar-blind", 20))
    assert result.plan is not None and result.cost == 20 and len(result.plan) == 4


@pytest.mark.parametrize("decomposer", ["plan-deal", "plan-split", "goal-split"])
def test_offline_methods_on_axioms_and_conditional_effects(decomposer: str, tmp_path: Path) -> None:
    from twostep.decomposers.goal_split import GoalSplitDecomposer
    from twostep.decomposers.plan_split import PlanSplitDecomposer
    from twostep.methods import MethodRequest, check_run, method_for
    from twostep.tasks.benchmark import load_task

    folder = tmp_path / "shelf"
    folder.mkdir()
    (folder / "domain.pddl").write_text(SHELF)
    (folder / "p01.pddl").write_text(SHELF_PROBLEM)
    task = load_task("shelf", 1, root=tmp_path)
    facts = ("holding",)
    sources = {"plan-split": PlanSplitDecomposer(facts), "goal-split": GoalSplitDecomposer(facts)}
    request = MethodRequest(
        task, 2, PlannerSettings("astar-blind", 20), facts, sources.get(decomposer)
    )
    run = method_for("twostep", decomposer)(request)
    assert run.success
    check_run(task.problem, run, facts)
    # one object each, side by side: 2 steps (the SA plan takes 4)
    assert run.exec_length == 2
