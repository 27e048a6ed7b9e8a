"""What a deal is: :class:`Deal`, the outcome of dealing one SA plan, :class:`DealError`,
and the clock dealing time is measured by (:func:`cpu_seconds`)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TypeAlias

SearchKey: TypeAlias = tuple[int, str, str, bool, "SearchKey | None"]
"""One owner search of a dealer (:meth:`~twostep.dealing.deal.Dealer.improve`): its agents,
cut, order and stealing, and the search whose owners it starts from (None: the list
schedule's)."""


def cpu_seconds() -> float:
    """The clock of dealing time: this process's CPU time. Fast Downward's planner time,
    which dealing is compared with, is CPU time too (of its processes), so the two compare
    on a busy machine, where wall-clock time counts the waits for a core."""
    return time.process_time()


class DealError(Exception):
    """The SA plan could not be dealt (a walk not found, a piece not applicable)."""


@dataclass
class Deal:
    """What :func:`twostep.dealing.deal_plan` decided: pieces, their agents, the agents' plans."""

    pieces: list[list[int]]  # SA action indices of each piece, in the order replayed
    owner: list[int]  # per piece: its agent (0-based)
    plans: list[list[str]]  # per agent, its actions
    estimate: int  # the list schedule's makespan, in actions
    walks: int  # walking actions the agents' plans have (SA's own were dropped)
    cleaned: int  # the SA plan's length after action elimination
    schedule: list[list[tuple[int, str]]]  # per time step: (agent, action), a valid joint schedule
    offloaded: bool = False  # every replay was stuck: pieces offloaded from the plan's run
    moves: int | None = None  # the owner search's kept moves (None: not searched)
    search: SearchKey | None = None  # the owner search that made it (None: not searched)
