"""``plan-deal``: the SA plan's pieces dealt to N agents, several pieces per agent.

TwoStep gives every helper one subgoal and plans the agents one after the other, so an
agent can only use what the agents before it left behind. On tasks whose work is a chain
of small, similar steps (termes blocks carried up one ramp, barman drinks made in one
shaker) that hand-off caps the overlap: multi-agent PDDL wins there because its agents
take turns on the chain. plan-deal goes beyond TwoStep's single hand-off and lets the
agents take turns on the SA plan itself:

0. *Clean-up*: greedy action elimination (:func:`eliminate_actions`) drops actions the
   goal does not need (a block placed and taken away again); lama-first's termes plans
   lose up to two thirds. The SA plan itself keeps its length in the results; the
   cleaned length is recorded beside it (``deal`` in result.json).
1. *Order and pieces*, as in :mod:`twostep.decomposers.plan_split` (steps 1-2): the
   deordering of the cleaned plan over environment facts (walking left out: it is found
   again in step 3), and its pieces, cut at free agent states (``cut="free"``) or tied by
   what the agent holds (``cut="holding"``).
2. *Dealing* (list scheduling without the hand-off constraint, at the grain of actions):
   ready pieces go one by one to the agent on which they start earliest; a piece may start
   before its predecessor pieces end, as long as each of its actions ends after the
   actions it needs (an agent fetches a block while another places the one before). An
   action's time is one step plus the walking before it in the SA plan. Ready pieces are
   taken by their longest path to the end (``order="critical"``, HLFET) or in the SA
   plan's order (``order="plan"``); ties go to an agent that made a predecessor piece.
   Any assignment is allowed, since no agent waits for another to be *planned*.
3. *Agent plans.* The pieces are replayed in the order of their start times (a
   linearisation the deordering allows; a piece whose walk does not exist yet waits for
   the next one the order allows), each by its agent. Walking (an action that
   changes no environment fact and only where the agent stands) is not replayed: before
   each action the agent walks, by breadth-first search over the domain's walking actions
   in the current environment, to a place where that action applies (often nowhere: it
   is already there). The replay is a sequential run of all agents' plans, checked step
   by step, so a valid joint schedule exists; the parallel scorer then finds the shortest.
   When no walk exists (the walk-free order of step 1 let a piece take a ramp away before
   another agent crossed it), the deal is made again with the walks' causal links kept.
4. *Joint clean-up*: action elimination again, over the replay with one copy of the
   agent facts per agent (:func:`eliminate_joint`): detours a single agent needed (a
   block parked on another to free its only arm) go.

Every action of an agent's plan is an action of Fast Downward's SA plan, or a shortest
walk found by the search above; the joint schedule is re-validated like every other.
The result is deterministic given the SA plan. :func:`run_plan_deal` deals with each cut
and order (four deals, no planner call), scores each and keeps the shortest, in a
:class:`~twostep.methods.twostep.RunResult` (the SA plan's planner time counts, as does the time
spent dealing).
"""

from __future__ import annotations

import bisect
import time
from collections import defaultdict, deque
from collections.abc import Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from twostep.decomposers.base import DecompositionRequest, SubgoalProposal
from twostep.decomposers.goal_split import positional_predicates
from twostep.decomposers.plan_split import (
    _merge_cycles,
    _topological_pieces,
    free_pieces,
    free_states,
    holding_pieces,
    plan_order,
)
from twostep.execution import ParallelExecution
from twostep.pddl import Fact, Problem
from twostep.pddl.model import ActionSchema, Atom
from twostep.progression import agent_part, environment_part
from twostep.strips import GroundAction, Grounder, PlanError

if TYPE_CHECKING:
    from twostep.benchmark import BenchmarkTask
    from twostep.methods.twostep import RunResult, Steps
    from twostep.planner import PlannerSettings, PlanResult

WALK_LIMIT = 20_000
"""States the walking search may visit for one action before the deal gives up."""


class DealError(Exception):
    """The SA plan could not be dealt (a walk not found, a piece not applicable)."""


@dataclass
class Deal:
    """What :func:`deal_plan` decided: pieces, their agents, and the agents' plans."""

    pieces: list[list[int]]  # SA action indices of each piece, in the order replayed
    owner: list[int]  # per piece: its agent (0-based)
    plans: list[list[str]]  # per agent, its actions
    estimate: int  # the list schedule's makespan, in actions
    walks: int  # walking actions the agents' plans have (SA's own were dropped)
    cleaned: int  # the SA plan's length after action elimination


