"""Config to library objects, in one place: the task, the planner settings and the
decomposer a job's config names, and the check that they exist and fit together.

Each library setting has one name in the config (``flows/config.py``, whose defaults
are the library dataclasses' defaults) and is mapped here once; ``planner.time_limit_s``
is the planner's ``search_time_limit_s``; :func:`llm_settings` maps the ``llm`` group to
the LLM client's settings; :func:`search_budget` maps ``score_max_nodes`` and
``score_time_limit_s`` to the scorer's budget.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from flows.checks import check_values
from flows.config import TwostepConfig
from twostep.benchmark import BenchmarkTask, load_task
from twostep.decomposers.base import Decomposer

if TYPE_CHECKING:
    from twostep.llm import LLMSettings
from twostep.embodied import ExecutorSettings
from twostep.execution import SearchBudget
from twostep.planner import PlannerSettings


class JobError(Exception):
    """A config that names something that does not exist or does not fit together."""


METHODS = ("sa", "ma", "twostep")
DECOMPOSERS = ("goal-split", "expert", "llm", "plan-split", "plan-deal", "portfolio")


def planner_settings(cfg: TwostepConfig) -> PlannerSettings:
    return PlannerSettings(
        alias=cfg.planner.alias,
        search_time_limit_s=float(cfg.planner.time_limit_s),
        memory_limit_mb=cfg.planner.memory_limit_mb,
    )


def search_budget(cfg: TwostepConfig) -> SearchBudget:
    """The exact scorer's budget: ``score_max_nodes`` and ``score_time_limit_s``."""
    max_nodes, time_limit_s = cfg.score_max_nodes, cfg.score_time_limit_s
    return SearchBudget(
        max_nodes=None if max_nodes is None else int(max_nodes),
        time_limit_s=None if time_limit_s is None else float(time_limit_s),
    )


@contextmanager
def open_decomposer(cfg: TwostepConfig) -> Iterator[Decomposer]:
    """The decomposer the config names, for the duration of one job.

    A context manager because the LLM decomposer owns a client (``llm=local`` runs a
    model server for the job's lifetime, stopped when the job ends).
    """
    name = cfg.decomposer.name
    agent_predicates = list(cfg.domain.agent_predicates)
    if name == "goal-split":
        from twostep.decomposers.goal_split import GoalSplitDecomposer

        yield GoalSplitDecomposer(agent_predicates, cfg.decomposer.link_degree)
    elif name == "expert":
        from twostep.decomposers.expert import ExpertDecomposer

        yield ExpertDecomposer()
    elif name == "plan-split":
        from twostep.decomposers.plan_split import PlanSplitDecomposer

        yield PlanSplitDecomposer(agent_predicates)
    elif name == "plan-deal":
        # Method-level too: run_twostep hands a PlanDeal to twostep.dealing.deal.run_plan_deal.
        from twostep.dealing.deal import PlanDeal

        yield PlanDeal(agent_predicates, cfg.decomposer.cut)
    elif name == "portfolio":
        # Method-level: run_twostep hands a Portfolio to twostep.methods.portfolio.run_portfolio.
        from twostep.methods.portfolio import Portfolio

        yield Portfolio(agent_predicates, cfg.decomposer.link_degree)
    elif name == "llm":
        from twostep.decomposers.llm import LLMDecomposer
        from twostep.llm import open_client

        with open_client(llm_settings(cfg)) as client:
            yield LLMDecomposer(client)
    else:
        raise JobError(f"unknown decomposer '{name}' (known: {', '.join(DECOMPOSERS)})")


def llm_settings(cfg: TwostepConfig) -> LLMSettings:
    """The LLM client's settings from the ``llm`` group (imported only for LLM jobs)."""
    from twostep.llm import LLMSettings

    llm = cfg.llm
    return LLMSettings(
        model=llm.model,
        temperature=float(llm.temperature),
        top_p=None if llm.top_p is None else float(llm.top_p),
        max_tokens=int(llm.max_tokens),
        api_base=llm.api_base,
        api_key_env=llm.api_key_env,
        mode=llm.mode,
        cache_dir=Path(llm.cache_dir),
        script=Path(llm.script) if llm.script else None,
        max_retries=int(llm.max_retries),
        backoff_s=float(llm.backoff_s),
        timeout_s=float(llm.timeout_s),
        use_cache=bool(llm.use_cache),
        local=bool(llm.local),
    )


def load_job_task(cfg: TwostepConfig) -> BenchmarkTask:
    cache = Path(cfg.output.root) / "cache" / "tasks"  # parsed PDDL: see load_problem
    return load_task(cfg.domain.name, int(cfg.task), Path(cfg.data.root), cache)


def check_job(cfg: TwostepConfig) -> None:
    """Reject a config that cannot run, before any work (and before any server starts)."""
    check_values(cfg)  # every value in range, one line naming the key and allowed values


def executor_settings(cfg: TwostepConfig) -> ExecutorSettings:
    """The embodied executor's settings; its seed is the job's."""
    return ExecutorSettings(
        seed=int(cfg.seed),
        max_steps=cfg.executor.max_steps,
        random_start=bool(cfg.executor.random_start),
        stall_limit=int(cfg.executor.stall_limit),
        backoff_radius=int(cfg.executor.backoff_radius),
    )
