"""The owner search of plan-deal (step 5): a dealt schedule made shorter by giving single
pieces to other agents.

The list schedule (:mod:`~twostep.dealing.schedule`) decides each piece's agent from
estimates: the walks of the SA plan's environment, actions that take one step. The
agents' real run (:mod:`~twostep.dealing.timeline`) and the joint clean-up after it
(:mod:`~twostep.dealing.cleanup`) differ: a termes robot finds the ramp it was to climb
still missing, a blocksworld arm that parks a block for another to move the one below
could just as well have held it. A first-improvement hill climb over the owners closes
some of that gap. In the order the pieces start, each piece is given in turn to each other
agent; the agents run again in time steps, and the move is kept when the cleaned run is
shorter (or as short, with fewer raw time steps). A trial whose raw run is more than one
step longer than the current one is not cleaned: the clean-up costs several runs, and
those trials hardly ever win.

The search is bounded by work, not time, so its result does not depend on the machine:
every run counts its actions, every clean-up four times its run's
(:data:`WORK`), and the search stops when the sum reaches the bound.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from twostep.dealing.model import DealError
from twostep.dealing.timeline import JointSteps

WORK = 40_000
"""The owner search's bound per deal, in simulated actions (module docstring)."""
CLEANUP_COST = 4
"""What one clean-up counts, per action of its run, against :data:`WORK`."""
SLACK = 1
"""How many time steps longer than the current one a trial's raw run may be and still be
cleaned (module docstring)."""


@dataclass
class Found:
    """The best owners found, their raw run and cleaned length, and the moves kept."""

    owner: list[int]
    steps: JointSteps
    length: int
    moves: int = 0


def search_owners(
    owner: Sequence[int],
    start: Sequence[int],
    agents: int,
    simulate: Callable[[Sequence[int]], JointSteps],
    cleaned_length: Callable[[JointSteps], int],
    work: int = WORK,
) -> Found:
    """The hill climb of the module docstring, from ``owner`` (each piece's agent);
    ``simulate`` runs the agents in time steps (raise :class:`DealError` when they cannot),
    ``cleaned_length`` is the length of a raw run after the joint clean-up."""
    steps = simulate(owner)
    spent = sum(map(len, steps)) * (1 + CLEANUP_COST)
    best = Found(list(owner), steps, cleaned_length(steps))
    for p in sorted(range(len(owner)), key=lambda p: (start[p], p)):
        for a in range(agents):
            if a == best.owner[p]:
                continue
            if spent >= work:
                return best
            trial = [*best.owner[:p], a, *best.owner[p + 1 :]]
            try:
                steps = simulate(trial)
            except DealError:
                continue
            size = sum(map(len, steps))
            spent += size
            if len(steps) > len(best.steps) + SLACK:
                continue
            spent += size * CLEANUP_COST
            length = cleaned_length(steps)
            if (length, len(steps)) < (best.length, len(best.steps)):
                best = Found(trial, steps, length, best.moves + 1)
                break
    return best