def is_walking(
    action: GroundAction, agent_predicates: Collection[str], positional: Collection[str]
) -> bool:
    """No environment effect, and the agent effects only say where the agent stands."""
    effects = action.add | action.delete
    return all(f[0] in agent_predicates and f[0] in positional for f in effects)


class Walker:
    """Shortest walks of one agent: breadth-first over the domain's walking actions.

    ``universe`` holds every environment fact a walk may meet (the facts of the SA plan's
    states: a replay only runs that plan's actions, and walks change no environment
    fact). The walking actions that could apply where an agent stands are found once per
    place, by joining their preconditions against it, and filtered by the current state.
    """

    def __init__(
        self, problem: Problem, agent_predicates: Collection[str], universe: frozenset[Fact]
    ):
        self.problem = problem
        self.grounder = Grounder(problem)
        self.agent_predicates = frozenset(agent_predicates)
        positional = positional_predicates(problem.domain)
        self.schemas = [
            s
            for s in problem.domain.actions.values()
            if (s.add or s.delete)
            and all(a.predicate in self.agent_predicates and a.predicate in positional
                    for a in (*s.add, *s.delete))
        ]  # fmt: skip
        self.objects = problem.all_objects
        self.universe = environment_part(universe, agent_predicates)
        self._candidates: dict[frozenset[Fact], list[GroundAction]] = {}

    def candidates(self, own: frozenset[Fact]) -> list[GroundAction]:
        """Walking actions whose preconditions hold in the universe plus ``own``."""
        found = self._candidates.get(own)
        if found is None:
            state = self.universe | own
            by_predicate: dict[str, list[Fact]] = defaultdict(list)
            for fact in state:
                by_predicate[fact[0]].append(fact)
            found = []
            for schema in self.schemas:
                for binding in _bindings(schema, by_predicate, self.objects, self.problem):
                    names = (binding[v] for v, _ in schema.parameters)
                    try:
                        action = self.grounder.ground("(" + " ".join((schema.name, *names)) + ")")
                    except PlanError:
                        continue
                    if action.applicable(state):
                        found.append(action)
            found.sort(key=str)  # set order varies per process: walks must not
            self._candidates[own] = found
        return found

    def successors(
        self, environment: frozenset[Fact], own: frozenset[Fact]
    ) -> Iterator[GroundAction]:
        state = environment | own
        return (a for a in self.candidates(own) if a.applicable(state))

    def walk_to(
        self, environment: frozenset[Fact], own: frozenset[Fact], target: GroundAction
    ) -> list[GroundAction]:
        """The shortest walk after which ``target`` applies (raise :class:`DealError`)."""
        start = own
        parents: dict[frozenset[Fact], tuple[frozenset[Fact], GroundAction] | None] = {start: None}
        queue = deque([start])
        while queue:
            node = queue.popleft()
            if target.applicable(environment | node):
                path: list[GroundAction] = []
                while (entry := parents[node]) is not None:
                    node, step = entry
                    path.append(step)
                return path[::-1]
            if len(parents) > WALK_LIMIT:
                break
            for action in self.successors(environment, node):
                child = agent_part(action.apply(environment | node), self.agent_predicates)
                if child not in parents:
                    parents[child] = (node, action)
                    queue.append(child)
        raise DealError(f"no walk to where {target} applies")


def _bindings(
    schema: ActionSchema,
    by_predicate: Mapping[str, list[Fact]],
    objects: Mapping[str, str],
    problem: Problem,
) -> Iterator[dict[str, str]]:
    """Variable bindings under which every positive precondition is in the state (a join)."""
    atoms = sorted(schema.pre_positive, key=lambda a: len(by_predicate.get(a.predicate, ())))

    def extend(k: int, binding: dict[str, str]) -> Iterator[dict[str, str]]:
        if k == len(atoms):
            yield from _free_variables(schema, binding, objects, problem)
            return
        atom: Atom = atoms[k]
        for fact in by_predicate.get(atom.predicate, ()):
            if len(fact) != len(atom.terms) + 1:
                continue
            new = dict(binding)
            if all(
                _unify(term, value, new) for term, value in zip(atom.terms, fact[1:], strict=True)
            ):
                yield from extend(k + 1, new)

    yield from extend(0, {})


