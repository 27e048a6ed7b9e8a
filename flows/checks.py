"""Checks before any work: every config value in its allowed range, and every location a
job writes to writable. Each problem is one line naming the key (or the location) and
what is allowed; the command prints it and exits 2.

:func:`check_values` runs from :func:`flows.build.check_job` (every job, before any
planning); :func:`check_writable` runs from the Hydra callback (:mod:`flows.sweep_callback`)
before Hydra creates the run directory of a single run or the sweep directory of a
multirun (the jobs of a sweep write where the sweep was checked).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from flows.locations import local_folder, write_problem


class JobError(Exception):
    """A config that names something that does not exist or does not fit together (an
    input error: one line, exit 2)."""


class ValidationError(Exception):
    """A config value out of range, or a location that cannot be written (exit 2)."""


def _choice(key: str, value: Any, allowed: Iterable[str]) -> str | None:
    allowed = tuple(allowed)
    if str(value) in allowed:
        return None
    return f"{key}={value} is not allowed (allowed: {', '.join(allowed)})"


# The longest time limit a key may set: the planner's wall-clock guard (1.25 x its limit +
# 15 s) must fit the operating system's poll() timeout (2**31 - 1 ms, about 24.8 days).
MAX_SECONDS = 1_000_000


def _seconds(key: str, value: Any) -> str | None:
    """A time limit: a finite number of seconds, > 0 and at most :data:`MAX_SECONDS`."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        return f"{key}={value} must be a number > 0"
    if not number > 0:
        return f"{key}={value} must be > 0"
    if not math.isfinite(number) or number > MAX_SECONDS:
        return f"{key}={value} is too large (allowed: > 0 and at most {MAX_SECONDS} seconds)"
    return None


def value_problems(cfg: Any) -> list[str]:
    """Every out-of-range value of a job config (an empty list: all fine)."""
    # Imported here: the writability check of every run needs none of this.
    from twostep.execution.model import MODES as SCORE_MODES
    from twostep.llm.client import MODES as LLM_MODES
    from twostep.llm.client import key_env_problem
    from twostep.methods.registry import DECOMPOSERS, METHODS
    from twostep.processes import DEFAULT_MEMORY_LIMIT_MB, MIN_MEMORY_LIMIT_MB

    problems = [
        _choice("score_mode", cfg.score_mode, SCORE_MODES),
        _choice("method", cfg.method.name, METHODS),
        _choice("llm.mode", cfg.llm.mode, LLM_MODES),
        _seconds("planner.time_limit_s", cfg.planner.time_limit_s),
        _seconds("llm.timeout_s", cfg.llm.timeout_s),
        _seconds("mlflow.connect_timeout_s", cfg.mlflow.connect_timeout_s),
        _seconds(
            "orchestration.server_startup_timeout_s", cfg.orchestration.server_startup_timeout_s
        ),
        key_env_problem(cfg.llm.api_key_env),
    ]
    if cfg.method.name == "twostep":
        problems.append(_choice("decomposer", cfg.decomposer.name, DECOMPOSERS))
    if int(cfg.agents) < 1:
        problems.append(f"agents={cfg.agents} must be at least 1")
    memory = cfg.planner.memory_limit_mb
    if memory is not None and int(memory) < MIN_MEMORY_LIMIT_MB:
        problems.append(
            f"planner.memory_limit_mb={memory} must be at least {MIN_MEMORY_LIMIT_MB} (MB; "
            f"null: {DEFAULT_MEMORY_LIMIT_MB})"
        )
    if cfg.planner.grounding_time_limit_s is not None:
        problems.append(
            _seconds("planner.grounding_time_limit_s", cfg.planner.grounding_time_limit_s)
        )
    if cfg.score_max_nodes is not None and int(cfg.score_max_nodes) < 0:
        problems.append(f"score_max_nodes={cfg.score_max_nodes} must be >= 0 (or null)")
    if cfg.score_time_limit_s is not None:
        problems.append(_seconds("score_time_limit_s", cfg.score_time_limit_s))
    if int(cfg.llm.max_retries) < 0:
        problems.append(f"llm.max_retries={cfg.llm.max_retries} must be >= 0")
    return [p for p in problems if p]


def check_values(cfg: Any) -> None:
    """Raise :class:`JobError` naming the first bad value, before any planning."""
    problems = value_problems(cfg)
    if problems:
        raise JobError(problems[0])


def secret_problem(cfg: Any) -> str | None:
    """A key pasted where a variable's name belongs (``llm.api_key_env``), in the config or
    in any value a sweep's override lists: refused before Hydra writes the config and the
    overrides to disk. The message never repeats the value."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    from twostep.llm.client import key_env_problem

    values = [cfg.llm.api_key_env]
    overrides = [str(o) for o in cfg.hydra.overrides.task] if "hydra" in cfg else []
    named = [o for o in overrides if o.lstrip("+~").split("=", 1)[0] == "llm.api_key_env"]
    try:
        for override in OverridesParser.create().parse_overrides(named):
            sweep = override.is_sweep_override()
            values += list(override.sweep_iterator()) if sweep else [override.value()]
    except Exception:  # Hydra refuses the override itself, with its own message
        pass
    for value in values:
        problem = key_env_problem(None if value is None else str(value))
        if problem:
            return problem
    return None


# ----------------------------------------------------------------- writable locations


def writable_locations(cfg: Any, run_dir: Path | None = None) -> list[tuple[str, Path]]:
    """(what, folder) for every place a run of this config writes to; ``run_dir``: the
    Hydra run or sweep directory (not created yet when the callback asks)."""
    locations: list[tuple[str, Path]] = [
        ("output.root", Path(str(cfg.output.root))),
        ("orchestration.job_store", Path(str(cfg.orchestration.job_store))),
    ]
    if run_dir is not None:
        locations.append(("the run directory", run_dir))
    if cfg.mlflow.enabled:
        for key, uri in (
            ("mlflow.tracking_uri", cfg.mlflow.tracking_uri),
            ("mlflow.artifact_location", cfg.mlflow.artifact_location),
        ):
            folder = local_folder(None if uri is None else str(uri))
            if folder is not None:
                locations.append((key, folder))
    return locations


def check_writable(cfg: Any, run_dir: Path | None = None) -> None:
    """Raise :class:`ValidationError` naming the first location that cannot be written."""
    for key, folder in writable_locations(cfg, run_dir):
        problem = write_problem(folder)
        if problem:
            raise ValidationError(
                f"{key} {folder} is not writable ({problem}): choose another "
                "location (e.g. output.root=<folder>) or fix its permissions"
            )
