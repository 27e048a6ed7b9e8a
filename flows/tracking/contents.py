"""What a job's MLflow run holds (docs/tracking.md): the tag names, params (what defines
the experiment, at most 15; nothing that looks like a secret), the tags of where and how
it ran, metrics from result.json, the status tags written last, and the record of one job
that every writer takes (:func:`job_record`); also the experiment name of a sweep.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from flows.identity import config_seed_matters, identity_config, is_relevant
from flows.redaction import redact_config
from flows.tracking.params import flatten_config
from twostep.util.outcome import SubgoalStatus

KIND = "twostep.kind"
JOB_KEY = "twostep.job_key"
SWEEP_KEY = "twostep.sweep_key"
OVERRIDES = "twostep.overrides"  # a sweep's overrides (its parent run's and experiment's tag)
STATUS = "twostep.status"
ERROR = "twostep.error"
SCRIPTED = "twostep.scripted_llm"
REUSED = "twostep.reused"
RESTORED = "twostep.restored_from_job_store"  # logged again: the store had lost the run
PARENT = "mlflow.parentRunId"
# Experiment tags: MLflow 3's UI opens an experiment of this kind on its runs table (not
# the GenAI overview); the note is the experiment's description (the sweep's command).
EXPERIMENT_KIND = "mlflow.experimentKind"
CLASSIC_RUNS = "custom_model_development"
NOTE = "mlflow.note.content"
GRID_AGENTS = "twostep.grid_agents"  # the grid's N (an SA job runs one agent whatever it is)
CONFIG = "twostep.config"  # the rest of the job's identity config, as JSON
DATA_ROOT = "twostep.data_root"
# Whether the job's seeds differ (the LLM, the embodied executor) or repeat one run.
DISTINCT_RUNS = "twostep.distinct_runs"
ONE_RUN = "1 (deterministic: every seed repeats this run)"
PER_SEED = "one per seed"

# The params of a job run: what defines the experiment (where it runs goes to tags). A
# key the job's method never reads (``decomposer.*`` for SA, ``llm.*`` without the LLM
# decomposer) is left out: flows.identity.is_relevant.
EXPERIMENT_PARAMS: tuple[str, ...] = (
    "domain.name",
    "task",
    "method.name",
    "agents",
    "seed",
    "decomposer.name",
    "planner.alias",
    "planner.time_limit_s",
    "llm.model",
    "llm.mode",
    "llm.translator",
    "score_mode",
    "executor.name",
)

DEFAULT_EXPERIMENT = "twostep"
_SECRET = re.compile(r"api_key|secret|token|password|authorization", re.IGNORECASE)
PARAM_LIMIT = 6000
TAG_LIMIT = 5000


def clip(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def metric_points(
    metrics: Mapping[str, float | list[float]], timestamp_ms: int
) -> list[tuple[str, float, int, int]]:
    """``(key, value, timestamp, step)`` of every metric point: a list is one point per step."""
    points: list[tuple[str, float, int, int]] = []
    for key, value in metrics.items():
        if isinstance(value, list):
            points += [(key, float(v), timestamp_ms, step) for step, v in enumerate(value)]
        else:
            points.append((key, float(value), timestamp_ms, 0))
    return points


def job_tags(record: Mapping[str, Any]) -> dict[str, str]:
    """The status tags written at the end of a job run's logging, in one batch."""
    tags = {
        STATUS: str(record["status"]),
        SCRIPTED: "true" if record["scripted"] else "false",
        REUSED: "true" if record["reused"] else "false",
    }
    if record["error"]:
        tags[ERROR] = str(record["error"])
    if record.get("restored"):
        tags[RESTORED] = "true"
    return tags


EXPERIMENT_NAME_LIMIT = 60


def experiment_name_for(overrides: Iterable[str], sweep_key: str) -> str:
    """A sweep's experiment name: short, told apart by its first characters, the same
    for the same command: ``sweep`` and the sweep key's first 12 characters (its Prefect
    tag ``sweep:<those>``), then as many of the overrides as fit in
    :data:`EXPERIMENT_NAME_LIMIT` characters (all of them are the experiment's
    description and its tag ``twostep.overrides``)."""
    name = f"sweep {sweep_key[:12]}"
    shown = " ".join(overrides) or "(defaults)"
    room = EXPERIMENT_NAME_LIMIT - len(name) - 1
    return f"{name} {shown if len(shown) <= room else shown[: room - 3].rstrip() + '...'}"


def _method_of(config: Mapping[str, Any]) -> tuple[str | None, str | None]:
    flat = flatten_config(config)
    return flat.get("method.name"), flat.get("decomposer.name")


def job_params(config: Mapping[str, Any]) -> dict[str, str]:
    """What defines the job's experiment (:data:`EXPERIMENT_PARAMS`, those its method
    reads); ``agents`` is the N the job ran: 1 for SA (the grid's N is a tag). Secret-looking
    keys never are params; credentials inside URLs are masked
    (:func:`flows.redaction.redact_config`)."""
    method, decomposer = _method_of(config)
    flat = flatten_config(redact_config(config))
    params: dict[str, str] = {}
    for key in EXPERIMENT_PARAMS:
        if key in flat and is_relevant(key, method, decomposer) and not _SECRET.search(key):
            params[key] = clip(flat[key], PARAM_LIMIT)
    if method == "sa" and "agents" in params:
        params["agents"] = "1"
    return params


