"""Finished jobs, stored by job key, so that no finished job is ever computed twice.

What goes into the key (the identity config and the content of every input file) and
which results are kept is decided by :mod:`twostep.identity`; this module reads the
config and the files, and owns ``<orchestration.job_store>/<key>/``. A result is written
once, atomically, after the job finished; a job that raised, or whose result says it did
not finish (``llm_error``, ``error``), is not stored: a re-run tries it again.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from twostep import identity
from twostep.benchmark import BenchmarkError, task_path
from twostep.files import write_json_atomic


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


def job_inputs(config: Mapping[str, Any]) -> dict[str, str]:
    """Digest of every file the job reads, by role (an unknown task: no problem file)."""
    try:
        problem: Path | None = task_path(
            str(config["domain"]["name"]), int(config["task"]), Path(str(config["data"]["root"]))
        )
    except (BenchmarkError, KeyError, TypeError, ValueError):
        problem = None  # the job fails on its input; it is not stored either
    return identity.input_digests(identity.job_input_files(config, problem))


def job_key(config: Mapping[str, Any], inputs: Mapping[str, str] | None = None) -> str:
    """The job's key (:func:`twostep.identity.job_key`); ``inputs``: :func:`job_inputs`."""
    return identity.job_key(config, inputs)


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

    def save(self, key: str, config: Mapping[str, Any], result: Mapping[str, Any]) -> bool:
        """Store a finished job's result; False (nothing written) for one that did not
        finish its work (:func:`twostep.identity.is_storable`)."""
        if not identity.is_storable(result):
            return False
        # config first: a stored result always has its config beside it.
        write_json_atomic(self.root / key / "config.json", dict(config))
        write_json_atomic(self.path(key), dict(result))
        return True

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
