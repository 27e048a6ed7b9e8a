"""``portfolio``: run several decompositions through TwoStep and keep the shortest schedule.

No single offline decomposer wins everywhere: goal-split finds nothing on one termes
tower, plan-split follows the SA plan's resource reuse, and fewer helpers than N-1
sometimes beat more (less waiting at shared places). The portfolio runs each candidate
(a decomposer and a number of agents <= N) through :func:`~twostep.methods.twostep.run_twostep`,
scores it exactly like any run, and returns the run with the shortest execution length
(ties: the earlier candidate). Every candidate's planner time counts in the planning time,
the SA plan's once; ``extra["candidates"]`` (result.json ``candidates``) lists every
candidate with its length. Candidates whose helper subgoals equal an earlier candidate's
are not planned again (same subgoals, same run, whatever the number of agents). With
``fallback_if_longer`` the SA plan is itself the last candidate: a winner longer than SA
gives way to it. plan-deal is a member too: it deals the SA plan's pieces to the agents
instead of proposing subgoals (:mod:`twostep.dealing.deal`), and costs no planner call.

The portfolio is a decomposer only in name: ``run_twostep`` hands a :class:`Portfolio` to
:func:`run_portfolio`, since choosing needs the whole pipeline, not just subgoals.
"""

from __future__ import annotations

import time
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from twostep.benchmark import BenchmarkTask
from twostep.dealing.deal import PlanDeal
from twostep.decomposers.base import Decomposer, DecompositionRequest, SubgoalProposal
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.decomposers.plan_split import PlanSplitDecomposer
from twostep.planner import PlannerSettings, PlanResult
from twostep.subgoals import SubgoalStatus

if TYPE_CHECKING:
    from twostep.methods.twostep import RunResult, Steps


@dataclass(frozen=True)
class Candidate:
    """One decomposition to try: a decomposer, with ``agents`` agents (at most N)."""

    decomposer: Decomposer
    agents: int


class _Fixed:
    """A decomposer that returns proposals made already (the portfolio asks once)."""

    def __init__(self, name: str, proposals: list[SubgoalProposal]):
        self.name = name
        self.proposals = proposals

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        return self.proposals


class Portfolio:
    """The candidates for N agents: each member with N, N-1, ..., 2 agents.

    Default members: plan-split cut at free states, plan-split cut by what the agent holds
    (with partial progress, and with goal literals only), goal-split, the three
    plan-splits again with consecutive stretches instead of the list schedule, and
    plan-deal (:mod:`twostep.dealing.deal`, with N agents only, tried last).
    """

    name = "portfolio"
    needs_sa_plan = True

    def __init__(
        self,
        agent_predicates: Collection[str],
        link_degree: int = 2,
        members: Sequence[Decomposer] | None = None,
    ):
        self.members: list[Decomposer] = list(members or ()) or [
            PlanSplitDecomposer(agent_predicates),
            PlanSplitDecomposer(agent_predicates, cut="holding"),
            PlanSplitDecomposer(agent_predicates, cut="holding", keep="goal"),
            GoalSplitDecomposer(agent_predicates, link_degree),
            PlanSplitDecomposer(agent_predicates, assign="chunks"),
            PlanSplitDecomposer(agent_predicates, cut="holding", assign="chunks"),
            PlanSplitDecomposer(agent_predicates, cut="holding", keep="goal", assign="chunks"),
            PlanDeal(agent_predicates),
        ]

    def candidates(self, agents: int) -> list[Candidate]:
        """Every TwoStep member with N, N-1, ..., 2 agents, then plan-deal with N agents
        (its list schedule leaves agents idle where fewer do better). Ties go to the
        earlier candidate, so TwoStep's own hand-off wins a tie."""
        subgoals = [d for d in self.members if not isinstance(d, PlanDeal)]
        deals = [d for d in self.members if isinstance(d, PlanDeal)]
        return [Candidate(d, n) for n in range(agents, 1, -1) for d in subgoals] + [
            Candidate(d, agents) for d in deals
        ]

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        """Never asked by the pipeline (see the module docstring); no subgoal of its own."""
        return []


