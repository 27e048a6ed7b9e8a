"""What the jobs of one sweep share on disk: the sweep's state, its identity, job records.

The launching process (:class:`flows.sweep_callback.SweepCallback`) writes
``<sweep dir>/.twostep/sweep.json``; every job reads it. Jobs report to
``.twostep/jobs/<num>.json`` (one file each: nothing to lock between joblib or submitit
workers); the progress line and the summary are computed from those files.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from omegaconf import DictConfig

from flows.identity import is_sweep_identity_key
from twostep.util.files import write_json_atomic
from twostep.util.redaction import redact_text

STATE_DIR = ".twostep"


@dataclass
class SweepState:
    """What the launching process tells every job of the sweep."""

    sweep_dir: str
    started_at: float
    main_pid: int
    hostname: str = ""
    total_jobs: int | None = None
    parallel: int | None = None  # jobs the launcher runs at once (None: not known)
    sweep_key: str = ""
    overrides: list[str] = field(default_factory=list)
    command: str = ""  # the sweep's command line (credentials in URLs masked)
    tracking_uri: str | None = None  # None: MLflow off
    artifact_location: str | None = None
    experiment: str | None = None
    server: dict[str, Any] | None = None  # ServerSettings for an on-demand server
    prefect_api_url: str | None = None  # a server the user runs (not ours to start or stop)
    dask_address: str | None = None

    @property
    def folder(self) -> Path:
        return Path(self.sweep_dir) / STATE_DIR

    @staticmethod
    def path(sweep_dir: Path) -> Path:
        return Path(sweep_dir) / STATE_DIR / "sweep.json"

    def save(self) -> None:
        write_json_atomic(self.path(Path(self.sweep_dir)), asdict(self))

    @classmethod
    def load(cls, sweep_dir: Path) -> SweepState | None:
        try:
            return cls(**json.loads(cls.path(sweep_dir).read_text()))
        except (OSError, ValueError, TypeError):
            return None

    @property
    def run_tag(self) -> str:
        """Prefect tag of this multirun's flow runs (a resumed sweep gets a new one)."""
        folder = Path(self.sweep_dir)
        return f"multirun:{folder.parent.name}_{folder.name}"

    @property
    def sweep_tag(self) -> str:
        """Prefect tag shared by every attempt of the same sweep."""
        return f"sweep:{self.sweep_key[:12]}"


# ----------------------------------------------------------------- sweep identity


def sweep_overrides(config: DictConfig) -> list[str]:
    """The sweep's command-line overrides that define what it computes, sorted.

    An experiment's grid is named by the command line that selects it
    (``experiment=paper``), not by the grid it expands to.
    """
    chosen: dict[str, str] = {}
    for item in config.hydra.overrides.task:
        key, _, value = str(item).partition("=")
        chosen[key] = value
    chosen = {key: redact_text(value) for key, value in chosen.items()}  # no URL credentials
    return sorted(f"{key}={value}" for key, value in chosen.items() if is_sweep_identity_key(key))


def sweep_key(overrides: list[str]) -> str:
    return hashlib.sha256("\n".join(overrides).encode()).hexdigest()[:32]


def count_jobs(config: DictConfig) -> int | None:
    """How many jobs the basic sweeper will launch (None if it cannot be told).

    The sweeper's parameters, then the command line (a later value of a key replaces an
    earlier one, as in the sweeper), parsed with Hydra's public override parser; the
    grid is the product of the number of values of every key.
    """
    if str(config.hydra.sweeper.get("_target_", "")).endswith("BundleSweeper"):
        from flows.replay_sweeper import planned_jobs  # experiment=paper_replay

        try:
            return len(planned_jobs(config))
        except Exception:
            return None
    try:
        from hydra.core.override_parser.overrides_parser import OverridesParser

        params = config.hydra.sweeper.get("params") or {}
        arguments = [f"{k}={v}" for k, v in params.items()]
        arguments += [str(o) for o in config.hydra.overrides.task]
        values: dict[str, int] = {}
        for override in OverridesParser.create().parse_overrides(arguments):
            key = override.get_key_element()
            sweep = override.is_sweep_override()
            values[key] = len(list(override.sweep_iterator())) if sweep else 1
        return math.prod(values.values())
    except Exception:  # another sweeper's syntax: progress shows "?"
        return None


def launcher_parallelism(config: DictConfig) -> int | None:
    """How many jobs the launcher runs at once: 1 for Hydra's basic launcher, joblib's
    ``n_jobs`` (-1: every core); None when it cannot be told (e.g. SLURM)."""
    launcher = config.hydra.launcher
    target = str(launcher.get("_target_", ""))
    if target.endswith("BasicLauncher"):
        return 1
    n_jobs = launcher.get("n_jobs") if "Joblib" in target else None
    if not isinstance(n_jobs, int) or n_jobs == 0:
        return None
    cores = os.cpu_count() or 1
    return n_jobs if n_jobs > 0 else max(1, cores + 1 + n_jobs)


# ----------------------------------------------------------------- job records


def record_job(sweep_dir: Path, num: int, record: Mapping[str, Any]) -> None:
    write_json_atomic(Path(sweep_dir) / STATE_DIR / "jobs" / f"{num}.json", dict(record))


# Records read by this process, by file: (modification time and size, the record). A
# record is written once per job (atomically, a new file each time), so a job's progress
# line reads only the records that are new since this process's last line, not all of
# them: with thousands of jobs, reading every record for every line would cost more per
# job the bigger the sweep.
_READ: dict[Path, tuple[tuple[int, int], dict[str, Any]]] = {}


def job_records(sweep_dir: Path) -> list[dict[str, Any]]:
    """The sweep's job records, in file name order."""
    records = []
    folder = Path(sweep_dir) / STATE_DIR / "jobs"
    try:
        entries = sorted(
            (e for e in os.scandir(folder) if e.name.endswith(".json")), key=lambda e: e.name
        )
    except OSError:
        return []
    for entry in entries:
        path = Path(entry.path)
        try:
            stat = entry.stat()
        except OSError:
            continue
        version = (stat.st_mtime_ns, stat.st_size)
        known = _READ.get(path)
        if known is not None and known[0] == version:
            records.append(known[1])
            continue
        with contextlib.suppress(OSError, ValueError):
            record = json.loads(path.read_text())
            _READ[path] = (version, record)
            records.append(record)
    return records
