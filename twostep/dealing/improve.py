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
shorter (or as short, with fewer raw time steps). Passes over the pieces repeat while one
keeps a move: a piece that could not move at first may move once others have. A trial
whose raw run is more than one step longer than the current one is not cleaned: the
clean-up costs several runs, and those trials hardly ever win. Nor does the search go on
once the run is as short as the longest chain of the plan's order
(:meth:`~twostep.dealing.deal.Dealer.chain`) and its clean-up dropped nothing: every run of
these pieces takes that chain's actions one after the other (tyreworld's one jack), so only
a clean-up could make one shorter.

The search is bounded by work, not time, so its result does not depend on the machine:
the runs, their walks and the clean-ups count what they do (agents' turns and pieces
looked at, states the walk searches reach and moves their relaxed check looks at, actions
simulated), and the search stops when the count reaches its bound (:func:`work_bound`):
:data:`WORK` times (N - 1)² for N agents. A pass makes N - 1 trials per piece, and plan-deal
starts the search for N agents where the one for N - 1 ended when that is shorter than
every deal to N agents (:meth:`~twostep.dealing.deal.Dealer.improve`), so the larger
search has the newly idle agent to fill too. On the benchmark's termes tasks, where the
searches run out of work, this spends less in all than a flat bound per search did (for
N = 4, 140,000 units over the searches for 2, 3 and 4 agents, against 180,000) and gains
more at N = 4 than it gives up at N = 2 (docs/results/methods.md has the numbers).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from twostep.dealing.model import DealError
from twostep.dealing.timeline import JointSteps

WORK = 10_000
"""The owner search's bound for 2 agents, in the runs' and clean-ups' own counts (module
docstring)."""
SLACK = 1
"""How many time steps longer than the current one a trial's raw run may be and still be
cleaned (module docstring)."""


def work_bound(agents: int) -> int:
    """The owner search's bound for ``agents`` agents: :data:`WORK` times (agents - 1)²
    (module docstring)."""
    return WORK * max(agents - 1, 1) ** 2


@dataclass
class Found:
    """The best owners found, their raw run and cleaned length, and the moves kept."""

    owner: list[int]
    steps: JointSteps
    length: int
    dropped: int  # the actions the clean-up dropped from the raw run
    moves: int = 0

    @classmethod
    def of(cls, owner: list[int], steps: JointSteps, cleaned: JointSteps, moves: int) -> Found:
        dropped = sum(map(len, steps)) - sum(map(len, cleaned))
        return cls(owner, steps, len(cleaned), dropped, moves)


def search_owners(
    owner: Sequence[int],
    start: Sequence[int],
    agents: int,
    simulate: Callable[[Sequence[int]], JointSteps],
    clean: Callable[[JointSteps], JointSteps],
    spent: Callable[[], int],
    floor: int = 0,
    work: int = WORK,
) -> Found:
    """The hill climb of the module docstring, from ``owner`` (each piece's agent);
    ``simulate`` runs the agents in time steps (raise :class:`DealError` when they cannot),
    ``clean`` gives a raw run's time steps after the joint clean-up, and ``spent`` the work
    both have done so far; no trial starts once it reaches ``work``, or once the cleaned
    run is no longer than ``floor`` and its clean-up dropped nothing. The passes end with
    the first that keeps no move."""
    steps = simulate(owner)
    best = Found.of(list(owner), steps, clean(steps), 0)
    order = sorted(range(len(owner)), key=lambda p: (start[p], p))
    moved = True
    while moved:  # passes over the pieces, while one keeps a move
        moved = False
        for p in order:
            for a in range(agents):
                if a == best.owner[p]:
                    continue
                if spent() >= work or (best.length <= floor and not best.dropped):
                    return best
                trial = [*best.owner[:p], a, *best.owner[p + 1 :]]
                try:
                    steps = simulate(trial)
                except DealError:
                    continue
                if len(steps) > len(best.steps) + SLACK:
                    continue
                cleaned = clean(steps)
                if (len(cleaned), len(steps)) < (best.length, len(best.steps)):
                    best = Found.of(trial, steps, cleaned, best.moves + 1)
                    moved = True
                    break
    return best