def _unify(term: str, value: str, binding: dict[str, str]) -> bool:
    if not term.startswith("?"):
        return term == value
    if term in binding:
        return binding[term] == value
    binding[term] = value
    return True


def _free_variables(
    schema: ActionSchema, binding: dict[str, str], objects: Mapping[str, str], problem: Problem
) -> Iterator[dict[str, str]]:
    """Bind parameters no precondition mentions to every object of their type (rare)."""
    free = [(v, t) for v, t in schema.parameters if v not in binding]
    if not free:
        yield binding
        return
    variable, kind = free[0]
    for name, its_type in objects.items():
        if problem.domain.is_subtype(its_type, kind):
            yield from _free_variables(schema, {**binding, variable: name}, objects, problem)


def eliminate_actions(problem: Problem, plan: Sequence[GroundAction]) -> list[GroundAction]:
    """Greedy action elimination: drop an action, and every later one that no longer
    applies, whenever the goal still holds without them (Fink and Yang's well-justified
    plans, greedy variant). The result is a valid plan no longer than ``plan``."""
    return [action for _, action in eliminate_joint(problem, [(0, a) for a in plan], 1, ())]


def clean_plan(problem: Problem, plan: Sequence[str]) -> list[GroundAction]:
    """Step 0: the SA plan, grounded, after action elimination."""
    return eliminate_actions(problem, Grounder(problem).ground_plan(plan))


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
        pieces = _merge_cycles(holding_pieces(problem, grounded, agent_predicates), edges)
    else:
        pieces = free_pieces(problem, grounded, agent_predicates)
    return _topological_pieces(pieces, edges)


def deal_plan(
    problem: Problem,
    plan: Sequence[str],
    agents: int,
    agent_predicates: Collection[str],
    cut: str = "free",
    order: str = "critical",
    cleaned: Sequence[GroundAction] | None = None,
) -> Deal:
    """Steps 0-4 of the module docstring for one SA plan and ``agents`` agents;
    ``cleaned`` is step 0's result when the caller has it (:func:`clean_plan`: one
    clean-up serves every cut and order).

    The order of step 1 leaves walking out; when the replay then finds no walk (a ramp
    taken away before an agent crossed it), the deal is made again with the walks' own
    causal links kept, each walk standing for the acting action it leads to.
    """
    grounded = list(cleaned) if cleaned is not None else clean_plan(problem, plan)
    try:
        return _deal(problem, grounded, agents, agent_predicates, cut, order, keep_walks=False)
    except DealError:
        return _deal(problem, grounded, agents, agent_predicates, cut, order, keep_walks=True)


