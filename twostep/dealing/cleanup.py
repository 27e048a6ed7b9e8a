"""Action elimination in plan-deal: drop the actions the goal does not need, from the SA
plan before it is dealt (step 0) and from the agents' joint run after (step 4).

Greedy action elimination (Fink and Yang's well-justified plans, greedy variant): drop an
action, and every later one that no longer applies, whenever the goal still holds without
them. Over a run of several agents each agent has its own copy of the agent-specific
facts, so with more hands a single agent's detours (a block parked on another to free its
only arm) are often no longer needed.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

from twostep.pddl import Fact, Problem
from twostep.progression import agent_part, environment_part
from twostep.strips import GroundAction, Grounder

JointRun = list[tuple[int, GroundAction]]  # (agent, action), in the order they run


def joint_goal_holds(
    problem: Problem, environment: frozenset[Fact], own: Sequence[frozenset[Fact]]
) -> bool:
    """The goal holds: environment literals once, agent-specific ones in every copy
    (derived ones in every agent's view)."""
    return all(problem.goal.holds(problem.close(environment | mine)) for mine in own)


def eliminate_joint(
    problem: Problem,
    joint: Sequence[tuple[int, GroundAction]],
    agents: int,
    agent_predicates: Collection[str],
) -> JointRun:
    """Greedy action elimination over a run of several agents (module docstring)."""
    start_own = agent_part(problem.init, agent_predicates)
    steps = list(joint)

    def run(
        env: frozenset[Fact], own: list[frozenset[Fact]], rest: Sequence[tuple[int, GroundAction]]
    ) -> tuple[frozenset[Fact], list[frozenset[Fact]], JointRun]:
        own = list(own)
        kept = []
        for a, action in rest:
            state = problem.close(env | own[a])
            if action.applicable(state):
                state = action.apply(state)
                env = environment_part(state, agent_predicates)
                own[a] = agent_part(state, agent_predicates)
                kept.append((a, action))
        return env, own, kept

    env = environment_part(problem.init, agent_predicates)
    own = [start_own] * agents
    i = 0
    while i < len(steps):
        end_env, end_own, kept = run(env, own, steps[i + 1 :])
        if joint_goal_holds(problem, end_env, end_own):
            steps[i:] = kept
            continue
        env, own, _ = run(env, own, steps[i : i + 1])
        i += 1
    return steps


def eliminate_actions(problem: Problem, plan: Sequence[GroundAction]) -> list[GroundAction]:
    """Greedy action elimination of one agent's plan: a valid plan no longer than ``plan``."""
    return [action for _, action in eliminate_joint(problem, [(0, a) for a in plan], 1, ())]


def clean_plan(problem: Problem, plan: Sequence[str]) -> list[GroundAction]:
    """Step 0: the SA plan, grounded, after action elimination."""
    return eliminate_actions(problem, Grounder(problem).ground_plan(plan))
