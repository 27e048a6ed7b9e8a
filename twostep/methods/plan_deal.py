"""``plan-deal`` as a method: deal the SA plan to 1, 2, ..., N agents with every cut and
order of :mod:`twostep.dealing`, score the deals, and keep the shortest schedule.

The deals to fewer agents are candidates too (an agent may stay idle), so a run with N
agents is never longer than one with N-1: by construction, not by luck. The one-agent
deal is the cleaned SA plan (the SA plan after action elimination); it is the outcome
when no deal to two or more agents works or none is shorter, and ``fallback`` says so.
The SA plan itself is the outcome only when there is none to deal or one agent.

No planner call beyond the SA plan: the run's planning time is the SA plan's planner time
and the time spent dealing (CPU time, both: :func:`~twostep.dealing.model.cpu_seconds`). Deals that give the same plans are scored once. result.json
``deal`` records every deal tried (its agents, cut and order, pieces, walks, the cleaned
SA plan's length, the agents used, ``offloaded`` when every replay was stuck and the pieces
were offloaded from the plan's own run, its length or its error), ``deal_seconds`` where the
dealing time went and ``agents_used`` how many agents the outcome has.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Annotated, Any, Literal

from twostep.dealing import CUTS, Deal, Dealer, DealError, Way, ways
from twostep.dealing.model import SearchKey, cpu_seconds
from twostep.dealing.rebind import Rebinder
from twostep.makespan import ParallelExecution, ScheduleError, check_schedule
from twostep.methods.request import MethodRequest
from twostep.methods.result import (
    AgentPlan,
    Fallback,
    FallbackReason,
    MethodName,
    RunResult,
    RunStatus,
    adopt_sa_plan,
    adopt_schedule,
    count_sa_time,
    longer_than_sa,
    new_run,
    solved_steps,
)
from twostep.methods.single_agent import single_agent_plan
from twostep.plans.simulate import Grounder, PlanError

SCORED_UP_TO = 40
"""Deals of at most this many actions in all are scored by the parallel scorer, which
proves their shortest schedule in milliseconds; longer ones keep their own schedule (the
scorer's search grows fast with agents and length: seconds for 4 agents and 200 actions)."""

REBOUND = (("rounds", False, False), ("tails", True, True))
"""The rebound plans dealt beside the cleaned SA plan: (their rows' ``rebound``, with
tails, with resets; :meth:`~twostep.dealing.rebind.Rebinder.rebind`). The second resets
objects too: where no object is ready for a round, it is the plan the deal can spread
over the objects that are left used (barman's shakers)."""

BEST = "best"
DealCut = Annotated[str, Literal["free", "holding", "mover", "best"]]
"""plan-deal's ``cut`` option: one of :data:`~twostep.dealing.CUTS`, or :data:`BEST` (each);
the registry checks an option against the ``Literal`` of its annotation."""
"""The default cut: every cut of :data:`twostep.dealing.CUTS`, the shorter schedule kept."""

DEAL_WORK = 2_000_000
"""plan-deal's work budget for 2 agents, in the dealers' own counts
(:attr:`~twostep.dealing.Dealer.work`: agents' turns, walk searches, clean-up steps);
:func:`deal_budget` grows it with N."""
DEAL_WORK_MAX = 20_000_000
"""The most work plan-deal spends for any N (20 to 30 s of dealing here)."""


def deal_budget(agents: int) -> int:
    """plan-deal's work budget for ``agents`` agents: :data:`DEAL_WORK` x (N - 1)², at most
    :data:`DEAL_WORK_MAX`. On the benchmark's 100 tasks (and the stress and large sets)
    the deals to N <= 4 agents spend at most 1,641,222 units, a tenth of the budget for 4
    (``docs/bench/methods_deal.json``'s SA plans dealt again); when it runs out, dealing
    stops and the best deal so far is kept (result.json ``deal_budget`` says where)."""
    return min(DEAL_WORK * max(agents - 1, 1) ** 2, DEAL_WORK_MAX)


def deal_name(cut: str = BEST) -> str:
    """The run's ``decomposer`` name: ``plan-deal``, or ``plan-deal-<cut>`` for one cut."""
    return "plan-deal" if cut == BEST else f"plan-deal-{cut}"


@dataclass
class Trials:
    """Every deal tried (result.json ``deal`` rows), the shortest schedule, the time spent."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    best: tuple[ParallelExecution, list[list[str]]] | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    invalid: str | None = None  # why the SA plan given does not apply (nothing dealt)
    capped: int | None = None  # the most agents dealt to, when fewer than asked (the pieces)
    stopped: dict[str, int] | None = None  # where the work budget ran out (None: it did not)

    @property
    def deal_time_s(self) -> float:
        return sum(s for phase, s in self.seconds.items() if phase != "scoring")


def check_cut(cut: str) -> None:
    """Raise :class:`ValueError` unless ``cut`` is one of :data:`~twostep.dealing.CUTS` or
    :data:`BEST`."""
    if cut not in (*CUTS, BEST):
        raise ValueError(f"plan-deal cut must be one of {(*CUTS, BEST)}, not {cut!r}")


def run_plan_deal(
    request: MethodRequest,
    cut: DealCut = BEST,
    rebind: bool = True,
    owner_search: bool = True,
    copies: bool = True,
) -> RunResult:
    """Deal the SA plan with ``cut`` (``free``, ``holding`` or ``best``: both) and each
    order to every number of agents up to N, and (``rebind``) the rebound plan too, and
    (``owner_search``) search the owners of each number's shortest deal; with ``copies``
    an agent may do a piece with another of its movers (:mod:`~twostep.dealing.copies`);
    the shortest schedule wins (module docstring)."""
    check_cut(cut)
    start = time.perf_counter()
    run = new_run(request, MethodName.TWOSTEP)
    run.decomposer = deal_name(cut)
    sa_plan = single_agent_plan(request)
    sa_steps = solved_steps(sa_plan)
    if run.sa_length is None and sa_steps is not None:
        run.sa_length = len(sa_steps)
    trials = Trials()
    if sa_steps is not None and request.agents > 1:
        tried = ways(None if cut == BEST else cut)
        try_deals(request, sa_steps, tried, trials, rebind, owner_search, copies)
    run.score_time_s = trials.seconds.get("scoring", 0.0)
    run.extra["deal"] = trials.rows
    run.extra["deal_seconds"] = {phase: round(s, 6) for phase, s in trials.seconds.items()}
    if trials.capped is not None:
        run.extra["deal_agents"] = trials.capped
    if trials.stopped is not None:
        run.extra["deal_budget"] = trials.stopped
        run.message = (
            f"plan-deal's work budget ({trials.stopped['work']:,} units for N={request.agents}) "
            f"ran out while dealing to {trials.stopped['agents']} agents: the best deal so far"
        )
    run.planner_calls.append(AgentPlan("agent0", "single", request.problem.goal.to_pddl(), sa_plan))
    if trials.best is not None:
        run.fallback = longer_than_sa(request, trials.best[0].length, sa_steps)
    if trials.best is not None and run.fallback is None:
        execution, plans = trials.best
        adopt_schedule(run, execution, [f"agent{k}" for k in range(len(plans))], plans)
        if len(plans) == 1:
            run.fallback = one_agent(trials.rows)
    else:
        if run.fallback is None:
            run.fallback = Fallback(
                FallbackReason.NO_SA_PLAN if sa_steps is None else FallbackReason.ONE_AGENT
            )
        adopt_sa_plan(run, sa_plan)
        if trials.invalid is not None:  # a caller's SA plan that does not apply: no success
            run.success, run.exec_length = False, None
            run.status = RunStatus.ERROR
            run.message = f"the SA plan does not apply: {trials.invalid}"
    run.extra["agents_used"] = len(run.agent_order) or 1
    run.state_editing_time_s = trials.deal_time_s
    run.planning_time_s = count_sa_time(run, sa_plan) + trials.deal_time_s
    run.wall_time_s = time.perf_counter() - start
    return run


def try_deals(
    request: MethodRequest,
    sa_steps: Sequence[str],
    tried: Sequence[Way],
    trials: Trials,
    rebinding: bool = True,
    owner_search: bool = True,
    copies: bool = True,
) -> None:
    """The cleaned SA plan (one agent), then every way for 2..N agents: of the cleaned SA
    plan and, with ``rebinding``, of each different plan rebinding makes of it
    (:mod:`~twostep.dealing.rebind`: its rounds; and its rounds and tails, objects reset
    where none is ready for a round: :data:`REBOUND`); with ``owner_search``, the owner
    search (:mod:`~twostep.dealing.improve`) from the shortest deal to each number of
    agents, or from where the search for one agent fewer ended when that is shorter (its
    row says ``after``). The shortest schedule is kept, ties to fewer agents, then to the
    earlier deal (its row is marked ``chosen``; a rebound plan's rows say ``rebound``:
    ``rounds`` or ``tails``, the owner search's ``improved``)."""
    problem = request.problem
    try:
        dealer = Dealer(problem, sa_steps, request.agent_predicates, copies=copies)
    except PlanError as error:  # an SA plan that does not apply: nothing to deal
        trials.rows.append({"agents": 1, "error": str(error)})
        trials.invalid = str(error)
        return
    cleaned = [str(a) for a in dealer.cleaned]
    first = {"agents": 1, "pieces": 1, "walks": sum(dealer.walking),
             "cleaned_sa_length": len(cleaned), "agents_used": 1}  # fmt: skip
    trials.rows.append(first)
    candidates = [(first, [cleaned], [[(0, a)] for a in cleaned])]
    start = cpu_seconds()
    rebound: dict[str, list[str]] = {}
    if rebinding:
        rebinder = Rebinder(problem, request.agent_predicates)
        for name, tails, resets in REBOUND:
            plan = rebinder.rebind(cleaned, tails, resets)
            if plan is not None and plan not in rebound.values():
                rebound[name] = plan
    spent = cpu_seconds() - start
    dealers: list[tuple[str | None, Dealer]] = [(None, dealer)]
    dealers += [(kind, Dealer(problem, plan, request.agent_predicates, copies=copies))
                for kind, plan in rebound.items()]  # fmt: skip
    most = request.agents
    if request.agents > 2:  # agents beyond the pieces would stay idle: not dealt to
        cuts = {way.cut for way in tried}
        most = min(most, max(2, *(one.most_pieces(cuts) for _, one in dealers)))
        trials.capped = most if most < request.agents else None
    budget = deal_budget(request.agents)

    def left() -> int:
        """What is left of the work budget (:func:`deal_budget`)."""
        return budget - sum(one.work for _, one in dealers)

    searched: tuple[int, str | None, Dealer, Way, SearchKey | None] | None = None  # the last
    for agents in range(2, most + 1):
        made: list[tuple[int, int, str | None, Dealer, Way]] = []  # this number's deals
        skipped = False  # a deal or the owner search left out: the budget ran out
        for kind, one in dealers:
            for way in tried:
                if way.cut == "mover" and free_way_of(way, tried) and one.mover_cut_is_free():
                    continue  # the free cut's pieces: the free way's deal, tried beside it
                if left() <= 0:
                    skipped = True
                    break
                row = deal_row(agents, way, kind)
                trials.rows.append(row)
                try:
                    dealt = one.deal(agents, way.cut, way.order, way.steal)
                except DealError as error:
                    row["error"] = str(error)
                    continue
                candidates.append(candidate(row, dealt))
                made.append((len(dealt.schedule), len(made), kind, one, way))
        skipped = skipped or (owner_search and bool(made) and left() <= 0)
        if owner_search and made and left() > 0:  # from this number's shortest deal
            length, _, kind, one, way = min(made, key=lambda entry: entry[:2])
            after = None
            if searched is not None and searched[0] < length:  # or where the last one ended
                _, kind, one, way, after = searched
            row = {**deal_row(agents, way, kind), "improved": True}
            if after is not None:
                row["after"] = after[0]
            trials.rows.append(row)
            try:
                dealt = one.improve(agents, way.cut, way.order, way.steal, after, left())
            except DealError as error:
                row["error"] = str(error)
            else:
                candidates.append(candidate(row, dealt))
                searched = (len(dealt.schedule), kind, one, way, dealt.search)
        if skipped or (left() <= 0 and agents < most):  # the deals so far are the candidates
            trials.stopped = {"work": budget, "spent": budget - left(), "agents": agents}
            break
    for _, one in dealers:  # the dealers' phases, and rebinding and scoring beside them
        for phase, seconds in one.seconds.items():
            trials.seconds[phase] = trials.seconds.get(phase, 0.0) + seconds
    trials.seconds["rebinding"] = spent
    choose_deal(request, candidates, trials)


def free_way_of(way: Way, tried: Sequence[Way]) -> bool:
    """Whether ``tried`` has the free cut's way of ``way``'s order and stealing."""
    return Way("free", way.order, way.steal) in tried


def deal_row(agents: int, way: Way, kind: str | None) -> dict[str, Any]:
    """A deal's result.json row before it is dealt: its agents and way, and which
    rebound plan it deals (``rebound``; none: the cleaned SA plan)."""
    row: dict[str, Any] = {"agents": agents, "cut": way.cut, "order": way.order,
                           "steal": way.steal}  # fmt: skip
    if kind is not None:
        row["rebound"] = kind
    return row


def candidate(
    row: dict[str, Any], dealt: Deal
) -> tuple[dict[str, Any], list[list[str]], list[list[tuple[int, str]]]]:
    """A deal as a candidate of :func:`choose_deal`: its row filled in, the plans and the
    schedule of the agents that act."""
    plans, schedule = used_agents(dealt.plans, dealt.schedule)
    row.update(pieces=len(dealt.pieces), walks=dealt.walks,
               cleaned_sa_length=dealt.cleaned, agents_used=len(plans))  # fmt: skip
    if dealt.offloaded:
        row["offloaded"] = True
    if dealt.moves is not None:
        row["moves"] = dealt.moves
    return row, plans, schedule


def used_agents(
    plans: Sequence[list[str]], schedule: Sequence[Sequence[tuple[int, str]]]
) -> tuple[list[list[str]], list[list[tuple[int, str]]]]:
    """The plans of the agents that act, and the schedule with them numbered 0, 1, ...
    (each time step in agent order)."""
    number = {a: k for k, a in enumerate(a for a, plan in enumerate(plans) if plan)}
    steps = [sorted((number[a], action) for a, action in step) for step in schedule]
    return [plan for plan in plans if plan], steps


def own_execution(
    schedule: Sequence[Sequence[tuple[int, str]]], plans: Sequence[Sequence[str]]
) -> ParallelExecution:
    """A deal's own joint schedule, with the lower bound every schedule of its plans has:
    the longest plan, and the actions shared out evenly (one per agent and time step)."""
    steps = tuple(tuple(step) for step in schedule)
    total = sum(map(len, plans))
    bound = max(max(map(len, plans), default=0), -(-total // max(len(plans), 1)))
    return ParallelExecution(len(steps), steps, "exact", 0, len(steps) == bound, bound)


def choose_deal(
    request: MethodRequest,
    candidates: Sequence[tuple[dict[str, Any], list[list[str]], list[list[tuple[int, str]]]]],
    trials: Trials,
) -> None:
    """Score the deals and keep the shortest that re-validates (ties: fewer agents, then
    the earlier deal). Each deal comes with its own joint schedule (dealt in time steps,
    each action as early as the run allows); the parallel scorer scores instead when the
    request's mode is not ``exact``."""
    start = cpu_seconds()
    grounder = Grounder(request.problem)
    problem, predicates = request.problem, request.agent_predicates
    ranked: list[tuple[int, int, int, ParallelExecution, list[list[str]], dict[str, Any]]] = []
    for row, plans, schedule in candidates:
        execution = own_execution(schedule, plans)
        if request.score_mode != "exact" or sum(map(len, plans)) <= SCORED_UP_TO:
            try:
                scored = request.score(plans)
            except (ScheduleError, PlanError) as error:
                row["error"] = f"joint schedule invalid: {error}"
                continue
            if request.score_mode != "exact" or scored.length <= execution.length:
                execution = scored
        row["exec_length"] = execution.length
        ranked.append((execution.length, len(plans), len(ranked), execution, plans, row))
    for *_, execution, plans, row in sorted(ranked, key=lambda entry: entry[:3]):
        try:
            check_schedule(execution.steps, [grounder.ground_plan(p) for p in plans],
                           problem.init, problem.goal, predicates)  # fmt: skip
        except (ScheduleError, PlanError) as error:
            row["error"] = f"joint schedule invalid: {error}"
            continue
        row["chosen"] = True
        trials.best = (execution, plans)
        break
    trials.seconds["scoring"] = trials.seconds.get("scoring", 0.0) + cpu_seconds() - start


def one_agent(rows: Sequence[dict[str, Any]]) -> Fallback:
    """Why the run is the cleaned SA plan: every deal to more agents failed, or none was
    shorter."""
    failed = [r for r in rows if r["agents"] > 1 and "exec_length" not in r]
    if failed and len(failed) == len(rows) - 1:
        return Fallback(
            FallbackReason.NO_DEAL,
            "; ".join(f"N={r['agents']} {r['cut']}/{r['order']}: {r.get('error')}" for r in failed),
        )
    return Fallback(FallbackReason.NO_SHORTER_DEAL)