def _deal(
    problem: Problem,
    grounded: list[GroundAction],
    agents: int,
    agent_predicates: Collection[str],
    cut: str,
    order: str,
    keep_walks: bool,
) -> Deal:
    positional = positional_predicates(problem.domain)
    walking = [is_walking(a, agent_predicates, positional) for a in grounded]
    acting = [i for i in range(len(grounded)) if not walking[i]]
    if keep_walks:  # a walk's links bind the acting action it leads to (else the one before)
        edges_all, _ = plan_order(problem, grounded, agent_predicates)
        leads = {}
        for i in range(len(grounded)):
            k = bisect.bisect_left(acting, i)  # the first acting action from i on
            leads[i] = acting[k] if k < len(acting) else (acting[-1] if acting else i)
        edges = {(leads[i], leads[j]) for i, j in edges_all if leads[i] != leads[j]}
    else:  # the order the acting actions need; walks are found again at replay (step 3)
        sub_edges, _ = plan_order(problem, [grounded[i] for i in acting], agent_predicates)
        edges = {(acting[i], acting[j]) for i, j in sub_edges}
    pieces = [[i for i in p if not walking[i]]
              for p in pieces_of(problem, grounded, agent_predicates, edges, cut)]  # fmt: skip
    pieces = [p for p in pieces if p]
    # an action's time: itself plus the walking just before it in the SA plan
    walk_before: dict[int, int] = {}
    for i in acting:
        j = i - 1
        while j >= 0 and walking[j]:
            j -= 1
        walk_before[i] = i - 1 - j
    piece_of = {i: p for p, members in enumerate(pieces) for i in members}
    preds: list[set[int]] = [set() for _ in pieces]
    action_preds: dict[int, list[int]] = defaultdict(list)
    for i, j in edges:
        if i in piece_of and j in piece_of and piece_of[i] != piece_of[j]:
            preds[piece_of[j]].add(piece_of[i])
            action_preds[j].append(i)

    # 2. list scheduling at the grain of actions: a piece may start before its predecessor
    # pieces end, as long as each of its actions comes after the actions it needs. Ready
    # pieces go in order of their longest path to the end of the plan (HLFET: chains that
    # gate the most work start first) with ``order="critical"``, in the SA plan's order
    # with ``order="plan"``.
    length = [sum(walk_before[i] + 1 for i in piece) for piece in pieces]
    succs: list[set[int]] = [set() for _ in pieces]
    for p, before in enumerate(preds):
        for q in before:
            succs[q].add(p)
    level = [0] * len(pieces)
    for p in reversed(range(len(pieces))):  # pieces come in a topological order
        level[p] = length[p] + max((level[q] for q in succs[p]), default=0)
    owner = [0] * len(pieces)
    start = [0] * len(pieces)
    done_at: dict[int, int] = {}  # action index -> the time step it ends
    free_at = [0] * agents
    # where each agent will stand (its positional facts), and the SA plan's states, for
    # the walk to a piece's first action
    sa_states = [problem.init]
    for action in grounded:
        sa_states.append(action.apply(sa_states[-1]))
    standing = [frozenset(f for f in st if f[0] in positional and f[0] in agent_predicates)
                for st in sa_states]  # fmt: skip
    resting = agent_part(problem.init, agent_predicates) - standing[0]
    at = [standing[0]] * agents
    walker = Walker(problem, agent_predicates, frozenset().union(*sa_states))
    walk_cache: dict[tuple[frozenset[Fact], int], int] = {}

    def walk_length(position: frozenset[Fact], i: int, default: int) -> int:
        key = (position, i)
        if key not in walk_cache:
            try:
                env = environment_part(sa_states[i], agent_predicates)
                walk_cache[key] = len(walker.walk_to(env, position | resting, grounded[i]))
            except DealError:
                walk_cache[key] = default
        return walk_cache[key]

    waiting = [len(before) for before in preds]
    ready_pieces = [p for p in range(len(pieces)) if not waiting[p]]
    while ready_pieces:
        p = min(ready_pieces, key=lambda q: (-level[q], q) if order == "critical" else (q,))
        ready_pieces.remove(p)
        piece = pieces[p]

        def timing(a: int, piece: list[int]) -> tuple[int, list[int]]:
            """When agent ``a`` could start the piece, and when each action would end."""
            offsets: list[int] = []  # counted from the piece's start
            elapsed = 0
            for k, i in enumerate(piece):
                walk = walk_before[i]
                if k == 0:  # from where agent a will stand, in the SA plan's environment
                    walk = walk_length(at[a], i, walk)
                elapsed += walk + 1
                offsets.append(elapsed)
            ready = max(
                (done_at[q] - offset + 1 for i, offset in zip(piece, offsets, strict=True)
                 for q in action_preds[i]),
                default=0,
            )  # fmt: skip
            return max(ready, free_at[a], 0), offsets

        timings = [timing(a, piece) for a in range(agents)]
        best = min(
            range(agents),
            key=lambda a: (
                timings[a][0] + timings[a][1][-1],
                -sum(owner[q] == a for q in preds[p]),
                free_at[a],
                a,
            ),
        )
        owner[p] = best
        start[p], offsets = timings[best]
        for i, offset in zip(piece, offsets, strict=True):
            done_at[i] = start[p] + offset
        free_at[best] = start[p] + offsets[-1]
        at[best] = standing[piece[-1] + 1]
        for q in succs[p]:
            waiting[q] -= 1
            if not waiting[q]:
                ready_pieces.append(q)
    finish = free_at

    # 3. replay in order of start time, walking where needed; a piece whose walk does not
    # exist yet waits for the next piece the order allows
    pending = sorted(range(len(pieces)), key=lambda p: (start[p], p))
    environment = environment_part(problem.init, agent_predicates)
    own_state = [agent_part(problem.init, agent_predicates)] * agents
    replayed: list[int] = []
    done: set[int] = set()
    joint: list[tuple[int, GroundAction]] = []  # the replay: (agent, action) in order
    while pending:
        for p in pending:
            if not preds[p] <= done:
                continue
            try:
                path, state = _replay(walker, pieces[p], grounded, environment, own_state[owner[p]])
            except DealError:
                continue
            break
        else:
            raise DealError(f"piece {pending[0]}: no agent can walk to where it applies")
        a = owner[p]
        joint.extend((a, step) for step in path)
        environment = environment_part(state, agent_predicates)
        own_state[a] = agent_part(state, agent_predicates)
        pending.remove(p)
        done.add(p)
        replayed.append(p)
    if not _joint_goal(problem, environment, own_state):
        raise DealError("the dealt plans do not reach the goal")
    # 4. what several agents no longer need (a block parked for want of a second hand)
    joint = eliminate_joint(problem, joint, agents, agent_predicates)
    walks = sum(is_walking(step, agent_predicates, positional) for _, step in joint)
    plans: list[list[str]] = [[] for _ in range(agents)]
    for a, step in joint:
        plans[a].append(str(step))
    return Deal(
        [pieces[p] for p in replayed],
        [owner[p] for p in replayed],
        plans,
        max(finish, default=0),
        walks,
        len(grounded),
    )


