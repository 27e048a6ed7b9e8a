"""Checks before any work: every config value in its allowed range, and every location a
job writes to writable. Each problem is one line naming the key (or the location) and
what is allowed; the command prints it and exits 2.

:func:`check_values` runs from :func:`flows.build.check_job` (every job, before any
planning); :func:`check_writable` runs from the Hydra callback (:mod:`flows.sweep_callback`)
before Hydra creates the run directory of a single run or the sweep directory of a
multirun (the jobs of a sweep write where the sweep was checked).
"""

from __future__ import annotations

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


def _positive(key: str, value: Any) -> str | None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return f"{key}={value} must be a number > 0"
    return None if number > 0 else f"{key}={value} must be > 0"


def value_problems(cfg: Any) -> list[str]:
    """Every out-of-range value of a job config (an empty list: all fine)."""
    # Imported here: the writability check of every run needs none of this.
    from twostep.execution.model import MODES as SCORE_MODES
    from twostep.llm.client import MODES as LLM_MODES
    from twostep.methods.registry import DECOMPOSERS, METHODS

    problems = [
        _choice("score_mode", cfg.score_mode, SCORE_MODES),
        _choice("method", cfg.method.name, METHODS),
        _choice("llm.mode", cfg.llm.mode, LLM_MODES),
        _positive("planner.time_limit_s", cfg.planner.time_limit_s),
        _positive("llm.timeout_s", cfg.llm.timeout_s),
        _positive("mlflow.connect_timeout_s", cfg.mlflow.connect_timeout_s),
        _positive(
            "orchestration.server_startup_timeout_s", cfg.orchestration.server_startup_timeout_s
        ),
    ]
    if cfg.method.name == "twostep":
        problems.append(_choice("decomposer", cfg.decomposer.name, DECOMPOSERS))
    if int(cfg.agents) < 1:
        problems.append(f"agents={cfg.agents} must be at least 1")
    if cfg.planner.memory_limit_mb is not None and int(cfg.planner.memory_limit_mb) <= 0:
        problems.append(f"planner.memory_limit_mb={cfg.planner.memory_limit_mb} must be > 0")
    if cfg.score_max_nodes is not None and int(cfg.score_max_nodes) < 0:
        problems.append(f"score_max_nodes={cfg.score_max_nodes} must be >= 0 (or null)")
    if cfg.score_time_limit_s is not None:
        problems.append(_positive("score_time_limit_s", cfg.score_time_limit_s))
    if int(cfg.llm.max_retries) < 0:
        problems.append(f"llm.max_retries={cfg.llm.max_retries} must be >= 0")
    return [p for p in problems if p]


def check_values(cfg: Any) -> None:
    """Raise :class:`JobError` naming the first bad value, before any planning."""
    problems = value_problems(cfg)
    if problems:
        raise JobError(problems[0])


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
