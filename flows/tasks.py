"""The pipeline's steps as Prefect tasks: each task calls one library function.

=================  =======================================  ==========================
task               library function                          cache / retries
=================  =======================================  ==========================
``plan``           :func:`twostep.planner.plan_pddl`         cached on PDDL text
``generate``       :func:`~twostep.decomposers.llm.generate_subgoal`   cached, retried
``translate``      :func:`~twostep.decomposers.llm.translate_subgoal`  cached, retried
``progress_state`` :func:`twostep.pipeline.progress`         no (microseconds)
``score``          :func:`twostep.pipeline.score`            no (milliseconds)
=================  =======================================  ==========================

:func:`prefect_steps` packs them into a :class:`twostep.pipeline.Steps`, so the library
runs its own control flow and only the step calls become task runs.

Cache keys are explicit (``cache_key_fn``): Prefect's INPUTS policy would hash Python
objects, and a :class:`~twostep.pddl.Problem` holds frozensets whose iteration order,
hence pickle, changes between processes. ``plan`` is keyed on the PDDL text the planner
reads, the planner settings, the Fast Downward wheel version and :data:`PLAN_VERSION`;
the LLM tasks on the LLM client's own request key (model, messages, sampling, seed: no
secret) plus :data:`LLM_VERSION`. Results persist under ``orchestration.result_storage``,
so a cache hit survives the process, the sweep and a ``kill -9``. A planner crash is not
cached (the task fails; the pipeline still gets the crash as a status), and scripted LLM
answers are never cached (they depend on call order).
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable, Collection, Sequence
from dataclasses import asdict
from functools import cache
from importlib import metadata
from typing import Any

from prefect import State, task
from prefect.cache_policies import NO_CACHE
from prefect.context import TaskRunContext
from prefect.utilities.annotations import quote

from flows.job import StepStats
from twostep import pipeline, planner
from twostep.execution import ParallelExecution
from twostep.pddl import Fact, Problem
from twostep.pipeline import Steps
from twostep.planner import PlannerSettings, PlanResult, Status

# Bump when a change in the library makes cached task results stale.
PLAN_VERSION = "plan-1"
LLM_VERSION = "llm-1"


@cache
def _planner_version() -> str:
    try:
        return f"up-fast-downward {metadata.version('up-fast-downward')}"
    except metadata.PackageNotFoundError:
        return "up-fast-downward unknown"


def _digest(data: Any) -> str:
    blob = json.dumps(data, sort_keys=True, ensure_ascii=False, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


class PlannerCrashed(Exception):
    """Raised by the ``plan`` task for a planner error, so the error is not cached."""

    def __init__(self, result: PlanResult) -> None:
        super().__init__(result)
        self.result = result

    def __str__(self) -> str:
        return f"planner error: {self.result.message}"


# ----------------------------------------------------------------- planner


def plan_cache_key(context: TaskRunContext, parameters: dict[str, Any]) -> str:
    settings: PlannerSettings = parameters["settings"]
    return _digest(
        {
            "task": "plan",
            "version": PLAN_VERSION,
            "planner": _planner_version(),
            "domain": parameters["domain_pddl"],
            "problem": parameters["problem_pddl"],
            "settings": asdict(settings),
        }
    )


@task(name="plan", persist_result=True, cache_key_fn=plan_cache_key)
def plan_task(domain_pddl: str, problem_pddl: str, settings: PlannerSettings) -> PlanResult:
    result = planner.plan_pddl(domain_pddl, problem_pddl, settings)
    if result.status is Status.ERROR:
        raise PlannerCrashed(result)
    return result


@task(name="progress_state", cache_policy=NO_CACHE, persist_result=False)
def progress_task(
    problem: Problem, plan_steps: Sequence[str], agent_predicates: Collection[str]
) -> frozenset[Fact]:
    return pipeline.progress(problem, plan_steps, agent_predicates)


@task(name="score", cache_policy=NO_CACHE, persist_result=False)
def score_task(
    problem: Problem, plans: Sequence[Sequence[str]], agent_predicates: Collection[str], mode: str
) -> ParallelExecution:
    return pipeline.score(problem, plans, agent_predicates, mode)


# ----------------------------------------------------------------- LLM


def _llm_request_key(client: Any, messages: Any, seed: int) -> str | None:
    if client.settings.mode == "scripted":
        return None  # answers depend on call order: never cache them
    return str(client.cache_key(client.request(messages, seed)))


def generate_cache_key(context: TaskRunContext, parameters: dict[str, Any]) -> str | None:
    from twostep.llm.prompts import generator_messages

    messages = generator_messages(
        parameters["task"],
        parameters["agents"],
        parameters["helper"],
        parameters["earlier"],
        fixed_example=parameters.get("fixed_example", True),
    )
    request = _llm_request_key(parameters["client"], messages, parameters["seed"])
    return None if request is None else _digest(["generate", LLM_VERSION, request])


def translate_cache_key(context: TaskRunContext, parameters: dict[str, Any]) -> str | None:
    from twostep.llm.prompts import translator_messages

    messages = translator_messages(parameters["task"], parameters["english"])
    request = _llm_request_key(parameters["client"], messages, parameters["seed"])
    if request is None:
        return None
    # helper and earlier subgoals decide the check (repeats are rejected), not the request
    earlier = sorted((parameters.get("earlier") or {}).items())
    return _digest(["translate", LLM_VERSION, request, parameters.get("helper", 1), earlier])


def _retry_transient(task: Any, task_run: Any, state: State[Any]) -> bool:
    """Retry only provider failures; missing credentials, replay misses and scripts are final."""
    from twostep.llm.client import LLMCallError

    try:
        error = state.result(raise_on_failure=False)
    except Exception:  # the state holds no readable result: do not retry blindly
        return False
    return isinstance(error, LLMCallError)


@task(
    name="generate",
    persist_result=True,
    cache_key_fn=generate_cache_key,
    retry_condition_fn=_retry_transient,
)
def generate_task(
    client: Any,
    task: Any,
    agents: int,
    helper: int,
    earlier: Sequence[str],
    seed: int,
    *,
    fixed_example: bool = True,
) -> tuple[str | None, dict[str, Any]]:
    from twostep.decomposers.llm import generate_subgoal

    return generate_subgoal(
        client, task, agents, helper, list(earlier), seed, fixed_example=fixed_example
    )


@task(
    name="translate",
    persist_result=True,
    cache_key_fn=translate_cache_key,
    retry_condition_fn=_retry_transient,
)
def translate_task(
    client: Any,
    task: Any,
    english: str,
    seed: int,
    *,
    helper: int = 1,
    earlier: dict[int, str] | None = None,
) -> tuple[str | None, dict[str, Any]]:
    from twostep.decomposers.llm import translate_subgoal

    return translate_subgoal(client, task, english, seed, helper=helper, earlier=earlier)


# ----------------------------------------------------------------- steps


def _run(task_fn: Any, submit: bool, *args: Any, **kwargs: Any) -> State[Any]:
    """Run a task and return its final state: inline, or on the flow's task runner."""
    if submit:
        future = task_fn.submit(*args, **kwargs)
        future.wait()
        return future.state  # type: ignore[no-any-return]
    return task_fn(*args, return_state=True, **kwargs)  # type: ignore[no-any-return]


