"""``portfolio``: several decompositions run as methods, the shortest schedule kept.

No single offline decomposer wins everywhere: goal-split finds nothing on one termes
tower, plan-split follows the SA plan's resource reuse, and fewer helpers than N-1
sometimes beat more (less waiting at shared places). The portfolio runs each candidate
(a subgoal source through :func:`~twostep.methods.twostep.run_twostep` with a number of
agents <= N, or :func:`~twostep.methods.plan_deal.run_plan_deal` with N), scores it
exactly like any run, and returns the run with the shortest execution length (ties: the
earlier candidate). Every candidate's planner time counts in the planning time, the SA
plan's once; result.json ``candidates`` lists every candidate with its length.
Candidates whose helper subgoals equal an earlier candidate's are not planned again (same
subgoals, same run, whatever the number of agents). With ``fallback_if_longer`` the SA
plan is itself the last candidate: a winner longer than SA gives way to it.

Then the re-deals (``redeal``): plan-deal keeps the SA plan's choices (on barman one
shot glass carries every ingredient, so the deal is one chain), while a TwoStep candidate
has planned again. Each solved TwoStep candidate's agents' plans, one after the other in
planning order (the helpers in hand-off order, then the main agent), make a sequential
plan, with a walk where an agent starts elsewhere than the one before ended
(:func:`~twostep.dealing.walks.stitch`: a helper's robot ends in another room); it is
dealt by plan-deal to N agents with each cut of ``deals`` exactly as the SA plan is (its
own planning time is the stitching and dealing time only: the plans were planned and
counted in their candidate's row). A concatenation equal to the SA plan or to one dealt
already is not dealt again (its row says ``same_as``); one that no walk makes a valid plan
for one agent (a helper that ends holding something) is skipped, its row says why
(``skipped``) and carries the stitching time. Re-deal rows come after every other
candidate (``dealt_from``: the row the plans came from), so a tie keeps the earlier
candidate; the comparison with SA and ``fallback_if_longer`` use the true SA plan.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, replace
from typing import Any

from twostep.dealing.model import DealError, cpu_seconds
from twostep.dealing.walks import stitch
from twostep.decomposers.base import (
    Decomposer,
    DecompositionRequest,
    SubgoalProposal,
    reads_sa_plan,
)
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.decomposers.plan_split import PlanSplitDecomposer
from twostep.methods.plan_deal import BEST, deal_name, run_plan_deal
from twostep.methods.request import MethodRequest
from twostep.methods.result import (
    AgentPlan,
    Fallback,
    FallbackReason,
    MethodName,
    RunResult,
    adopt_sa_plan,
    count_sa_time,
    longer_than_sa,
    new_run,
    solved_steps,
)
from twostep.methods.single_agent import single_agent_plan
from twostep.methods.twostep import propose, run_twostep
from twostep.planner import PlanResult, Status
from twostep.plans.simulate import PlanError
from twostep.plans.subgoals import SubgoalStatus


@dataclass(frozen=True)
class Candidate:
    """One decomposition to try with ``agents`` agents (at most N): a subgoal source run
    through TwoStep, or plan-deal with a cut."""

    name: str
    agents: int
    decomposer: Decomposer | None = None
    deal_cut: str | None = None


class Proposed:
    """A decomposer that returns proposals made already (the portfolio asks each member
    once, to recognise repeats before planning)."""

    def __init__(self, name: str, proposals: list[SubgoalProposal]):
        self.name = name
        self.proposals = proposals

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        return self.proposals


def lite_members(agent_predicates: Collection[str], link_degree: int = 2) -> list[Decomposer]:
    """``portfolio-lite``'s members: plan-split cut by what the agent holds, and
    goal-split; of every pair of :func:`default_members`, the one with the lowest mean
    macro exec/SA over N = 2-4 on the 100 tasks when the portfolio's runs are replayed
    with that pair beside plan-deal (``bench/bench_portfolio_members.py``)."""
    return [
        PlanSplitDecomposer(agent_predicates, cut="holding"),
        GoalSplitDecomposer(agent_predicates, link_degree),
    ]


def default_members(agent_predicates: Collection[str], link_degree: int = 2) -> list[Decomposer]:
    """plan-split cut at free states, cut by what the agent holds (with partial progress,
    and with goal literals only), goal-split, and the three plan-splits again with
    consecutive stretches instead of the list schedule."""
    return [
        PlanSplitDecomposer(agent_predicates),
        PlanSplitDecomposer(agent_predicates, cut="holding"),
        PlanSplitDecomposer(agent_predicates, cut="holding", keep="goal"),
        GoalSplitDecomposer(agent_predicates, link_degree),
        PlanSplitDecomposer(agent_predicates, assign="chunks"),
        PlanSplitDecomposer(agent_predicates, cut="holding", assign="chunks"),
        PlanSplitDecomposer(agent_predicates, cut="holding", keep="goal", assign="chunks"),
    ]


Members = Callable[[Collection[str], int], list[Decomposer]]
"""The members a portfolio makes per request, from its agent predicates and link degree."""


class Portfolio:
    """The candidates: every member (``members``, or those ``make_members`` makes for the
    request: :func:`default_members`) with N, N-1, ..., 2 agents (``fewer_agents``; else
    with N only), then plan-deal with each cut of ``deals`` and N agents, then (``redeal``)
    the solved TwoStep candidates' plans, concatenated, dealt with each cut of ``deals``.
    ``name`` is the runs' ``decomposer``."""

    def __init__(
        self,
        link_degree: int = 2,
        members: Sequence[Decomposer] | None = None,
        deals: Sequence[str] = (BEST,),
        redeal: bool = True,
        fewer_agents: bool = True,
        name: str = "portfolio",
        make_members: Members = default_members,
        rebind: bool = True,
        owner_search: bool = True,
    ):
        self.link_degree = link_degree
        self.members = None if members is None else list(members)
        self.deals = tuple(deals)
        self.redeal = redeal
        self.fewer_agents = fewer_agents
        self.name = name
        self.make_members = make_members
        self.rebind = rebind
        self.owner_search = owner_search

    @classmethod
    def lite(
        cls, link_degree: int = 2, rebind: bool = True, owner_search: bool = True
    ) -> Portfolio:
        """``portfolio-lite``: plan-deal, and the re-deals of two TwoStep candidates
        (:func:`lite_members`) with N agents only; a fraction of the portfolio's planning
        time for most of its gain (docs/results/methods.md)."""
        return cls(
            link_degree,
            fewer_agents=False,
            name="portfolio-lite",
            make_members=lite_members,
            rebind=rebind,
            owner_search=owner_search,
        )

    def candidates(self, request: MethodRequest) -> list[Candidate]:
        """Members first, with N agents down to 2, then plan-deal with N (its list schedule
        leaves agents idle where fewer do better). Ties go to the earlier candidate, so
        TwoStep's own hand-off wins a tie."""
        members = self.members
        if members is None:
            members = self.make_members(request.agent_predicates, self.link_degree)
        agents = request.agents
        counts = range(agents, 1, -1) if self.fewer_agents else (agents,)
        return [Candidate(d.name, n, decomposer=d) for n in counts for d in members] + [
            Candidate(deal_name(cut), agents, deal_cut=cut) for cut in self.deals
        ]


