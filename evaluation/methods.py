"""The methods bench's runs: every method on one task (:func:`run_job`), each schedule
re-validated by simulation against the original task, and the rows a run keeps and reuses.

``bench/bench_methods.py`` is its command line; :mod:`evaluation.method_tables` turns the
rows into its tables, the results pages and the README's headline. A new subgoal source
joins with one line in :data:`SUBGOAL_SOURCES`; every method runs through the registry
(:func:`twostep.methods.method_for`).
"""

from __future__ import annotations

import sys
import time
import traceback
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from twostep.decomposers.base import Decomposer
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.decomposers.plan_split import PlanSplitDecomposer
from twostep.methods import MethodRequest, RunResult, check_run, method_for
from twostep.methods.registry import TWOSTEP_METHODS
from twostep.planner import PlannerSettings
from twostep.planner.results import PlanResult, Status
from twostep.tasks.benchmark import load_task

REPO = Path(__file__).resolve().parent.parent
CONF = REPO / "conf"

# The TwoStep decomposers the bench knows, by their config name (conf/decomposer/<name>):
# the subgoal sources, built from the domain's agent predicates (a new one joins with one
# line here), then the methods the registry runs under the same name (plan-deal, portfolio).
SUBGOAL_SOURCES: dict[str, Callable[[list[str]], Decomposer]] = {
    "goal-split": GoalSplitDecomposer,
    "plan-split": PlanSplitDecomposer,
}
DECOMPOSERS = (*SUBGOAL_SOURCES, *TWOSTEP_METHODS)
METHODS = ("ma", *DECOMPOSERS)
REUSED_BY_DEFAULT = ("sa", "ma")  # planner only: unchanged by any decomposer's code
TARGETS = {2: 0.55, 3: 0.45, 4: 0.40}  # issue 18: macro exec/SA of the offline default
# Rows written before rows named their settings were all planned with these.
LEGACY = {"data": "data", "alias": "lama-first", "time_limit_s": 60.0, "fallback_if_longer": True}

Row = dict[str, Any]
RowKey = tuple[str, str, int, int, str]  # data root, domain, task, N, method


def agent_predicates(domain: str) -> list[str]:
    return list(
        yaml.safe_load((CONF / "domain" / f"{domain}.yaml").read_text())["agent_predicates"]
    )


def offline_default() -> str:
    """The method the default config runs (conf/config.yaml's defaults list), as this bench
    names methods: TwoStep by its decomposer, the others by their name."""
    from flows.spelling import new_spelling

    defaults = yaml.safe_load((CONF / "config.yaml").read_text())["defaults"]
    chosen = {k: v for d in defaults if isinstance(d, dict) for k, v in d.items()}
    method, decomposer = str(chosen["method"]), chosen.get("decomposer")
    named = new_spelling(method, None if decomposer is None else str(decomposer))
    return named or (str(decomposer) if method == "twostep" else method)


def data_label(root: Path) -> str:
    """How rows name a data root: relative to the repository when inside it (``data``,
    ``data/large``), so rows of one checkout are reused in another; else absolute."""
    path = root.resolve()
    return path.relative_to(REPO).as_posix() if path.is_relative_to(REPO) else path.as_posix()


def row_data(row: Mapping[str, Any]) -> str:
    """The data root a row was planned on (rows of the first runs name none: ``data``)."""
    return str(row.get("data", LEGACY["data"]))


def row_key(row: Mapping[str, Any]) -> RowKey:
    return row_data(row), row["domain"], int(row["task"]), int(row["agents"]), row["method"]


def same_settings(row: Mapping[str, Any], alias: str, time_limit_s: float, fallback: bool) -> bool:
    """Was ``row`` planned as this run would plan it? (fallback matters to TwoStep only)."""
    if row.get("alias", LEGACY["alias"]) != alias:
        return False
    if float(row.get("time_limit_s", LEGACY["time_limit_s"])) != time_limit_s:
        return False
    if row["method"] in ("sa", "ma"):
        return True
    return bool(row.get("fallback_if_longer", LEGACY["fallback_if_longer"])) == fallback


def reusable_rows(
    rows: Iterable[Row],
    methods: Collection[str],
    alias: str,
    time_limit_s: float,
    fallback: bool,
) -> dict[RowKey, Row]:
    """The rows of ``methods`` planned with these settings, by key (the last one wins)."""
    return {
        row_key(r): r
        for r in rows
        if r["method"] in methods and same_settings(r, alias, time_limit_s, fallback)
    }


def verify(task: Any, result: RunResult, preds: list[str]) -> bool:
    if not result.success:
        return False
    check_run(task.problem, result, preds)
    return True


def outcome_fields(result: RunResult) -> Row:
    """What a row keeps of a run beyond its length: the actions of all its agents (for the
    lower bound: at most N actions per time step), the agents that act, why it fell back,
    and plan-deal's cleaned SA plan and dealing time by phase."""
    fields: Row = {
        "total_actions": sum(map(len, result.plans.values())) if result.success else None,
        "agents_used": len(result.agent_order) if result.success else None,
        "fallback_reason": None if result.fallback is None else result.fallback.reason.value,
    }
    deals = result.extra.get("deal")
    if deals:
        fields["cleaned_sa_length"] = deals[0].get("cleaned_sa_length")
        fields["deal_seconds"] = result.extra.get("deal_seconds")
    return fields


