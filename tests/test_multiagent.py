"""twostep.multiagent: the N-agent compilation and plan splitting."""

from __future__ import annotations

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.multiagent import compile_multi_agent_problem, split_plan
from twostep.pddl import domain_to_pddl, parse_problem, problem_to_pddl
from twostep.planner import PlannerSettings, plan
from twostep.strips import Grounder

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
