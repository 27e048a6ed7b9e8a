"""One job of a sweep, from its resolved config to a result: wiring only, no planning logic.

``run_job`` reads the task, builds the planner settings and the decomposer the config
names, and calls the library's method (:mod:`twostep.pipeline`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from twostep.benchmark import BenchmarkTask, load_task
from twostep.decomposers.base import Decomposer
from twostep.pipeline import RunResult, run_multi_agent, run_single_agent, run_twostep
from twostep.planner import PlannerSettings


class JobError(Exception):
    """A config that names something that does not exist or does not fit together."""


def planner_settings(cfg: Any) -> PlannerSettings:
    return PlannerSettings(
        alias=cfg.planner.alias,
        search_time_limit_s=float(cfg.planner.time_limit_s),
        memory_limit_mb=cfg.planner.memory_limit_mb,
    )


def build_decomposer(cfg: Any) -> Decomposer:
    name = cfg.decomposer.name
    agent_predicates = list(cfg.domain.agent_predicates)
    if name == "goal-split":
        from twostep.decomposers.goal_split import GoalSplitDecomposer

        return GoalSplitDecomposer(agent_predicates, cfg.decomposer.link_degree)
    if name == "expert":
        from twostep.decomposers.expert import ExpertDecomposer

        return ExpertDecomposer()
    if name == "llm":
        from flows.llm import build_llm_decomposer

        return build_llm_decomposer(cfg)
    raise JobError(f"unknown decomposer '{name}' (known: goal-split, expert, llm)")


def load_job_task(cfg: Any) -> BenchmarkTask:
    return load_task(cfg.domain.name, int(cfg.task), Path(cfg.data.root))


def run_job(cfg: Any, task: BenchmarkTask | None = None) -> RunResult:
    """Run the method the config names on its task and return the result."""
    task = task or load_job_task(cfg)
    settings = planner_settings(cfg)
    method = cfg.method.name
    agents = int(cfg.agents)
    seed = int(cfg.seed)
    agent_predicates = list(cfg.domain.agent_predicates)
    if agents < 1:
        raise JobError(f"agents must be at least 1, got {agents}")
    if method == "sa":
        return run_single_agent(task, settings, seed)
    sa_length = None
    if cfg.compare_sa:
        sa = run_single_agent(task, settings, seed)
        sa_length = sa.sa_length
    if method == "ma":
        result = run_multi_agent(task, agents, agent_predicates, settings, cfg.score_mode, seed, sa_length)
    elif method == "twostep":
        decomposer = build_decomposer(cfg)
        result = run_twostep(task, agents, decomposer, agent_predicates, settings, cfg.score_mode, seed, sa_length)
    else:
        raise JobError(f"unknown method '{method}' (known: sa, ma, twostep)")
    return result


def format_summary(result: RunResult) -> str:
    """One line for the terminal."""
    parts = [
        f"{result.domain} p{result.task:02d} {result.method}",
        f"N={result.agents}",
        "success" if result.success else f"FAILED ({result.status}: {result.message})",
        f"exec_length={result.exec_length}",
    ]
    if result.sa_length is not None:
        parts.append(f"sa_length={result.sa_length}")
    parts.append(f"planning_time={result.planning_time_s:.2f}s")
    if result.decomposer:
        accepted = sum(1 for s in result.subgoals if s["status"] == "accepted")
        parts.append(f"subgoals={accepted}/{len(result.subgoals)} accepted")
    if result.fallback:
        parts.append(f"fallback: {result.fallback}")
    return " | ".join(parts)


def format_schedule(result: RunResult, width: int = 34) -> str:
    """The joint schedule as a table, one column per agent."""
    agents = sorted(result.plans, key=lambda a: int(a.removeprefix("agent")) if a[5:].isdigit() else 0)
    if not result.schedule or len(agents) < 2:
        return ""
    header = "step  " + "".join(a.ljust(width) for a in agents)
    lines = [header, "-" * len(header)]
    for t, step in enumerate(result.schedule, start=1):
        acting = dict(step)
        lines.append(f"{t:>4}  " + "".join(acting.get(a, ".").ljust(width) for a in agents))
    return "\n".join(lines)
