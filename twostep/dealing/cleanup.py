"""Action elimination in plan-deal: drop the actions the goal does not need, from the SA
plan before it is dealt (step 0) and from the agents' joint run after (step 4).

Greedy action elimination (Fink and Yang's well-justified plans, greedy variant): drop an
action, and every later one that no longer applies, whenever the goal still holds without
them. Over a run of several agents each agent has its own copy of the agent-specific
facts, so with more hands a single agent's detours (a block parked on another to free its
only arm) are often no longer needed.

Trying every action is quadratic in the run's length; two exact shortcuts keep it fast on
runs of hundreds of actions. A trial that reaches a state of the unchanged run at the same
action runs on as before from there, so the goal holds (accepted without simulating the
rest); and a trial in which a goal literal is wrong and no remaining action could set it
right has failed (rejected at once).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

from twostep.dealing.encoding import FactSpace, GoalBits, Owns, Step
from twostep.pddl import Problem
from twostep.plans.simulate import GroundAction, Grounder, PlanError

JointRun = list[tuple[int, Step]]  # (agent, step), in the order they run


class Elimination:
    """Greedy action elimination of one valid run of ``agents`` agents (module docstring)."""

    def __init__(self, goal: GoalBits, env: int, owns: Owns, run: Sequence[tuple[int, Step]]):
        self.goal = goal
        self.start = (env, owns)
        self.steps = list(run)
        self.work = 0  # actions simulated: what the clean-up cost, as a count

    def run(self) -> JointRun:
        """The run with every action dropped that the goal does not need."""
        i = 0
        self._prepare(0)
        while i < len(self.steps):
            kept = self._without(i)
            if kept is None:
                i += 1
                continue
            self.steps[i:] = kept
            self._prepare(i)
        return self.steps

    def _prepare(self, i: int) -> None:
        """The states before each action from ``i`` on, and what the actions from each
        index on could still set right (added or deleted facts), per agent."""
        steps, agents = self.steps, len(self.start[1])
        if i == 0:
            self.envs, self.owns = [self.start[0]], [self.start[1]]
        else:
            del self.envs[i + 1 :], self.owns[i + 1 :]
        env, owns = self.envs[i], self.owns[i]
        self.work += len(steps) - i
        for a, step in steps[i:]:
            if i == 0 and not step.applicable(env, owns[a]):
                raise PlanError(f"not a valid run: {step} does not apply")
            new_env, own = step.apply(env, owns[a])
            env, owns = new_env, (*owns[:a], own, *owns[a + 1 :])
            self.envs.append(env)
            self.owns.append(owns)
        n = len(steps)
        # what later actions set, from each index on: only the entries after i are read
        # from now on (by _without(i) and later calls), so only those are made
        self.adds_env, self.dels_env = [0] * (n + 1), [0] * (n + 1)
        self.adds_own = [[0] * agents for _ in range(n + 1)]
        self.dels_own = [[0] * agents for _ in range(n + 1)]
        for k in range(n - 1, i, -1):
            a, step = steps[k]
            self.adds_env[k] = self.adds_env[k + 1] | step.add_env
            self.dels_env[k] = self.dels_env[k + 1] | step.del_env
            adds, dels = list(self.adds_own[k + 1]), list(self.dels_own[k + 1])
            adds[a] |= step.add_own
            dels[a] |= step.del_own
            self.adds_own[k], self.dels_own[k] = adds, dels

    def _lost_own(self, j: int, owns: Owns) -> bool:
        """An agent's goal literal is wrong before action ``j`` and no action of that
        agent from ``j`` on sets it."""
        goal, adds, dels = self.goal, self.adds_own[j], self.dels_own[j]
        return any(
            goal.pos_own & ~own & ~adds[a] or goal.neg_own & own & ~dels[a]
            for a, own in enumerate(owns)
        )

    def _without(self, i: int) -> list[tuple[int, Step]] | None:
        """The actions after ``i`` that still apply once ``i`` is dropped, when the goal
        still holds without it (else None). The hot loop of the clean-up: written out (the
        actions it simulated, j - i, are counted in :attr:`work` where it ends)."""
        steps, envs, owns_at = self.steps, self.envs, self.owns
        adds_env, dels_env = self.adds_env, self.dels_env
        goal = self.goal
        pos_env, neg_env = goal.pos_env, goal.neg_env
        own_goal = bool(goal.pos_own or goal.neg_own)
        env, owns = envs[i], owns_at[i]
        kept: list[tuple[int, Step]] = []
        for j in range(i + 1, len(steps)):
            if env == envs[j] and owns == owns_at[j]:
                self.work += j - i
                return kept + steps[j:]  # back on the unchanged run: it reaches the goal
            # a goal literal wrong that no later action sets right: the goal is lost
            if pos_env & ~(env | adds_env[j]) or neg_env & env & ~dels_env[j]:
                self.work += j - i
                return None
            if own_goal and not j & 7 and self._lost_own(j, owns):
                self.work += j - i
                return None  # agent literals: checked now and then, a shortcut all the same
            entry = steps[j]
            a, step = entry
            own = owns[a]
            if step.space is not None:  # not exact as bits: the grounded model decides
                if step.applicable(env, own):
                    env, own = step.apply(env, own)
                    owns = (*owns[:a], own, *owns[a + 1 :])
                    kept.append(entry)
            elif (
                env & step.pre_env == step.pre_env
                and own & step.pre_own == step.pre_own
                and not (env & step.neg_env or own & step.neg_own)
            ):
                env = (env & ~step.del_env) | step.add_env
                owns = (*owns[:a], (own & ~step.del_own) | step.add_own, *owns[a + 1 :])
                kept.append(entry)
        self.work += len(steps) - 1 - i
        return kept if goal.holds(env, owns) else None


def eliminate_joint(
    problem: Problem,
    joint: Sequence[tuple[int, GroundAction]],
    agents: int,
    agent_predicates: Collection[str],
) -> list[tuple[int, GroundAction]]:
    """Greedy action elimination over a valid run of several agents (module docstring)."""
    space = FactSpace(problem, agent_predicates, ())
    env, own = space.bits(problem.init)
    run = [(a, space.step(action)) for a, action in joint]
    kept = Elimination(space.goal(), env, (own,) * agents, run).run()
    return [(a, step.action) for a, step in kept]


def eliminate_actions(problem: Problem, plan: Sequence[GroundAction]) -> list[GroundAction]:
    """Greedy action elimination of one agent's plan: a valid plan no longer than ``plan``."""
    return [action for _, action in eliminate_joint(problem, [(0, a) for a in plan], 1, ())]


def clean_plan(problem: Problem, plan: Sequence[str]) -> list[GroundAction]:
    """Step 0: the SA plan, grounded, after action elimination."""
    return eliminate_actions(problem, Grounder(problem).ground_plan(plan))
