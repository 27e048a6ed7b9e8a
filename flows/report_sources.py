"""Where a report's runs come from, on the config's side: the run table's canonical
columns made from a job's config, and what its ``param.*`` columns stand for.

The library's report (:mod:`twostep.report`) takes a run table with canonical columns and
knows no config; this module is the one that does:

- :data:`KEY_PARAMS`: the config keys that are the table's key columns (domain, method,
  decomposer, ...); :func:`params_to_columns` splits a job's flat params into those and
  ``param.*`` columns (MLflow's params, a job's ``.hydra/config.yaml``);
- :func:`load_runs_from_sweep_dir`: a Hydra multirun directory's jobs (``result.json``
  and ``.hydra/config.yaml``), without MLflow;
- :data:`RUN_PARAMS`: what the ``param.*`` columns stand for: the job identity's rules
  (:mod:`flows.identity`: which params can split a series, which a method reads), the
  executor, the planner's settings; passed to :func:`twostep.report.build_report`;
- :func:`replay_bundle`, :func:`replay_model`, :func:`replay_settings`: the replayed LLM
  runs' bundle, model and settings, for the replay report.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from flows.identity import is_identity_key, is_relevant
from flows.spelling import recorded
from flows.tracking.params import flatten_config
from twostep.report.runs import (
    PARAM_PREFIX,
    ReportInputError,
    RunParams,
    normalise_runs,
    result_to_row,
)
from twostep.util.files import FileFormatError, read_yaml_file

#: Config keys that are the key columns themselves (not kept as ``param.*`` columns).
KEY_PARAMS: dict[str, str] = {
    "domain.name": "domain",
    "task": "task",
    "method.name": "method",
    "decomposer.name": "decomposer",
    "agents": "agents",
    "seed": "seed",
}

RUN_PARAMS = RunParams(
    identity=is_identity_key,
    read_by=is_relevant,
    executor="executor.name",
    planner=(("planner.alias", ""), ("planner.time_limit_s", " s")),
)
"""What a run table's ``param.*`` columns stand for: the config's rules, for the report."""


def params_to_columns(params: Mapping[str, str]) -> dict[str, Any]:
    """Split flattened params into key columns and ``param.*`` columns."""
    row: dict[str, Any] = {}
    for key, value in params.items():
        if key in KEY_PARAMS:
            row[KEY_PARAMS[key]] = value
        elif not key.startswith("hydra."):
            row[PARAM_PREFIX + key] = value
    return row


def _read_hydra_config(job_dir: Path) -> dict[str, str]:
    path = job_dir / ".hydra" / "config.yaml"
    if not path.is_file():
        return {}
    try:
        loaded = read_yaml_file(path)
    except FileFormatError:
        return {}
    if not isinstance(loaded, Mapping):
        return {}
    # as the job was recorded (flows.spelling): method=plan-deal's params are the old
    # spelling's, so that the runs of both spellings are one series
    return flatten_config(recorded({str(k): v for k, v in loaded.items()}))


def _job_dirs(root: Path) -> Iterable[Path]:
    seen: set[Path] = set()
    for path in sorted(root.rglob("result.json")):
        seen.add(path.parent)
    for path in sorted(root.rglob(".hydra/config.yaml")):
        seen.add(path.parent.parent)
    return sorted(seen)


def load_runs_from_sweep_dir(root: Path) -> pd.DataFrame:
    """The canonical run table of a Hydra multirun directory, without MLflow (report it
    with ``build_report(runs, params=RUN_PARAMS)``).

    Every job directory below ``root`` counts: one with a ``result.json`` gives its
    metrics; one with only ``.hydra/config.yaml`` (the job started but wrote no result)
    is a failed run. Params come from the job's ``.hydra/config.yaml`` when present.
    """
    if not root.is_dir():
        raise ReportInputError(f"sweep dir not found: {root}")
    rows: list[dict[str, Any]] = []
    for job_dir in _job_dirs(root):
        params = _read_hydra_config(job_dir)
        row = params_to_columns(params)
        row["agents_param"] = params.get("agents")  # as launched (SA ignores it)
        result_path = job_dir / "result.json"
        if result_path.is_file():
            try:
                result = json.loads(result_path.read_text())
            except (OSError, json.JSONDecodeError) as error:
                row.update(status="failed", error=f"unreadable result.json: {error}")
            else:
                if isinstance(result, Mapping):
                    row.update({k: v for k, v in result_to_row(result).items() if v is not None})
                else:
                    row.update(status="failed", error="result.json is not a JSON object")
        else:
            row.update(status="failed", error="job wrote no result.json")
        row["run_id"] = str(job_dir.relative_to(root)) if job_dir != root else "."
        rows.append(row)
    if not rows:
        raise ReportInputError(f"no job directories (result.json or .hydra/) under {root}")
    return normalise_runs(pd.DataFrame.from_records(rows))


def _param(runs: pd.DataFrame, key: str) -> list[str]:
    column = f"{PARAM_PREFIX}{key}"
    if column not in runs:
        return []
    replayed = runs[(runs["method"] == "twostep") & (runs["decomposer"] == "llm")]
    return [str(v) for v in dict.fromkeys(replayed[column]) if str(v) not in ("", "None", "nan")]


def replay_bundle(runs: pd.DataFrame) -> str | None:
    """The bundle the replayed TwoStep runs read (``llm.bundle``), if exactly one."""
    found = _param(runs, "llm.bundle")
    return found[0] if len(found) == 1 else None


def replay_model(runs: pd.DataFrame) -> str | None:
    found = _param(runs, "llm.model")
    return found[0] if len(found) == 1 else None


def replay_settings(runs: pd.DataFrame) -> dict[str, str]:
    """How the replayed runs planned and scored, for the report's caption."""
    alias = ", ".join(_param(runs, "planner.alias")) or "?"
    limit = ", ".join(_param(runs, "planner.time_limit_s")) or "?"
    score = ", ".join(_param(runs, "score_mode")) or "exact"
    translator = ", ".join(_param(runs, "llm.translator")) or "?"
    return {
        "planner": f"Fast Downward {alias}, search time limit {limit} s (TwoStep: that / N per agent)",
        "score": f"{score} (minimum makespan)" if score == "exact" else score,
        "translator": translator,
    }