def run_portfolio(
    task: BenchmarkTask,
    agents: int,
    portfolio: Portfolio,
    agent_predicates: Collection[str],
    settings: PlannerSettings,
    mode: str = "exact",
    seed: int = 0,
    sa_length: int | None = None,
    steps: Steps | None = None,
    sa_plan: PlanResult | None = None,
    fallback_if_longer: bool = True,
) -> RunResult:
    """Every candidate through TwoStep; the shortest schedule wins (module docstring)."""
    from twostep.methods.twostep import DIRECT, run_twostep

    steps = steps or DIRECT
    start = time.perf_counter()
    problem = task.problem
    if sa_plan is None:
        sa_plan = steps.plan(problem, settings)
    rows: list[dict[str, Any]] = []
    runs: list[RunResult] = []
    seen: dict[tuple[str | None, ...], int] = {}
    planning = 0.0
    for candidate in portfolio.candidates(agents):
        if isinstance(candidate.decomposer, PlanDeal):  # plans, not subgoals: no dedup key
            run = run_twostep(
                task, candidate.agents, candidate.decomposer, agent_predicates, settings,
                mode, seed, sa_length, steps, sa_plan=sa_plan, fallback_if_longer=False,
            )  # fmt: skip
            planning += run.planning_time_s - float(run.extra.get("sa_time_included_s", 0.0))
            _add_candidate(rows, runs, run, candidate)
            continue
        request = DecompositionRequest(
            task, candidate.agents, seed, sa_plan=_steps_of(sa_plan, candidate.decomposer)
        )
        proposals = steps.propose(candidate.decomposer, request, steps.generate, steps.translate)
        proposals = proposals[: candidate.agents - 1]
        pddl = tuple(p.pddl for p in proposals if p.status == SubgoalStatus.PROPOSED)
        key = pddl  # same subgoals, same run (only the per-agent time limit would differ)
        if key in seen:
            rows.append(
                {
                    "decomposer": candidate.decomposer.name,
                    "agents": candidate.agents,
                    "same_as": seen[key],
                    "exec_length": rows[seen[key]]["exec_length"],
                }
            )
            continue
        seen[key] = len(rows)
        run = run_twostep(
            task,
            candidate.agents,
            _Fixed(candidate.decomposer.name, proposals),
            agent_predicates,
            settings,
            mode,
            seed,
            sa_length,
            steps,
            sa_plan=sa_plan,
            fallback_if_longer=False,
        )
        included = float(run.extra.get("sa_time_included_s", 0.0))  # counted once, below
        planning += run.planning_time_s - included
        _add_candidate(rows, runs, run, candidate)
    solved = [r for r in runs if r.success and r.exec_length is not None]
    best: RunResult | None = min(solved, key=lambda r: r.exec_length or 0, default=None)
    sa_steps = _steps_of(sa_plan, None)
    if best is None or (
        fallback_if_longer
        and sa_steps is not None
        and best.exec_length is not None
        and best.exec_length > len(sa_steps)
    ):
        from twostep.methods.twostep import AgentPlan, _use_single_agent_plan

        chosen = best
        best = _sa_run(task, agents, seed, sa_length, sa_plan)
        best.fallback = (
            ("no candidate solved" if rows else "no candidate (one agent)")
            if chosen is None
            else f"joint schedule longer than SA ({chosen.exec_length} > {len(sa_steps or ())})"
        )
        if sa_plan is not None:
            best.planner_calls.append(
                AgentPlan("agent0", "single", problem.goal.to_pddl(), sa_plan)
            )
            _use_single_agent_plan(best, sa_plan)
    # the SA plan was planned (or given) and compared against: its time counts, once
    sa_time = sa_plan.planner_time_s if sa_plan is not None else 0.0
    best.agents = agents
    best.decomposer = portfolio.name
    best.extra["agents_used"] = len(best.agent_order) if best.agent_order else 1
    best.extra["candidates"] = rows
    best.extra["sa_time_included_s"] = round(sa_time, 4)
    best.planning_time_s = planning + sa_time
    best.wall_time_s = time.perf_counter() - start
    return best


def _add_candidate(
    rows: list[dict[str, Any]], runs: list[RunResult], run: RunResult, candidate: Candidate
) -> None:
    """One candidate's row for result.json ``candidates`` (its own planning time only)."""
    included = float(run.extra.get("sa_time_included_s", 0.0))
    rows.append(
        {
            "decomposer": candidate.decomposer.name,
            "agents": candidate.agents,
            "exec_length": run.exec_length if run.success else None,
            "planning_time_s": round(run.planning_time_s - included, 4),
            "fallback": run.fallback,
            "accepted": sum(s["status"] == SubgoalStatus.ACCEPTED for s in run.subgoals),
        }
    )
    runs.append(run)
    run.extra["candidate"] = len(rows) - 1


def _steps_of(sa_plan: PlanResult | None, decomposer: Decomposer | None) -> tuple[str, ...] | None:
    """The SA plan's actions, when solved (and, given a decomposer, when it reads them)."""
    if decomposer is not None and not getattr(decomposer, "needs_sa_plan", False):
        return None
    if sa_plan is None or not sa_plan.solved or sa_plan.plan is None:
        return None
    return tuple(sa_plan.plan)


def _sa_run(
    task: BenchmarkTask, agents: int, seed: int, sa_length: int | None, sa_plan: PlanResult | None
) -> RunResult:
    from twostep.methods.twostep import RunResult

    run = RunResult(task.domain_name, task.task_id, "twostep", agents, seed, sa_length=sa_length)
    if sa_plan is None:
        run.status, run.message = "error", "no SA plan"
    return run


__all__: Sequence[str] = ("Candidate", "Portfolio", "run_portfolio")
