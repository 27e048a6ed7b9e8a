"""Parallel execution length: how many time steps N sequential agent plans take together.

This is the paper's execution-length metric (its Algorithm 1), made exact for every N.

Model
    ``plans[i]`` is agent i's sequential plan. Plans come in hand-off order: each was planned
    from the environment state the previous ones left, so running them one after the other
    is a valid schedule when the plans are right, and where that run breaks is the
    diagnosis when no schedule exists (plans that only work interleaved, such as a
    multi-agent plan split per agent, are scored all the same). Facts whose predicate is
    agent-specific (``arm-empty``, ``holding`` in blocksworld) are private: every agent has
    its own copy, initialised to the agent-specific facts of the initial state, and only its
    own actions read or write it.
    All other facts form one shared environment. For STRIPS actions an agent's copy changes
    only through its own actions in a way fixed in advance, so its content after k actions
    is known and the search state is (plan indices, environment state). With conditional
    effects or derived facts an agent's effect on its copy may depend on the environment:
    the copies then join the search state (:mod:`twostep.makespan.compiled`), and the
    bounds that assume STRIPS steps (pairs, contention) and the symmetry reduction are left
    out.

Interference (Graphplan, extended to negative preconditions, conditional effects and axioms)
    Several agents may take their next actions in the same time step when every action's
    preconditions hold in the current state and no action possibly deletes a positive
    precondition of another or what another possibly adds, possibly adds a negative
    precondition of another or what another possibly deletes, or possibly changes a fact
    on which another's outcome depends beyond its precondition (a condition of one of its
    conditional effects, or a basic fact one of its derived preconditions is derived
    from). An action's *possible* adds and deletes are those of all its effects,
    conditional ones included, whether or not their conditions hold: a conservative rule,
    exactly Graphplan's for STRIPS actions. Only environment facts can interfere: agent
    copies are private. Each action's effects are evaluated in the state before the step;
    a step applies all deletes and then all adds, and derived facts are evaluated on the
    result; with no interference this equals applying the actions in any order.
    After the last step every goal literal must hold: environment literals on the shared
    state, agent-specific literals in every agent's copy, derived literals (a goal formula
    included) in every agent's view of the state.

Search
    Both modes run A* over (plan indices, environment state) with unit step cost. The bound
    h is the largest of the longest remaining plan, the contention bound below and, for
    every pair of agents whose plans interact, the exact makespan of those two plans with
    the other agents abstracted away (:class:`~twostep.makespan.bounds.PairProjection`,
    solved once up front, then a dict lookup per node). Every part is admissible, so the
    first goal node popped is optimal (a node reached again with a smaller g is expanded
    again, which keeps this true over canonical nodes); a pair that cannot reach its goal
    marks a dead end, which also refutes impossible cases quickly. The pair bound is what
    sees a main agent waiting for a helper's effect, the usual shape of hand-off plans.
    Ties on f go to the node with more progress (larger g, then fewer actions left), so
    cases without contention go straight down.

    A greedy list schedule (longest remaining plan first) gives an upper bound first; a
    contention bound (:class:`~twostep.makespan.bounds.ContentionBound`: agents that
    consume the same exclusive fact, such as a free cell, take turns) often meets it at
    the start, and then no search runs (N carts queueing at one hub). Otherwise A* stops
    when f reaches the greedy length, or at its budget (:class:`SearchBudget`: ``max_nodes``
    expanded nodes, ``time_limit_s`` seconds): then the greedy schedule comes back with
    ``exact=False`` and the proven ``lower_bound``.

    Interchangeable agents (:class:`~twostep.makespan.symmetry.Symmetry`: plans of the
    same shape up to their private facts, like carts driving their own tracks through
    the same hubs) make many nodes equivalent; A* visits one canonical node per
    relabelling of them, and pairs of agents the relabelling maps onto each other share
    one pair projection.

    * ``paper`` -- the successors of the paper's recursion: one agent alone, or all agents
      that still have actions together. Its memoised recursion computes the shortest path in
      exactly this graph, which A* finds without visiting every index tuple.
    * ``exact`` -- any non-empty set of applicable, pairwise non-interfering agents. One
      dominance rule keeps it fast; see :func:`~twostep.makespan.search.free_agents` for
      why it is safe.

Facts are numbered and states are Python ints used as bit sets, so a joint step is a few
integer operations. :func:`check_schedule` re-validates a schedule with plain frozensets,
independently of the search, and :func:`parallel_length` runs it on every result.

One job per module:

- :mod:`twostep.makespan.model`      :class:`ParallelExecution`, :class:`ScheduleError`, modes,
  :class:`SearchBudget`
- :mod:`twostep.makespan.diagnosis`  why no schedule exists (agent copies, hand-off run)
- :mod:`twostep.makespan.compiled`   plans as bit sets over numbered facts
- :mod:`twostep.makespan.bounds`     the A* lower bound (remaining plans, contention, pairs)
- :mod:`twostep.makespan.symmetry`   interchangeable agents and canonical nodes
- :mod:`twostep.makespan.search`     greedy upper bound, budgeted A* with each mode's successors
- :mod:`twostep.makespan.check`      :func:`check_schedule`, the independent re-validation
- :mod:`twostep.makespan.parallel`   :func:`parallel_length`, which ties them together
"""

from twostep.makespan.check import check_schedule
from twostep.makespan.model import (
    DEFAULT_SEARCH_BUDGET,
    MODES,
    ParallelExecution,
    Schedule,
    ScheduleError,
    SearchBudget,
    split_state,
)
from twostep.makespan.parallel import parallel_length

__all__ = [
    "DEFAULT_SEARCH_BUDGET",
    "MODES",
    "ParallelExecution",
    "Schedule",
    "ScheduleError",
    "SearchBudget",
    "check_schedule",
    "parallel_length",
    "split_state",
]