def run_full_portfolio(
    request: MethodRequest, link_degree: int = 2, rebind: bool = True, owner_search: bool = True
) -> RunResult:
    """The method ``portfolio``: :func:`run_portfolio` with every member of
    :func:`default_members` (``link_degree`` for goal-split's) and N, N-1, ..., 2 agents;
    ``rebind`` and ``owner_search`` are its plan-deal's."""
    portfolio = Portfolio(link_degree, rebind=rebind, owner_search=owner_search)
    return run_portfolio(request, portfolio)


def run_portfolio_lite(
    request: MethodRequest, link_degree: int = 2, rebind: bool = True, owner_search: bool = True
) -> RunResult:
    """The method ``portfolio-lite``: :func:`run_portfolio` with :meth:`Portfolio.lite`."""
    return run_portfolio(request, Portfolio.lite(link_degree, rebind, owner_search))


def run_portfolio(request: MethodRequest, portfolio: Portfolio | None = None) -> RunResult:
    """Every candidate of ``portfolio`` (default: :class:`Portfolio`); the shortest
    schedule wins (module docstring)."""
    portfolio = portfolio or Portfolio()
    start = time.perf_counter()
    sa_plan = single_agent_plan(request)
    rows: list[dict[str, Any]] = []
    runs: list[RunResult] = []
    seen: dict[tuple[str | None, ...], int] = {}  # subgoals -> the row that planned them
    planned: list[tuple[int, RunResult]] = []  # the TwoStep candidates' rows and runs
    planning = 0.0
    for candidate in portfolio.candidates(request):
        one = replace(request, agents=candidate.agents, sa_plan=sa_plan, fallback_if_longer=False)
        if candidate.deal_cut is not None:
            run = run_plan_deal(one, candidate.deal_cut, portfolio.rebind, portfolio.owner_search)
        else:
            assert candidate.decomposer is not None
            read = reads_sa_plan(candidate.decomposer)
            proposals = propose(one, candidate.decomposer, solved_steps(sa_plan) if read else None)
            # same subgoals, same run (only the per-agent time limit would differ)
            key = tuple(p.pddl for p in proposals if p.status == SubgoalStatus.PROPOSED)
            if key in seen:
                rows.append({"decomposer": candidate.name, "agents": candidate.agents,
                             "same_as": seen[key], "exec_length": rows[seen[key]]["exec_length"]})  # fmt: skip
                continue
            seen[key] = len(rows)
            run = run_twostep(replace(one, decomposer=Proposed(candidate.name, proposals)))
            planned.append((len(rows), run))
        planning += run.planning_time_s - (run.sa_time_included_s or 0.0)  # SA counted once
        rows.append(candidate_row(run, candidate))
        run.extra["candidate"] = len(rows) - 1
        runs.append(run)
    if portfolio.redeal and request.agents > 1:
        planning += redeal_all(request, portfolio, planned, sa_plan, rows, runs)
    best = choose(request, runs, rows, sa_plan)
    best.agents = request.agents
    best.decomposer = portfolio.name
    best.extra["agents_used"] = len(best.agent_order) if best.agent_order else 1
    best.extra["candidates"] = rows
    best.planning_time_s = planning + count_sa_time(best, sa_plan)
    best.wall_time_s = time.perf_counter() - start
    return best