def _joint_goal(
    problem: Problem, environment: frozenset[Fact], own: Sequence[frozenset[Fact]]
) -> bool:
    """The goal holds: environment literals once, agent-specific ones in every copy."""
    return all(problem.goal.holds(environment | mine) for mine in own)


def eliminate_joint(
    problem: Problem,
    joint: Sequence[tuple[int, GroundAction]],
    agents: int,
    agent_predicates: Collection[str],
) -> list[tuple[int, GroundAction]]:
    """Greedy action elimination over a run of several agents, each with its own copy of
    the agent-specific facts: drop an action, and every later one that no longer applies,
    whenever the goal still holds. With more hands, a single agent's detours (a block
    parked on another to free the arm) are often no longer needed."""
    start_own = agent_part(problem.init, agent_predicates)
    steps = list(joint)

    def run(
        env: frozenset[Fact], own: list[frozenset[Fact]], rest: Sequence[tuple[int, GroundAction]]
    ) -> tuple[frozenset[Fact], list[frozenset[Fact]], list[tuple[int, GroundAction]]]:
        own = list(own)
        kept = []
        for a, action in rest:
            state = env | own[a]
            if action.applicable(state):
                state = action.apply(state)
                env = environment_part(state, agent_predicates)
                own[a] = agent_part(state, agent_predicates)
                kept.append((a, action))
        return env, own, kept

    env = environment_part(problem.init, agent_predicates)
    own = [start_own] * agents
    i = 0
    while i < len(steps):
        end_env, end_own, kept = run(env, own, steps[i + 1 :])
        if _joint_goal(problem, end_env, end_own):
            steps[i:] = kept
            continue
        env, own, _ = run(env, own, steps[i : i + 1])
        i += 1
    return steps


def _replay(
    walker: Walker,
    piece: Sequence[int],
    grounded: Sequence[GroundAction],
    environment: frozenset[Fact],
    own: frozenset[Fact],
) -> tuple[list[GroundAction], frozenset[Fact]]:
    """One agent runs one piece, walking before an action where needed: its actions and
    the state after them (raise :class:`DealError`)."""
    state = environment | own
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


CUTS = ("free", "holding")
ORDERS = ("critical", "plan")


class PlanDeal:
    """The decomposer-side handle of plan-deal (it makes plans, not subgoals).

    ``cut`` is ``"free"``, ``"holding"`` or ``"best"`` (both, the shorter schedule kept;
    the default). :func:`~twostep.methods.twostep.run_twostep` hands it to :func:`run_plan_deal`;
    ``propose`` is never asked.
    """

    needs_sa_plan = True

    def __init__(self, agent_predicates: Collection[str], cut: str = "best"):
        if cut not in (*CUTS, "best"):
            raise ValueError(f"plan-deal cut must be one of {(*CUTS, 'best')}, not {cut!r}")
        self.agent_predicates = frozenset(agent_predicates)
        self.cut = cut
        self.name = "plan-deal" if cut == "best" else f"plan-deal-{cut}"

    @property
    def cuts(self) -> tuple[str, ...]:
        return CUTS if self.cut == "best" else (self.cut,)

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        return []


