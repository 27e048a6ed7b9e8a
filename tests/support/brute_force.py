"""Brute-force oracles of the execution-length tests, and the random cases they check."""

from __future__ import annotations

import itertools
import random
from collections import deque
from collections.abc import Collection, Sequence

from hypothesis import strategies as st

from tests.examples import TOY_AGENT
from twostep.makespan import (
    split_state,
)
from twostep.pddl import Fact, Goal, Problem
from twostep.plans.simulate import GroundAction, Grounder


def brute_force_length(
    plans: list[list[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Sequence[str],
) -> int | None:
    """Breadth-first search over every index tuple and every non-empty set of agents."""
    start = start_node(plans, init, agent_predicates)
    seen = {start}
    queue = deque([(start, 0)])
    while queue:
        node, depth = queue.popleft()
        done = finished(plans, node, goal)
        if done is not None:
            if done:
                return depth
            continue
        active = [i for i, p in enumerate(plans) if node[0][i] < len(p)]
        for size in range(1, len(active) + 1):
            for chosen in itertools.combinations(active, size):
                child = joint_step(plans, node, chosen, agent_predicates)
                if child is not None and child not in seen:
                    seen.add(child)
                    queue.append((child, depth + 1))
    return None


def random_case(
    rng: random.Random, prob: Problem
) -> tuple[list[list[GroundAction]], frozenset[Fact], Goal]:
    """Random initial state, plans (mostly random walks in hand-off order) and goal."""
    grounder = Grounder(prob)
    actions = [
        grounder.ground(f"({name} {obj})") for name in prob.domain.actions for obj in ("o1", "o2")
    ]
    env_facts = [(p, o) for p in ("f", "g") for o in ("o1", "o2")]
    init = frozenset(f for f in env_facts if rng.random() < 0.5)
    init |= {("h", "o1")} if rng.random() < 0.2 else set()
    environment, agent = split_state(init, TOY_AGENT)
    plans = []
    for _ in range(rng.randint(1, 4)):
        copy = agent
        plan = []
        for _ in range(rng.randint(0, 4)):
            view = environment | copy
            applicable = [a for a in actions if a.applicable(view)]
            action = rng.choice(applicable if applicable and rng.random() < 0.85 else actions)
            plan.append(action)
            if action.applicable(view):
                environment, copy = split_state(action.apply(view), TOY_AGENT)
        plans.append(plan)
    positive = frozenset(f for f in environment if rng.random() < 0.5)
    negative = frozenset(f for f in env_facts if f not in environment and rng.random() < 0.3)
    if rng.random() < 0.2:
        negative |= {("h", "o1")}
    return plans, init, Goal(positive, negative)


def joint_step(
    plans: list[list[GroundAction]],
    node: JointState,
    chosen: Sequence[int],
    agent_predicates: Sequence[str],
) -> JointState | None:
    """The state after the chosen agents act together, or None if they cannot."""
    indices, env, copies = node
    actions = [plans[i][indices[i]] for i in chosen]
    if not all(a.applicable(env | copies[i]) for i, a in zip(chosen, actions, strict=True)):
        return None
    if any(interfere(a, b, agent_predicates) for a, b in itertools.combinations(actions, 2)):
        return None
    delete = set().union(*(a.delete for a in actions))
    add = set().union(*(a.add for a in actions))
    new_env = frozenset(f for f in (env - delete) | add if f[0] not in agent_predicates)
    new_copies = list(copies)
    new_indices = list(indices)
    for i, a in zip(chosen, actions, strict=True):
        new_copies[i] = split_state(a.apply(env | copies[i]), agent_predicates)[1]
        new_indices[i] += 1
    return tuple(new_indices), new_env, tuple(new_copies)


def finished(plans: list[list[GroundAction]], node: JointState, goal: Goal) -> bool | None:
    """None while some plan has actions left, else whether the goal holds in every view."""
    indices, env, copies = node
    if any(i < len(p) for i, p in zip(indices, plans, strict=True)):
        return None
    return all(goal.holds(env | c) for c in copies) if copies else goal.holds(env)


def start_node(
    plans: list[list[GroundAction]], init: frozenset[Fact], agent_predicates: Sequence[str]
) -> JointState:
    environment, agent = split_state(init, agent_predicates)
    return (0,) * len(plans), environment, (agent,) * len(plans)


JointState = tuple[tuple[int, ...], frozenset[Fact], tuple[frozenset[Fact], ...]]


def interfere(a: GroundAction, b: GroundAction, agent_predicates: Sequence[str]) -> bool:
    """Graphplan interference on environment facts, written out plainly for the oracle."""

    def env(facts: frozenset[Fact]) -> set[Fact]:
        return {f for f in facts if f[0] not in agent_predicates}

    return any(
        env(x.delete) & (y.pre_positive | y.add) or env(x.add) & (y.pre_negative | y.delete)
        for x, y in ((a, b), (b, a))
    )


def brute_force(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> int | None:
    """Minimum makespan by breadth-first search over every subset of agents per step.

    Written from the rules (SPEC section 5) without the scorer's bit sets, bounds or
    dominance: each agent keeps its own copy of the agent-specific facts; a set of agents
    may act together when each action is applicable in (environment + own copy) and no
    two interfere on environment facts.
    """

    def private(fact: Fact) -> bool:
        return fact[0] in agent_predicates

    def interfere(a: GroundAction, b: GroundAction) -> bool:
        for x, y in ((a, b), (b, a)):
            if any(not private(f) for f in x.delete & (y.pre_positive | y.add)):
                return True
            if any(not private(f) for f in x.add & y.pre_negative):
                return True
        return False

    env0 = frozenset(f for f in init if not private(f))
    own0 = frozenset(f for f in init if private(f))
    start = (tuple(0 for _ in plans), env0, tuple(own0 for _ in plans))
    seen = {start}
    queue = deque([(start, 0)])
    while queue:
        (indices, env, owns), depth = queue.popleft()
        if all(i == len(p) for i, p in zip(indices, plans, strict=True)):
            ok = all(
                (f in owns[k] if private(f) else f in env)
                for f in goal.positive
                for k in range(len(plans))
            ) and not any(
                (f in owns[k] if private(f) else f in env)
                for f in goal.negative
                for k in range(len(plans))
            )
            if ok:
                return depth
            continue
        ready = [k for k in range(len(plans)) if indices[k] < len(plans[k])]
        for size in range(1, len(ready) + 1):
            for chosen in itertools.combinations(ready, size):
                actions = [plans[k][indices[k]] for k in chosen]
                if not all(
                    a.applicable(env | owns[k]) for a, k in zip(actions, chosen, strict=True)
                ):
                    continue
                if any(interfere(a, b) for a, b in itertools.combinations(actions, 2)):
                    continue
                new_env = set(env)
                new_owns = list(owns)
                for a in actions:
                    new_env -= {f for f in a.delete if not private(f)}
                for a in actions:
                    new_env |= {f for f in a.add if not private(f)}
                for a, k in zip(actions, chosen, strict=True):
                    new_owns[k] = frozenset(
                        (owns[k] - {f for f in a.delete if private(f)})
                        | {f for f in a.add if private(f)}
                    )
                new_indices = tuple(i + (1 if k in chosen else 0) for k, i in enumerate(indices))
                node = (new_indices, frozenset(new_env), tuple(new_owns))
                if node not in seen:
                    seen.add(node)
                    queue.append((node, depth + 1))
    return None


@st.composite
def cases(draw: st.DrawFn):
    """Plans that run one after the other in hand-off order (preconditions drawn from what
    holds then), sometimes with a random precondition that may break every schedule."""
    predicates = draw(st.sampled_from([(), ("h",), ("e",), ("e", "h")]))
    init = draw(st.frozensets(facts, min_size=1))
    agents = draw(st.sampled_from([1, 2, 3, 3]))
    own0 = frozenset(f for f in init if f[0] in predicates)
    env = frozenset(f for f in init if f[0] not in predicates)
    plans, owns = [], []
    for agent in range(agents):
        own, plan = own0, []
        for step in range(draw(st.integers(0, 4))):
            state = env | own
            if draw(st.integers(0, 9)) == 0:
                positive = draw_subset(draw, ENV + OWN, 1)  # anything: may never hold
            else:
                positive = draw_subset(draw, state, 2)
            negative = draw_subset(draw, set(ENV + OWN) - state, 1)
            add = draw_subset(draw, ENV + OWN, 2)
            delete = draw_subset(draw, ENV + OWN, 2) - add
            action = GroundAction(f"a{agent}", (str(step),), positive, negative, add, delete)
            plan.append(action)
            after = action.apply(state)
            env = frozenset(f for f in after if f[0] not in predicates)
            own = frozenset(f for f in after if f[0] in predicates)
        plans.append(plan)
        owns.append(own)
    shared_private = frozenset.intersection(*owns)
    goal = Goal(
        draw_subset(draw, env | shared_private, 2),
        draw_subset(draw, set(ENV) - env, 1),
    )
    return plans, init, goal, predicates


ENV = [("e", str(i)) for i in range(4)]  # environment facts


OWN = [("h", str(i)) for i in range(2)]  # candidate agent-specific facts


facts = st.sampled_from(ENV + OWN)


def draw_subset(draw: st.DrawFn, pool: Collection[Fact], most: int) -> frozenset[Fact]:
    if not pool:
        return frozenset()
    return draw(st.frozensets(st.sampled_from(sorted(pool)), max_size=most))