NOT_ONE_PLAN = "not a valid plan for one agent"
"""Why a TwoStep candidate's plans are not dealt again (a re-deal row's ``skipped``)."""


def concatenation(request: MethodRequest, run: RunResult) -> tuple[str, ...] | str | None:
    """A solved TwoStep run's agents' plans one after the other, in planning order (the
    helpers in hand-off order, then the main agent), stitched with walks
    (:func:`~twostep.dealing.walks.stitch`); why not, when no walk helps; None for a run
    that is not a joint schedule of two agents or more (it fell back to the SA plan)."""
    if not run.success or run.fallback is not None or len(run.agent_order) < 2:
        return None
    plans = [run.plans[agent] for agent in run.agent_order]
    try:
        return tuple(stitch(request.problem, plans, request.agent_predicates))
    except (DealError, PlanError) as error:
        return f"{NOT_ONE_PLAN}: {error}"


def redeal_all(
    request: MethodRequest,
    portfolio: Portfolio,
    planned: Sequence[tuple[int, RunResult]],
    sa_plan: PlanResult,
    rows: list[dict[str, Any]],
    runs: list[RunResult],
) -> float:
    """Deal each TwoStep candidate's concatenated plans with each of the portfolio's cuts
    (module docstring): the rows and the runs are appended to ``rows`` and ``runs``;
    returns the time spent."""
    cuts = portfolio.deals
    sa_steps = solved_steps(sa_plan)
    sa_length = request.sa_length
    if sa_length is None and sa_steps is not None:
        sa_length = len(sa_steps)
    one = replace(request, sa_length=sa_length, fallback_if_longer=False)
    dealt: dict[tuple[str, tuple[str, ...]], int] = {}  # (cut, plan) -> its row
    if sa_steps is not None:  # the SA plan: plan-deal's own rows
        for k, earlier in enumerate(rows):
            for cut in cuts:
                if earlier["decomposer"] == deal_name(cut) and earlier["agents"] == request.agents:
                    dealt[(cut, sa_steps)] = k
    spent = 0.0
    for source, twostep in planned:
        start = cpu_seconds()
        plan = concatenation(request, twostep)
        stitching = cpu_seconds() - start
        spent += stitching
        if plan is None:
            continue
        for cut in cuts:
            row: dict[str, Any] = {"decomposer": f"{deal_name(cut)}<{rows[source]['decomposer']}>",
                                   "agents": request.agents, "dealt_from": source}  # fmt: skip
            if isinstance(plan, str):  # the stitching time on the first cut's row only
                rows.append({**row, "exec_length": None, "skipped": plan,
                             "planning_time_s": round(stitching, 4)})  # fmt: skip
                stitching = 0.0
                continue
            if (cut, plan) in dealt:
                same = dealt[(cut, plan)]
                rows.append({**row, "same_as": same, "exec_length": rows[same]["exec_length"]})
                continue
            dealt[(cut, plan)] = len(rows)
            start = cpu_seconds()
            run = redeal(one, plan, cut, portfolio.rebind, portfolio.owner_search)
            if isinstance(run, str):
                seconds = cpu_seconds() - start
                row.update(exec_length=None, planning_time_s=round(seconds, 4), skipped=run)
                rows.append(row)
                spent += seconds
                continue
            run.planner_calls = list(twostep.planner_calls)  # the calls that made the plan
            run.sa_length = sa_length  # the SA plan's, not the concatenation's
            run.extra["dealt_from"] = source
            spent += run.planning_time_s
            rows.append({**row, **candidate_row(run, Candidate(row["decomposer"], request.agents))})
            run.extra["candidate"] = len(rows) - 1
            runs.append(run)
    return spent


