"""One deal of an SA plan to N agents: steps 0-4 of :mod:`twostep.dealing`, in order.

:func:`deal_plan` cleans the plan (:mod:`~twostep.dealing.cleanup`), finds the order it
needs and its pieces (:func:`order_edges`, :func:`pieces_of`), deals the pieces
(:mod:`~twostep.dealing.schedule`), replays them (:mod:`~twostep.dealing.replay`) and
cleans the joint run again.
"""

from __future__ import annotations

import bisect
from collections.abc import Collection, Sequence

from twostep.dealing.cleanup import clean_plan, eliminate_joint
from twostep.dealing.model import Deal, DealError
from twostep.dealing.replay import replay
from twostep.dealing.schedule import ListScheduler, PieceOrder, WalkEstimate
from twostep.dealing.walks import Walker, is_walking
from twostep.decomposers.goal_split import positional_predicates
from twostep.decomposers.plan_split import (
    free_pieces,
    free_states,
    holding_pieces,
    merge_cycles,
    plan_order,
    topological_pieces,
)
from twostep.pddl import Fact, Problem
from twostep.strips import GroundAction

CUTS = ("free", "holding")
"""Where the plan is cut into pieces: at free agent states, or by what the agent holds."""
ORDERS = ("critical", "plan")
"""Which ready piece is dealt next: the longest path to the end first, or the plan's order."""


def order_edges(
    problem: Problem,
    grounded: Sequence[GroundAction],
    walking: Sequence[bool],
    agent_predicates: Collection[str],
    keep_walks: bool,
) -> set[tuple[int, int]]:
    """Step 1's order between the acting actions (indices into ``grounded``).

    Walking is left out (it is found again at replay); with ``keep_walks`` the walks'
    own causal links are kept instead, each walk standing for the acting action it leads
    to (or, after the last one, the action before it)."""
    acting = [i for i in range(len(grounded)) if not walking[i]]
    if not keep_walks:
        sub_edges, _ = plan_order(problem, [grounded[i] for i in acting], agent_predicates)
        return {(acting[i], acting[j]) for i, j in sub_edges}
    edges_all, _ = plan_order(problem, grounded, agent_predicates)
    leads = {}
    for i in range(len(grounded)):
        k = bisect.bisect_left(acting, i)  # the first acting action from i on
        leads[i] = acting[k] if k < len(acting) else (acting[-1] if acting else i)
    return {(leads[i], leads[j]) for i, j in edges_all if leads[i] != leads[j]}


def pieces_of(
    problem: Problem,
    grounded: Sequence[GroundAction],
    agent_predicates: Collection[str],
    edges: set[tuple[int, int]],
    cut: str,
) -> list[list[int]]:
    """Step 1's pieces (plan-split's step 2), in an order the deordering allows."""
    if cut == "holding":
        free_states(problem, grounded, agent_predicates)  # the plan must be applicable
        pieces = merge_cycles(holding_pieces(problem, grounded, agent_predicates), edges)
    else:
        pieces = free_pieces(problem, grounded, agent_predicates)
    return topological_pieces(pieces, edges)


def walks_before(walking: Sequence[bool]) -> dict[int, int]:
    """Per acting action: the walking actions just before it in the SA plan."""
    counts = {}
    for i in (i for i in range(len(walking)) if not walking[i]):
        j = i - 1
        while j >= 0 and walking[j]:
            j -= 1
        counts[i] = i - 1 - j
    return counts


def deal_plan(
    problem: Problem,
    plan: Sequence[str],
    agents: int,
    agent_predicates: Collection[str],
    cut: str = "free",
    order: str = "critical",
    cleaned: Sequence[GroundAction] | None = None,
) -> Deal:
    """Steps 0-4 of :mod:`twostep.dealing` for one SA plan and ``agents`` agents;
    ``cleaned`` is step 0's result when the caller has it (:func:`clean_plan`: one
    clean-up serves every cut and order).

    The order of step 1 leaves walking out; when the replay then finds no walk (a ramp
    taken away before an agent crossed it), the deal is made again with the walks' own
    causal links kept (:func:`order_edges`).
    """
    grounded = list(cleaned) if cleaned is not None else clean_plan(problem, plan)
    try:
        return deal_once(problem, grounded, agents, agent_predicates, cut, order, False)
    except DealError:
        return deal_once(problem, grounded, agents, agent_predicates, cut, order, True)


def deal_once(
    problem: Problem,
    grounded: list[GroundAction],
    agents: int,
    agent_predicates: Collection[str],
    cut: str,
    order: str,
    keep_walks: bool,
) -> Deal:
    """Steps 1-4 for a cleaned plan (raise :class:`DealError` when the replay fails)."""
    positional = positional_predicates(problem.domain)
    walking = [is_walking(a, agent_predicates, positional) for a in grounded]
    edges = order_edges(problem, grounded, walking, agent_predicates, keep_walks)
    pieces = [[i for i in p if not walking[i]]
              for p in pieces_of(problem, grounded, agent_predicates, edges, cut)]  # fmt: skip
    pieces = [p for p in pieces if p]
    piece_order = PieceOrder.of(pieces, edges)
    sa_states: list[frozenset[Fact]] = [problem.init]
    for action in grounded:
        sa_states.append(action.apply(sa_states[-1]))
    walker = Walker(problem, agent_predicates, frozenset().union(*sa_states))
    walks = WalkEstimate(walker, grounded, sa_states, positional)
    scheduler = ListScheduler(pieces, piece_order, walks_before(walking), walks, agents)
    schedule = scheduler.run(order)
    joint, replayed = replay(
        problem, walker, grounded, pieces, piece_order.preds, schedule.owner, schedule.start, agents
    )
    # 4. what several agents no longer need (a block parked for want of a second hand)
    joint = eliminate_joint(problem, joint, agents, agent_predicates)
    plans: list[list[str]] = [[] for _ in range(agents)]
    for a, step in joint:
        plans[a].append(str(step))
    return Deal(
        [pieces[p] for p in replayed],
        [schedule.owner[p] for p in replayed],
        plans,
        schedule.makespan,
        sum(is_walking(step, agent_predicates, positional) for _, step in joint),
        len(grounded),
    )
