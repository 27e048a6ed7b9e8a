"""twostep.plans.progression: environment facts carry over, agent facts stay with the agent."""

from __future__ import annotations

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.pddl import Goal, parse_problem
from twostep.plans.progression import handoff_problem, progress_state
from twostep.plans.simulate import Grounder

BW = ["arm-empty", "holding"]


def test_handoff_keeps_environment_and_resets_agent_state() -> None:
    p = parse_problem(
        BLOCKS_DOMAIN,
        blocks_problem(
            "(on-table a) (clear a) (on-table b) (clear b) (arm-empty)", "(on a b)", "a b"
        ),
    )
    helper_plan = Grounder(p).ground_plan(["(pickup a)"])  # the helper ends holding a
    env = progress_state(p.init, helper_plan, BW)
    assert ("holding", "a") not in env and ("arm-empty",) not in env
    assert ("on-table", "a") not in env and ("clear", "b") in env
    nxt = handoff_problem(p, env, p.goal, BW)
    assert ("arm-empty",) in nxt.init  # the next agent's own initial agent state
    assert ("holding", "a") not in nxt.init
    assert nxt.goal == p.goal
    other = handoff_problem(p, env, Goal(frozenset({("clear", "b")})), BW)
    assert other.goal.positive == {("clear", "b")}