def stored_sa_plan(row: Row) -> PlanResult | None:
    """The SA planner result a stored SA row carries (rows since the ``plan`` field)."""
    if row.get("plan") is None or row.get("status") != Status.SOLVED.value:
        return None
    plan = tuple(row["plan"])
    return PlanResult(Status.SOLVED, plan, row["planning_time_s"], row.get("wall_s", 0.0))


def say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


@dataclass(frozen=True)
class Job:
    """One task of one data root, and what to do with it."""

    data: str  # the root as given (to read the task)
    label: str  # the root as rows name it
    domain: str
    task: int
    agents: tuple[int, ...]
    methods: tuple[str, ...]
    alias: str
    time_limit_s: float
    fallback: bool
    known: tuple[Row, ...]  # rows of this task that are reused, not planned again
    predicates: tuple[str, ...] | None = None  # the agent predicates; None: conf/domain's


def run_job(job: Job) -> list[Row]:
    """Every row of one task: reused ones as they are, the others planned now."""
    name = f"{job.label}:{job.domain}/p{job.task:02d}"
    known = {(r["agents"], r["method"]): r for r in job.known}
    todo = [(n, m) for n in job.agents if n > 1 for m in job.methods if (n, m) not in known]
    task = load_task(job.domain, job.task, Path(job.data))
    preds = agent_predicates(job.domain) if job.predicates is None else list(job.predicates)
    settings = PlannerSettings(job.alias, job.time_limit_s)
    common = {"data": job.label, "domain": job.domain, "task": job.task, "alias": job.alias,
              "time_limit_s": job.time_limit_s}  # fmt: skip
    sa_row = known.get((1, "sa"))
    sa_plan = stored_sa_plan(sa_row) if sa_row else None
    needs_plan = any(m != "ma" for _, m in todo)
    if sa_row is None or (needs_plan and sa_plan is None):
        start = time.perf_counter()
        sa = method_for("sa")(MethodRequest(task, planner=settings))
        sa_plan = sa.planner_calls[0].result
        sa_row = {**common, "method": "sa", "agents": 1, "exec_length": sa.exec_length,
                  "planning_time_s": sa.planning_time_s, "sa_length": sa.sa_length,
                  "valid": verify(task, sa, preds), "status": sa.status,
                  "plan": list(sa_plan.plan) if sa_plan.plan else None,
                  "total_actions": sa.exec_length,
                  "wall_s": time.perf_counter() - start}  # fmt: skip
        say(f"  {name} sa: {sa.status}, length {sa.exec_length}, {sa_row['wall_s']:.1f} s")
    rows = [sa_row]
    sa_length = sa_row["sa_length"]
    for n, method in [(n, m) for n in job.agents if n > 1 for m in job.methods]:
        if (n, method) in known:
            rows.append(known[(n, method)])
            continue
        start = time.perf_counter()
        try:
            source = SUBGOAL_SOURCES.get(method)
            request = MethodRequest(
                task, n, settings, preds, source(preds) if source else None,
                sa_length=sa_length, sa_plan=sa_plan, fallback_if_longer=job.fallback,
            )  # fmt: skip
            result = method_for("ma" if method == "ma" else "twostep", method)(request)
            try:
                valid = verify(task, result, preds)
            except Exception as error:  # report, do not stop the table
                valid, result.message = False, f"schedule invalid: {error}"
        except Exception:  # a crash of one method is a row, not the end of an hour's run
            rows.append({**common, "method": method, "agents": n, "exec_length": None,
                         "planning_time_s": None, "sa_length": sa_length, "valid": False,
                         "status": "error", "message": traceback.format_exc(limit=3),
                         "wall_s": time.perf_counter() - start})  # fmt: skip
            say(f"  {name} {method} N={n}: error")
            continue
        rows.append({**common, "method": method, "agents": n, "exec_length": result.exec_length,
                     "planning_time_s": result.planning_time_s, "sa_length": sa_length,
                     "valid": valid, "status": result.status, "exact": result.exact,
                     "lower_bound": result.lower_bound, "fallback_if_longer": job.fallback,
                     "fallback": result.fallback, "message": result.message,
                     "accepted": sum(s["status"] == "accepted" for s in result.subgoals),
                     "candidates": result.extra.get("candidates"),
                     **outcome_fields(result),
                     "wall_s": time.perf_counter() - start})  # fmt: skip
        say(f"  {name} {method} N={n}: {result.status}, length {result.exec_length}, "
             f"planning {result.planning_time_s:.1f} s, {rows[-1]['wall_s']:.1f} s")  # fmt: skip
    return rows


def task_ids(spec: str, available: list[int]) -> list[int]:
    """``1-20`` (a range) or ``1,6,11,16`` (a list)."""
    if "," in spec:
        wanted = {int(x) for x in spec.split(",")}
        return [t for t in available if t in wanted]
    lo, _, hi = spec.partition("-")
    return [t for t in available if int(lo) <= t <= int(hi or lo)]
