"""Finished jobs, stored by job key, so that no finished job is ever computed twice.

The job key is a hash of the job's resolved config without the keys that only say
*where* or *how* a job runs (``hydra``, ``output``, ``mlflow``, ``orchestration``,
``llm.cache_dir``), plus :data:`JOB_VERSION`. The same job in another sweep, with another
launcher, or after a ``kill -9`` has the same key. Its result is written once, atomically,
to ``<orchestration.job_store>/<key>/result.json`` after the job finished; a job that
raised is not stored (a re-run tries it again).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

# Bump when a change to the pipeline makes stored results stale.
JOB_VERSION = "job-1"

# Top-level keys (or dotted paths) that do not change what a job computes.
NOT_IN_KEY = ("hydra", "output", "mlflow", "orchestration", "experiment", "llm.cache_dir")


def job_config(cfg: Any) -> dict[str, Any]:
    """The job's resolved config as plain data, without ``hydra``."""
    from omegaconf import DictConfig, OmegaConf

    if isinstance(cfg, DictConfig):
        data = OmegaConf.to_container(cfg, resolve=True, enum_to_str=True)
    else:
        data = dict(cfg)
    assert isinstance(data, dict)
    data.pop("hydra", None)
    return {str(k): v for k, v in data.items()}


def _without(data: Mapping[str, Any], dotted: str) -> dict[str, Any]:
    head, _, rest = dotted.partition(".")
    out = dict(data)
    if head not in out:
        return out
    if not rest:
        del out[head]
    elif isinstance(out[head], Mapping):
        out[head] = _without(out[head], rest)
    return out


def job_key(config: Mapping[str, Any]) -> str:
    """Stable hash of what the job computes (``twostep.job_key`` in MLflow)."""
    identity: dict[str, Any] = dict(config)
    for dotted in NOT_IN_KEY:
        identity = _without(identity, dotted)
    blob = json.dumps({"version": JOB_VERSION, "config": identity}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:32]


def write_json_atomic(path: Path, data: Any) -> None:
    """Write JSON so that a reader (or a ``kill -9``) never sees half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, indent=2, default=str) + "\n")
    os.replace(tmp, path)


class JobStore:
    """``<root>/<job key>/result.json`` (+ ``config.json``) for every finished job.

    ``mlflow.json`` beside them remembers the runs the result was fully logged to, so a
    re-run that reuses the result does not need MLflow at all (delete the file to log
    the job again, e.g. after deleting its run in MLflow).
    """

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)

    def path(self, key: str) -> Path:
        return self.root / key / "result.json"

    def load(self, key: str) -> dict[str, Any] | None:
        try:
            data = json.loads(self.path(key).read_text())
        except (OSError, ValueError):
            return None
        return data if isinstance(data, dict) else None

    def save(self, key: str, config: Mapping[str, Any], result: Mapping[str, Any]) -> None:
        # config first: a stored result always has its config beside it.
        write_json_atomic(self.root / key / "config.json", dict(config))
        write_json_atomic(self.path(key), dict(result))

    def logged_to(self, key: str) -> dict[str, str]:
        """``"<tracking uri> <experiment>" -> run id`` for the runs holding this job."""
        try:
            data = json.loads((self.root / key / "mlflow.json").read_text())
        except (OSError, ValueError):
            return {}
        return {str(k): str(v) for k, v in data.items()} if isinstance(data, dict) else {}

    def mark_logged(self, key: str, tracking_uri: str, experiment: str, run_id: str) -> None:
        if not (self.root / key).is_dir():
            return  # the job is not stored (it failed): nothing to skip next time
        logged = self.logged_to(key)
        logged[f"{tracking_uri} {experiment}"] = run_id
        write_json_atomic(self.root / key / "mlflow.json", logged)
