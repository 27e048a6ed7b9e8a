"""The agents' plans in plan-deal (step 3): the dealt pieces replayed, each by its agent.

The pieces are replayed in the order of their start times (a linearisation the plan's
order allows; a piece whose walk does not exist yet waits for the next one the order
allows). Before each action its agent walks, where needed, to a place where the action
applies (:class:`~twostep.dealing.walks.Walker`). The replay is a sequential run of all
agents' plans, checked step by step, so a valid joint schedule exists; the parallel
scorer then finds the shortest.
"""

from __future__ import annotations

from collections.abc import Sequence

from twostep.dealing.cleanup import JointRun, joint_goal_holds
from twostep.dealing.model import DealError
from twostep.dealing.walks import Walker
from twostep.pddl import Fact, Problem
from twostep.progression import agent_part, environment_part
from twostep.strips import GroundAction


def replay_piece(
    walker: Walker,
    piece: Sequence[int],
    grounded: Sequence[GroundAction],
    environment: frozenset[Fact],
    own: frozenset[Fact],
) -> tuple[list[GroundAction], frozenset[Fact]]:
    """One agent runs one piece, walking before an action where needed: its actions and
    the state after them (raise :class:`DealError`)."""
    state = walker.problem.close(environment | own)
    steps: list[GroundAction] = []
    for i in piece:
        action = grounded[i]
        if not action.applicable(state):
            agent = agent_part(state, walker.agent_predicates)
            for step in walker.walk_to(
                environment_part(state, walker.agent_predicates), agent, action
            ):
                state = step.apply(state)
                steps.append(step)
            if not action.applicable(state):
                raise DealError(f"{action} does not apply")
        state = action.apply(state)
        steps.append(action)
    return steps, state


def replay(
    problem: Problem,
    walker: Walker,
    grounded: Sequence[GroundAction],
    pieces: Sequence[Sequence[int]],
    preds: Sequence[set[int]],
    owner: Sequence[int],
    start: Sequence[int],
    agents: int,
) -> tuple[JointRun, list[int]]:
    """The joint run of the dealt pieces and the order they were replayed in (module
    docstring); :class:`DealError` when a piece cannot be replayed or the goal is missed."""
    predicates = walker.agent_predicates
    pending = sorted(range(len(pieces)), key=lambda p: (start[p], p))
    environment = environment_part(problem.init, predicates)
    own_state = [agent_part(problem.init, predicates)] * agents
    replayed: list[int] = []
    done: set[int] = set()
    joint: JointRun = []
    while pending:
        for p in pending:
            if not preds[p] <= done:
                continue
            try:
                path, state = replay_piece(
                    walker, pieces[p], grounded, environment, own_state[owner[p]]
                )
            except DealError:
                continue
            break
        else:
            raise DealError(f"piece {pending[0]}: no agent can walk to where it applies")
        joint.extend((owner[p], step) for step in path)
        environment = environment_part(state, predicates)
        own_state[owner[p]] = agent_part(state, predicates)
        pending.remove(p)
        done.add(p)
        replayed.append(p)
    if not joint_goal_holds(problem, environment, own_state):
        raise DealError("the dealt plans do not reach the goal")
    return joint, replayed