def config_tags(config: Mapping[str, Any]) -> dict[str, str]:
    """Tags of a job run made from its config: the grid's N, the data root, and the rest
    of what defines the job (its identity config without the params) as JSON, which the
    report reads to tell series apart (``decomposer.cut=best`` vs ``first``)."""
    flat = flatten_config(config)
    tags: dict[str, str] = {}
    if "agents" in flat:
        tags[GRID_AGENTS] = flat["agents"]
    if "data.root" in flat:
        tags[DATA_ROOT] = flat["data.root"]
    tags[DISTINCT_RUNS] = PER_SEED if config_seed_matters(config) else ONE_RUN
    rest = {
        key: value
        for key, value in flatten_config(redact_config(identity_config(config))).items()
        if key not in EXPERIMENT_PARAMS and key != "data.root" and not _SECRET.search(key)
    }
    text = json.dumps(rest, sort_keys=True)
    if len(text) <= TAG_LIMIT:
        tags[CONFIG] = text
    return tags


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, int | float):
        return float(value)
    return None


# A job that did not succeed (timed out, failed) logs its outcome's values under these
# names, which no successful run has: MLflow's grouped means of ``planning_time_s``,
# ``exec_length``... are then over the same successful runs (a timed-out run's planning
# time, the time limit, never enters them). Shared by every run: ``success``, the counts
# of planner calls stopped by their limit, and the job's orchestration timings.
UNSOLVED_PREFIX = "unsolved."
SHARED_METRICS: frozenset[str] = frozenset({"success", "planner_timeouts", "planner_guard_stops"})


def unsolved_name(metric: str) -> str:
    """The name a metric of an unsuccessful job is logged under (``unsolved.<metric>``)."""
    return f"{UNSOLVED_PREFIX}{metric}"


def job_metrics(result: Mapping[str, Any], timings: Mapping[str, float]) -> dict[str, Any]:
    """Metrics of one job (docs/tracking.md); a value that is absent is not logged; an
    unsuccessful job's outcome values go under ``unsolved.<name>`` (:data:`UNSOLVED_PREFIX`)."""
    metrics = _outcome_metrics(result)
    if not result.get("success"):
        metrics = {
            key if key in SHARED_METRICS else unsolved_name(key): value
            for key, value in metrics.items()
        }
    for key, value in timings.items():
        metrics[key] = float(value)
    return metrics


def _outcome_metrics(result: Mapping[str, Any]) -> dict[str, Any]:
    """What the job's result says, as metrics (timings of the orchestration apart)."""
    metrics: dict[str, Any] = {"success": 1.0 if result.get("success") else 0.0}
    for key in (
        "exec_length",
        "sa_length",
        "planning_time_s",
        "llm_time_s",
        "state_editing_time_s",
        "wall_time_s",
        "sa_planning_time_s",
        "embodied_length",  # executor=embodied
        "waits",
        "backoffs",
    ):
        number = _number(result.get(key))
        if number is not None:
            metrics[key] = number
    exec_length, sa_length = _number(result.get("exec_length")), _number(result.get("sa_length"))
    if exec_length and sa_length is not None:
        metrics["speedup_exec"] = sa_length / exec_length
    subgoals = result.get("subgoals")
    if result.get("method") == "twostep" and isinstance(subgoals, list):
        statuses = [s.get("status") for s in subgoals if isinstance(s, Mapping)]
        metrics["subgoals_proposed"] = float(len(statuses))
        metrics["subgoals_accepted"] = float(statuses.count(SubgoalStatus.ACCEPTED))
        metrics["subgoals_discarded"] = float(statuses.count(SubgoalStatus.DISCARDED))
    translation = result.get("translation")
    if isinstance(translation, Mapping) and isinstance(translation.get("failed"), int):
        # the rules translator could not read these (llm.translator=rules): discarded
        metrics["subgoals_untranslated"] = float(translation["failed"])
    calls = [c for c in result.get("planner_calls") or [] if isinstance(c, Mapping)]
    for call in calls:
        number = _number(call.get("planner_time_s"))
        if number is not None:
            metrics[f"planner_time_s.{call.get('role')}.{call.get('agent')}"] = number
    per_call = [_number(c.get("planner_time_s")) for c in calls]
    if per_call and all(v is not None for v in per_call):
        metrics["planner_time_s"] = [v for v in per_call if v is not None]
    if calls:  # Table II's "timeout": planner calls stopped by their own time limit
        from twostep.planner.limits import guard_stops, planner_limit_hits

        metrics["planner_timeouts"] = float(planner_limit_hits(result))
        metrics["planner_guard_stops"] = float(guard_stops(result))
    return metrics


def job_record(
    *,
    key: str,
    name: str,
    status: str,
    error: str | None,
    reused: bool,
    config: Mapping[str, Any],
    result: Mapping[str, Any],
    timings: Mapping[str, float],
    files: Iterable[tuple[Path, str | None]],
    tags: Mapping[str, str] | None = None,
    window: tuple[float, float] | None = None,
) -> dict[str, Any]:
    """One job as plain data, as every writer logs it (:func:`flows.tracking.client.
    log_job_run`, the helper process). ``tags``: the run's system tags
    (:func:`flows.tracking.context.run_context_tags`); ``window``: when the job started and
    ended (``time.time()``), the run's start and end."""
    start, end = window if window is not None else (None, None)
    return {
        "key": key,
        "name": name,
        "status": status,
        "error": error,
        "reused": reused,
        "scripted": bool(result.get("scripted_llm")),
        "params": job_params(config),
        "metrics": job_metrics(result, timings),
        "files": [[str(path), folder] for path, folder in files],
        "tags": {**(tags or {}), **config_tags(config)},
        "start_ms": None if start is None else int(start * 1000),
        "end_ms": None if end is None else int(end * 1000),
    }