def redeal(
    request: MethodRequest,
    plan: tuple[str, ...],
    cut: str,
    rebind: bool = True,
    owner_search: bool = True,
) -> RunResult | str:
    """plan-deal of ``plan`` as if it were the SA plan (planned in no time): the run, or
    why ``plan`` cannot be dealt (not a valid plan for one agent, or no deal of it
    re-validates). The run's deals are its ``redeal`` rows (``deal`` stays the SA
    plan's: the bench reads the cleaned SA length there)."""
    made = PlanResult(Status.SOLVED, plan, 0.0, 0.0, message="agents' plans concatenated")
    run = run_plan_deal(
        replace(request, sa_plan=made), cut, rebind, owner_search
    )  # records a failing plan
    deals = run.extra.pop("deal")
    run.extra["redeal"] = deals
    run.extra["redeal_seconds"] = run.extra.pop("deal_seconds")
    if not any(d.get("chosen") for d in deals):
        why = deals[0].get("error") if deals else None
        return f"{NOT_ONE_PLAN}: {why}" if why else "no deal re-validates"
    return run


def candidate_row(run: RunResult, candidate: Candidate) -> dict[str, Any]:
    """One candidate's row for result.json ``candidates`` (its own planning time only)."""
    return {
        "decomposer": candidate.name,
        "agents": candidate.agents,
        "exec_length": run.exec_length if run.success else None,
        "planning_time_s": round(run.planning_time_s - (run.sa_time_included_s or 0.0), 4),
        "fallback": None if run.fallback is None else str(run.fallback),
        "accepted": sum(s["status"] == SubgoalStatus.ACCEPTED for s in run.subgoals),
    }


def choose(
    request: MethodRequest,
    runs: Sequence[RunResult],
    rows: Sequence[dict[str, Any]],
    sa_plan: PlanResult,
) -> RunResult:
    """The candidate run with the shortest schedule, or the SA plan when none solved or
    (``fallback_if_longer``) the shortest is longer than SA."""
    solved = [r for r in runs if r.success and r.exec_length is not None]
    best = min(solved, key=lambda r: r.exec_length or 0, default=None)
    fallback: Fallback | None
    if best is None:
        fallback = Fallback(
            FallbackReason.NO_CANDIDATE_SOLVED if rows else FallbackReason.NO_CANDIDATE
        )
    else:
        fallback = longer_than_sa(request, best.exec_length or 0, solved_steps(sa_plan))
    if best is not None and fallback is None:
        return best
    run = new_run(request, MethodName.TWOSTEP)
    run.fallback = fallback
    run.planner_calls.append(AgentPlan("agent0", "single", request.problem.goal.to_pddl(), sa_plan))
    adopt_sa_plan(run, sa_plan)
    return run
