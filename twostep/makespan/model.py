"""What the parallel-length search returns and raises, and the environment/agent state split."""

from __future__ import annotations

from collections.abc import Collection, Iterable
from dataclasses import dataclass

from twostep.pddl import Fact

MODES = ("exact", "paper")

DEFAULT_MAX_NODES = 2_000
"""Node budget of the search. A node costs about 0.1 ms with 4 agents and up to 1 ms
with 16 sharing two cells (pair bounds for every pair), so this stays within seconds."""

DEFAULT_TIME_LIMIT_S = 10.0
"""Time budget of the search in seconds: a backstop for the node budget on machines or
tasks where nodes are slow. Unlike the node budget it makes the answer depend on the
machine, so the node budget is the one that usually stops the search."""


@dataclass(frozen=True)
class SearchBudget:
    """How much search the exact scorer may spend once it has a schedule in hand.

    Past either limit it returns the best schedule found with ``exact=False`` and a
    proven ``lower_bound`` (see :func:`~twostep.makespan.parallel_length`); None: no
    limit. Both defaults keep a pipeline run from hanging on a hard schedule.
    """

    max_nodes: int | None = DEFAULT_MAX_NODES
    time_limit_s: float | None = DEFAULT_TIME_LIMIT_S


DEFAULT_SEARCH_BUDGET = SearchBudget()

Schedule = tuple[tuple[tuple[int, str], ...], ...]
"""Per time step, the (agent index, action text) pairs that act in it, in agent order."""


@dataclass(frozen=True)
class ParallelExecution:
    """A joint schedule of per-agent plans and its makespan."""

    length: int
    """Makespan: the number of time steps."""
    steps: Schedule
    """Per time step: (agent index, action text), agents in index order."""
    mode: str
    """``"exact"`` or ``"paper"``."""
    nodes_expanded: int
    """Search nodes expanded, a measure of effort for benchmarks."""
    exact: bool = True
    """Whether ``length`` is proven the shortest of the mode. False when the search hit
    its node budget and returned the best schedule found (still a valid schedule)."""
    lower_bound: int = -1
    """A proven lower bound on the shortest length; equals ``length`` when ``exact``
    (left out, it is set to ``length``)."""

    def __post_init__(self) -> None:
        if self.lower_bound < 0:
            object.__setattr__(self, "lower_bound", self.length)

    @property
    def gap(self) -> int:
        """``length - lower_bound``: 0 when exact."""
        return self.length - self.lower_bound


class ScheduleError(Exception):
    """No schedule of the plans reaches the goal, or a given schedule is invalid.

    ``agent`` is the agent index, ``step`` the 1-based step in that agent's plan, ``action``
    its text and ``precondition`` the failing precondition as PDDL; a failure at the end
    names the goal literal in ``goal`` instead. ``time_step`` (1-based) is set when a
    given joint schedule is checked.
    """

    def __init__(
        self,
        message: str,
        *,
        agent: int | None = None,
        step: int | None = None,
        action: str | None = None,
        precondition: str | None = None,
        goal: str | None = None,
        time_step: int | None = None,
    ):
        super().__init__(message)
        self.message = message
        self.agent = agent
        self.step = step
        self.action = action
        self.precondition = precondition
        self.goal = goal
        self.time_step = time_step


def split_state(
    state: Iterable[Fact], agent_predicates: Collection[str]
) -> tuple[frozenset[Fact], frozenset[Fact]]:
    """Split ``state`` into (environment facts, agent-specific facts) by predicate."""
    environment: set[Fact] = set()
    agent: set[Fact] = set()
    for fact in state:
        (agent if fact[0] in agent_predicates else environment).add(fact)
    return frozenset(environment), frozenset(agent)