def prefect_steps(stats: StepStats, submit: bool = False) -> Steps:
    """The pipeline's steps as task runs; ``submit`` sends planner calls to the task runner.

    Only ``plan`` is submitted: it is the step worth moving to a Dask worker, while
    progress_state and score take micro- to milliseconds and run inline.
    """

    def plan(problem: Problem, settings: PlannerSettings) -> PlanResult:
        if problem.goal.holds(problem.init):
            # The library answers this without calling the planner: no task run needed.
            return planner.plan(problem, settings)
        domain_pddl, problem_pddl = planner.planner_input(problem)
        state = _run(plan_task, submit, domain_pddl, problem_pddl, settings)
        outcome = state.result(raise_on_failure=False)
        if isinstance(outcome, PlannerCrashed):
            result = outcome.result
        elif isinstance(outcome, BaseException):
            raise outcome
        else:
            result = outcome
        cached = state.name == "Cached"
        stats.add(
            plan_calls=0 if cached else 1,
            plan_cache_hits=1 if cached else 0,
            planner_wall_s=0.0 if cached else result.wall_time_s,
        )
        return result

    def progress(
        problem: Problem, plan_steps: Sequence[str], agent_predicates: Collection[str]
    ) -> frozenset[Fact]:
        # quote(): Prefect must not walk the problem's fact sets looking for futures; it
        # hands the task the problem itself.
        environment: frozenset[Fact] = progress_task(
            quote(problem),  # type: ignore[call-overload]
            list(plan_steps),
            list(agent_predicates),
        )
        return environment

    def score(
        problem: Problem,
        plans: Sequence[Sequence[str]],
        agent_predicates: Collection[str],
        mode: str = "exact",
    ) -> ParallelExecution:
        execution: ParallelExecution = score_task(
            quote(problem),  # type: ignore[call-overload]
            [list(p) for p in plans],
            list(agent_predicates),
            mode,
        )
        return execution

    return Steps(propose=pipeline.propose, plan=plan, progress=progress, score=score)


def route_llm_calls(
    decomposer: Any, stats: StepStats, retries: int = 2, retry_delay_s: float = 5.0
) -> bool:
    """Run the LLM decomposer's ``generate`` and ``translate`` calls as Prefect tasks.

    The hook: a decomposer that exposes its two steps as the attributes ``generate`` and
    ``translate`` (same signatures as :func:`~twostep.decomposers.llm.generate_subgoal`
    and :func:`~twostep.decomposers.llm.translate_subgoal`) gets task-wrapped versions
    with retries, backoff and caching. Returns False, changing nothing, for a decomposer
    without them: its calls then run inside the job untasked (still replayed from the
    LLM client's own disk cache).
    """
    if not (hasattr(decomposer, "generate") and hasattr(decomposer, "translate")):
        return False
    delays = [retry_delay_s * 2**i for i in range(retries)]
    generate = generate_task.with_options(retries=retries, retry_delay_seconds=delays)
    translate = translate_task.with_options(retries=retries, retry_delay_seconds=delays)
    decomposer.generate = _llm_step(generate, stats)
    decomposer.translate = _llm_step(translate, stats)
    return True


def _llm_step(task_fn: Any, stats: StepStats) -> Callable[..., Any]:
    def call(client: Any, task: Any, *args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        state = task_fn(quote(client), quote(task), *args, return_state=True, **kwargs)
        cached = state.name == "Cached"
        stats.add(
            llm_calls=0 if cached else 1,
            llm_cache_hits=1 if cached else 0,
            llm_wall_s=0.0 if cached else time.perf_counter() - start,
        )
        return state.result()  # raises the task's error, as the plain function would

    return call
