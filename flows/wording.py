"""The library's messages worded for the command line, in one place.

The library names its own parameters when it says which setting to change
(``LLMSettings.mode=replay``, ``GroundingLimits.memory_mb``, ``GoalSplitDecomposer``); a
job's user sets them as config keys (``llm.mode=replay``, ``planner.memory_limit_mb``,
``decomposer=goal-split``). :data:`SETTING_KEYS` maps each library name that a message
may hold to what the command line calls it, and :func:`worded` rewrites a message with
it; flows/ applies it wherever a library message reaches the user or a stored result (an
``error:`` line, result.json, an MLflow field, a Prefect state), so what a job prints and
stores reads in config keys.
"""

from __future__ import annotations

import copy
import re
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from twostep.methods import RunResult

SETTING_KEYS: dict[str, str] = {
    # twostep.llm.LLMSettings (flows.build.llm_settings)
    "LLMSettings.model": "llm.model",
    "LLMSettings.api_key_env": "llm.api_key_env",
    "LLMSettings.mode": "llm.mode",
    "LLMSettings.script": "llm.script",
    "LLMSettings.bundle": "llm.bundle",
    "LLMSettings.translator": "llm.translator",
    # the model-free subgoal source a message offers instead of a model
    "GoalSplitDecomposer": "decomposer=goal-split",
    # the data root a task is read from (twostep.tasks.benchmark.load_task)
    "load_task(root=...)": "data.root",
    # resource limits (flows.build.planner_settings, grounding_limits)
    "GroundingLimits.memory_mb": "planner.memory_limit_mb",
    "GroundingLimits.time_s": "planner.grounding_time_limit_s",
    "PlannerSettings.memory_limit_mb": "planner.memory_limit_mb",
}
"""Library name -> the config key (or override) that sets it."""

_NAMES = re.compile(
    r"(?<![\w.])("
    + "|".join(re.escape(name) for name in sorted(SETTING_KEYS, key=len, reverse=True))
    + r")(?!\w|\.\w|\()"  # not a longer name, an attribute of it or a call
)


def worded(message: str) -> str:
    """``message`` with each library name of :data:`SETTING_KEYS` replaced by its config
    key: a whole name (``LLMSettings.mode=live``, ``... set LLMSettings.model.``), not part
    of a longer one, an attribute of it or a call (``GoalSplitDecomposer.__init__()``,
    ``GoalSplitDecomposer(facts)``: a traceback's words)."""
    return _NAMES.sub(lambda match: SETTING_KEYS[match.group(1)], message)


def setting_key(name: str) -> str:
    """The config key of the library name ``name`` (a :data:`SETTING_KEYS` name)."""
    return SETTING_KEYS[name]


def worded_run(run: RunResult) -> RunResult:
    """``run`` as a job records it: its message and its subgoals' reasons worded (an LLM
    call that failed says which setting to change); everything else as the library made
    it."""
    run.message = worded(run.message)
    for subgoal in run.subgoals:
        if isinstance(subgoal.get("reason"), str):
            subgoal["reason"] = worded(subgoal["reason"])
    return run


def worded_error(error: BaseException) -> BaseException:
    """``error`` with its message worded (:func:`worded`): a copy of the same type (an
    error that says no library name is returned as it is), for an error a job re-raises
    where an engine records its message (a Prefect flow run's state)."""
    text = str(error)
    said = worded(text)
    if said == text or error.args != (text,):
        return error
    copied = copy.copy(error)
    copied.args = (said,)
    return copied