def run_plan_deal(
    task: BenchmarkTask,
    agents: int,
    deal: PlanDeal,
    agent_predicates: Collection[str],
    settings: PlannerSettings,
    mode: str = "exact",
    seed: int = 0,
    sa_length: int | None = None,
    steps: Steps | None = None,
    sa_plan: PlanResult | None = None,
    fallback_if_longer: bool = True,
) -> RunResult:
    """Deal the SA plan to ``agents`` agents (each cut of ``deal``) and keep the shortest
    schedule; the SA plan when no deal works (or, with ``fallback_if_longer``, when the
    schedule is longer). ``extra["deal"]`` records each cut's outcome."""
    from twostep.execution import ScheduleError
    from twostep.methods.twostep import (
        DIRECT,
        AgentPlan,
        RunResult,
        _named_schedule,
        _use_single_agent_plan,
    )

    steps = steps or DIRECT
    start = time.perf_counter()
    problem = task.problem
    run = RunResult(task.domain_name, task.task_id, "twostep", agents, seed, sa_length=sa_length)
    run.origins = problem.domain.origins
    run.decomposer = deal.name
    if sa_plan is None:
        sa_plan = steps.plan(problem, settings)
    sa_steps = list(sa_plan.plan) if sa_plan.solved and sa_plan.plan is not None else None
    if run.sa_length is None and sa_steps is not None:
        run.sa_length = len(sa_steps)
    deal_time = score_time = 0.0
    best: tuple[ParallelExecution, list[list[str]]] | None = None
    tried: list[dict[str, object]] = []
    scored: dict[tuple[tuple[str, ...], ...], int] = {}
    chosen = 0
    cleaned: list[GroundAction] | None = None  # step 0 once, for every cut and order
    variants = [(c, o) for c in deal.cuts for o in ORDERS]
    for cut, order in variants if sa_steps is not None and agents > 1 else ():
        assert sa_steps is not None
        deal_start = time.perf_counter()
        row: dict[str, object] = {"cut": cut, "order": order}
        try:
            if cleaned is None:
                cleaned = clean_plan(problem, sa_steps)
            dealt = deal_plan(problem, sa_steps, agents, agent_predicates, cut, order, cleaned)
        except (DealError, PlanError) as error:
            row["error"] = str(error)
            tried.append(row)
            deal_time += time.perf_counter() - deal_start
            continue
        deal_time += time.perf_counter() - deal_start
        plans = [p for p in dealt.plans if p]
        row.update(pieces=len(dealt.pieces), walks=dealt.walks, cleaned_sa_length=dealt.cleaned,
                   agents_used=len(plans))  # fmt: skip
        key = tuple(map(tuple, plans))
        if key in scored:  # another cut or order dealt the same plans
            row.update(same_as=scored[key], exec_length=tried[scored[key]].get("exec_length"))
            tried.append(row)
            continue
        scored[key] = len(tried)
        score_start = time.perf_counter()
        try:
            execution = steps.score(problem, plans, agent_predicates, mode)
        except (ScheduleError, PlanError) as error:
            row["error"] = f"joint schedule invalid: {error}"
        else:
            row["exec_length"] = execution.length
            if best is None or execution.length < best[0].length:
                best = (execution, plans)
                chosen = len(tried)
        score_time += time.perf_counter() - score_start
        tried.append(row)
    run.score_time_s = score_time
    if best is not None:
        tried[chosen]["chosen"] = True
    run.extra["deal"] = tried
    if best is not None and fallback_if_longer and sa_steps and best[0].length > len(sa_steps):
        run.fallback = f"joint schedule longer than SA ({best[0].length} > {len(sa_steps)})"
        best = None
    run.planner_calls.append(AgentPlan("agent0", "single", problem.goal.to_pddl(), sa_plan))
    if best is not None:
        execution, plans = best
        names = [f"agent{k}" for k in range(len(plans))]
        run.agent_order = names
        run.plans = dict(zip(names, plans, strict=True))
        run.schedule = _named_schedule(execution, names)
        run.exec_length = execution.length
        run.exact, run.lower_bound = execution.exact, execution.lower_bound
        run.success = True
    else:
        if run.fallback is None:
            run.fallback = (
                "one agent" if agents < 2 and sa_steps is not None
                else "no SA plan to deal" if sa_steps is None
                else "; ".join(f"{r['cut']}: {r.get('error')}" for r in tried)
            )  # fmt: skip
        _use_single_agent_plan(run, sa_plan)
    run.extra["sa_time_included_s"] = round(sa_plan.planner_time_s, 4)
    run.state_editing_time_s = deal_time
    run.planning_time_s = sa_plan.planner_time_s + deal_time
    run.wall_time_s = time.perf_counter() - start
    return run
