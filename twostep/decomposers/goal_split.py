"""``goal-split``: our LLM-free decomposer, the offline default and a baseline for the LLM.

Algorithm, for a task with goal G and N agents (N-1 helpers and the main agent):

1. *Open literals.* Keep the environment literals of G that do not hold initially
   (agent-specific literals concern every agent and are handled in step 4).
2. *Components.* Two open literals belong together when they share an object that few
   open literals mention (at most ``link_degree``, default 2). Objects that many literals
   mention are shared places or containers (a room, the boot): linking through them would
   glue the whole goal into one piece. Towers in blocksworld, one hub's wheel, nut and
   inflation in tyreworld, and single cocktails in barman come out as components.
3. *Balancing.* Components are dealt to N buckets, largest first, each to the currently
   lightest bucket (longest-processing-time rule). Bucket 0 stays with the main agent; the
   other non-empty buckets become helper subgoals. The main agent always plans for the
   full goal, so what a helper does not finish, the main agent does.
4. *Release conditions.* A helper must not keep what the main agent may need. Every
   helper subgoal gets (a) the agent-specific literals of G (e.g. termes'
   ``(not (has-block))``) and (b) the initial agent-specific facts of predicates that
   describe holding capacity rather than position (``arm-empty``, ``handempty``,
   ``free``): a predicate counts as positional when some action both adds and deletes it
   (moving from one place to another), and positional facts are left free.

The result is deterministic. A task whose open goal forms a single component (e.g. one
termes tower) yields no helper: TwoStep then returns the single-agent plan.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Collection

from twostep.decomposers.base import DecompositionRequest, SubgoalProposal
from twostep.pddl import Domain, Fact, Goal, Problem
from twostep.pddl.lifted import EffectAtom, effect_parts
from twostep.plans.progression import agent_part, environment_part


def positional_predicates(domain: Domain) -> set[str]:
    """Predicates that some action both adds and deletes (an agent moving, say), whatever
    the state and the objects: effects under a ``when`` or a ``forall`` do not count (a
    lift's stop that lets some passengers in and others out changes what it carries, not
    where it is)."""
    found: set[str] = set()
    for action in domain.actions.values():
        if action.is_strips:
            added = {a.predicate for a in action.add}
            deleted = {a.predicate for a in action.delete}
        else:
            parts = [p for p in effect_parts(action.effect)
                     if isinstance(p, EffectAtom) and not p.conditional]  # fmt: skip
            added = {str(p.atom[0]) for p in parts if p.positive}
            deleted = {str(p.atom[0]) for p in parts if not p.positive}
        found |= added & deleted
    return found


def open_goal_components(
    problem: Problem, agent_predicates: Collection[str], link_degree: int = 2
) -> list[list[Fact]]:
    """Connected groups of the open environment goal literals (see the module docstring)."""
    open_literals = sorted(environment_part(problem.goal.positive - problem.init, agent_predicates))
    degree: dict[str, int] = defaultdict(int)
    for fact in open_literals:
        for obj in set(fact[1:]):
            degree[obj] += 1
    parent = list(range(len(open_literals)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    first_with: dict[str, int] = {}
    for i, fact in enumerate(open_literals):
        for obj in fact[1:]:
            if degree[obj] > link_degree:
                continue
            if obj in first_with:
                parent[find(i)] = find(first_with[obj])
            else:
                first_with[obj] = i
    groups: dict[int, list[Fact]] = defaultdict(list)
    for i, fact in enumerate(open_literals):
        groups[find(i)].append(fact)
    return sorted(groups.values(), key=lambda g: (-len(g), g))


def release_literals(problem: Problem, agent_predicates: Collection[str]) -> Goal:
    """What every helper must leave true at its end (step 4 of the module docstring)."""
    capacity = set(agent_predicates) - positional_predicates(problem.domain)
    positive = agent_part(problem.goal.positive, agent_predicates)
    negative = agent_part(problem.goal.negative, agent_predicates)
    positive |= agent_part(problem.init, capacity)
    return Goal(positive, negative - positive)


def split_goal(
    problem: Problem, agents: int, agent_predicates: Collection[str], link_degree: int = 2
) -> list[Goal]:
    """Helper subgoals (at most ``agents - 1``) for ``problem``."""
    if agents < 2:
        return []
    components = open_goal_components(problem, agent_predicates, link_degree)
    if len(components) < 2:
        return []
    buckets: list[list[Fact]] = [[] for _ in range(agents)]
    for component in components:  # largest first
        lightest = min(range(agents), key=lambda b: (len(buckets[b]), b))
        buckets[lightest].extend(component)
    release = release_literals(problem, agent_predicates)
    return [
        Goal(frozenset(bucket) | release.positive, release.negative)
        for bucket in buckets[1:]
        if bucket
    ]


class GoalSplitDecomposer:
    """Decomposer protocol wrapper around :func:`split_goal`."""

    name = "goal-split"

    def __init__(self, agent_predicates: Collection[str], link_degree: int = 2):
        self.agent_predicates = frozenset(agent_predicates)
        self.link_degree = link_degree

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        goals = split_goal(
            request.task.problem, request.agents, self.agent_predicates, self.link_degree
        )
        return [
            SubgoalProposal(helper=i, pddl=goal.to_pddl()) for i, goal in enumerate(goals, start=1)
        ]
