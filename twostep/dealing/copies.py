"""Copies: an agent does a piece with whichever of its interchangeable movers stands ready.

Every agent has its own copy of the agent facts (SPEC §3), so in a task with several
robots each agent has every robot, each where the task starts it. The SA plan picks one
robot for each carry; once the pieces are dealt, the agent that takes a piece may have
that robot far away (it drove it elsewhere for an earlier piece) while another of its
robots stands where the piece begins. The piece's *copies* are the piece done with another
mover (an object that stays in an agent fact an action moves: :func:`~twostep.dealing.rebind.movers`)
of the same type, renamed with the objects its own agent facts name in the initial state (a
robot's grippers to the other robot's).

A copy is kept only when its actions change nothing else: each renamed action grounds,
is exact as bits, and has the same environment bits as the action it stands for (what it
needs, forbids, adds and deletes), so the plan's order and every other agent meet the same
environment whichever copy an agent takes. A task whose goal names agent facts has no
copies (the goal could name the robot).

In the agents' run (:mod:`~twostep.dealing.timeline`), an agent that begins a piece whose
first action does not apply where it stands takes the first copy whose first action does
and whose agent facts beyond where it stands (the grippers free) carry it through the piece;
otherwise it walks, as before.

The *mover cut* (:func:`mover_pieces`) cuts the plan into pieces by mover: each robot's
actions, cut where its own grippers are free again. The free cut waits until the agent
holds nothing at all, so where the SA plan lets two robots work at once their trips make
one piece; by mover they are two, which two agents can do at once.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

from twostep.dealing.encoding import FactSpace, Step
from twostep.dealing.rebind import matching, movers, rename_action
from twostep.decomposers.goal_split import positional_predicates
from twostep.pddl import Fact, Problem
from twostep.plans.simulate import GroundAction, Grounder, PlanError

COPIES = 8
"""Copies made of one piece, at most."""


def piece_copies(
    problem: Problem,
    space: FactSpace,
    steps: Sequence[Step],
    pieces: Sequence[Sequence[int]],
    agent_predicates: Collection[str],
    moving: frozenset[str] | None = None,
) -> dict[int, list[list[Step]]]:
    """Each piece's copies (module docstring), aligned with its actions; pieces without
    any are left out. ``moving``: the task's movers, when the caller has them."""
    goal = space.goal()
    if goal.space is not None or goal.pos_own or goal.neg_own:
        return {}
    agent = frozenset(agent_predicates)
    if moving is None:
        moving = task_movers(problem, agent)
    if not moving:
        return {}
    types = problem.all_objects
    grounder = Grounder(problem)
    own = {  # each mover's own facts in the initial state (a robot's grippers free)
        mover: frozenset(
            f for f in problem.init if mover in f[1:] and f[0] in agent
            and f[0] not in space.positional
        )
        for mover in moving
    }  # fmt: skip
    found: dict[int, list[list[Step]]] = {}
    for p, piece in enumerate(pieces):
        originals = [steps[i] for i in piece]
        busy = {o for step in originals for o in step.action.args}
        mine = sorted(busy & moving)
        if len(mine) != 1:
            continue
        mover = mine[0]
        copies: list[list[Step]] = []
        for other in sorted(moving - busy):
            if len(copies) >= COPIES:
                break
            if types[other] != types[mover]:
                continue
            names = matching(own[mover], own[other], mover, other, busy, types)
            if names is None:
                continue
            copy = _renamed(space, grounder, originals, names)
            if copy is not None:
                copies.append(copy)
        if copies:
            found[p] = copies
    return found


def _renamed(
    space: FactSpace, grounder: Grounder, originals: Sequence[Step], names: dict[str, str]
) -> list[Step] | None:
    """The piece's steps renamed, or None when one does not ground, is not exact, or
    touches the environment otherwise than the action it stands for."""
    copy = []
    for original in originals:
        try:
            action = grounder.ground(rename_action(str(original.action), names))
        except PlanError:
            return None
        step = space.step(action)
        if not step.exact or (step.pre_env, step.neg_env, step.add_env, step.del_env) != (
            original.pre_env,
            original.neg_env,
            original.add_env,
            original.del_env,
        ):
            return None
        copy.append(step)
    return copy


def task_movers(problem: Problem, agent_predicates: Collection[str]) -> frozenset[str]:
    """The task's movers: objects that stay in a positional agent fact an action moves
    (a robot in ``at-robby``)."""
    positional = positional_predicates(problem.domain) & frozenset(agent_predicates)
    return movers(problem, positional)


def carries_through(own: int, piece: Sequence[Step], where: int) -> bool:
    """Whether an agent with own facts ``own`` meets every own precondition of ``piece``
    beyond where it stands (walks see to that), one action after the other."""
    for step in piece:
        needs, forbids = step.pre_own & ~where, step.neg_own & ~where
        if own & needs != needs or own & forbids:
            return False
        own = (own & ~step.del_own) | step.add_own
    return True


def mover_pieces(
    problem: Problem,
    plan: Sequence[GroundAction],
    agent_predicates: Collection[str],
    moving: frozenset[str] | None = None,
) -> list[list[int]] | None:
    """The ``mover`` cut: each mover's actions, cut where its own agent facts beyond where
    it stands are as in the initial state again (a robot's grippers free), whatever the
    other movers do meanwhile (the ``free`` cut waits until every robot is free at once);
    None when the task has no movers or an action moves none or several of them."""
    agent = frozenset(agent_predicates)
    if moving is None:
        moving = task_movers(problem, agent)
    if not moving:
        return None
    capacity = agent - positional_predicates(problem.domain)
    mine: list[str] = []
    for action in plan:
        found = set(action.args) & moving
        if len(found) != 1:
            return None
        mine.append(found.pop())

    def own(state: frozenset[Fact], mover: str) -> frozenset[Fact]:
        return frozenset(f for f in state if f[0] in capacity and mover in f[1:])

    free = {mover: own(problem.init, mover) for mover in set(mine)}
    state = problem.init
    open_pieces: dict[str, list[int]] = {}
    pieces: list[list[int]] = []
    for i, (action, mover) in enumerate(zip(plan, mine, strict=True)):
        state = action.apply(state)
        open_pieces.setdefault(mover, []).append(i)
        if own(state, mover) == free[mover]:
            pieces.append(open_pieces.pop(mover))
    pieces += open_pieces.values()
    return sorted(pieces)
