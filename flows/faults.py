"""Faults of the machine while jobs run (a full disk, a read-only output folder): one line
each, never a traceback, and the sweep goes on to its summary.

Hydra creates a job's run directory and writes its ``.hydra/*.yaml`` before any callback
of ours runs (``hydra.core.utils.run_job``); a full disk or a folder made read-only
mid-sweep made that a traceback that ended the sweep without its summary and left its
MLflow parent run ``RUNNING``. :func:`guard_jobs` wraps ``run_job`` where the launchers
call it (Hydra's, for its basic launcher and a single run; the twostep launcher's, in its
worker processes): such a job is a ``failed`` job with one line naming the folder and the
error, recorded in the sweep, and the next job is tried. The same holds for a job that
raised ``OSError`` while writing its own files. When even its record cannot be written, it
is kept here (:data:`UNRECORDED`); a worker process returns it (:class:`JobFault`) and the
launching process keeps it (:func:`adopt_faults`), so the summary counts every job and the
exit code says whether one failed. :func:`quiet_store_errors` keeps MLflow's SQLAlchemy
tracebacks off the console (the job's ``warning: ...: not logged to MLflow: ...`` line
says it), and Python's ``--- Logging error ---`` tracebacks of a log file that cannot be
written.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from twostep.util import outcome

# Records of jobs that failed on a fault and whose record could not be written either
# (the disk is full): the sweep's summary counts them (flows.sweep_callback).
UNRECORDED: list[dict[str, Any]] = []
# Set when a job of this process failed on a fault (a single run exits 1).
FAULTED: list[str] = []


@dataclass
class JobFault:
    """What a job that met a fault returns: its sweep record, and whether it was written."""

    record: dict[str, Any]
    recorded: bool


def _keep(record: dict[str, Any]) -> None:
    """Keep a record that could not be written (it replaces the job's earlier one: the
    fault came after it)."""
    UNRECORDED[:] = [r for r in UNRECORDED if r.get("num") != record.get("num")]
    UNRECORDED.append(record)


def adopt_faults(returns: Iterable[Any]) -> None:
    """In the launching process: keep the records of jobs whose worker met a fault and
    could not write them (:class:`JobFault`)."""
    for ret in returns:
        fault = getattr(ret, "_return_value", None)
        if isinstance(fault, JobFault) and not fault.recorded:
            _keep(fault.record)


_MLFLOW_LOGGERS = ("mlflow.store.db.utils", "alembic.runtime.migration")


def quiet_store_errors() -> None:
    """No tracebacks from MLflow's store (a job says itself what was not logged) or from
    a log handler that cannot write (``logging.raiseExceptions``)."""
    logging.raiseExceptions = False
    for name in _MLFLOW_LOGGERS:
        logging.getLogger(name).setLevel(logging.CRITICAL)


def _fault_line(error: OSError, config: Any) -> str:
    where = error.filename or str(config.hydra.runtime.get("output_dir") or "")
    what = error.strerror or type(error).__name__
    return f"cannot write {where} ({what})"


def _job_label(config: Any) -> str:
    try:
        from flows.identity import job_name
        from flows.store import job_config

        return job_name(job_config(config))
    except Exception:  # a config that does not resolve: its overrides say which job
        return " ".join(str(o) for o in config.hydra.overrides.task)


def _failed(config: Any, error: OSError) -> Any:
    """A job that met a fault: its one line, its record, and a return Hydra accepts."""
    from hydra.core.utils import JobReturn, JobStatus
    from hydra.types import RunMode

    line = _fault_line(error, config)
    name = _job_label(config)
    FAULTED.append(line)
    print(f"error: {name}: {line}", file=sys.stderr, flush=True)
    fault = None
    if config.hydra.mode == RunMode.MULTIRUN:
        from flows.sweep_state import record_job

        num = int(config.hydra.job.num)
        record = {
            "num": num,
            "name": name,
            "status": outcome.JobStatus.FAILED.value,  # ours, not Hydra's JobStatus
            "error": line,
            "fault": True,
        }
        fault = JobFault(record, recorded=True)
        try:
            record_job(Path(str(config.hydra.sweep.dir)), num, record)
        except OSError:
            fault.recorded = False
            _keep(record)
    ret = JobReturn()
    ret.status = JobStatus.COMPLETED  # recorded as failed: the sweep goes on
    ret.return_value = fault
    return ret


def _guarded(run_job: Any) -> Any:
    def run_job_guarded(task_function: Any, config: Any, *args: Any, **kwargs: Any) -> Any:
        from hydra.core.utils import JobStatus

        try:
            ret = run_job(task_function, config, *args, **kwargs)
        except OSError as error:  # Hydra's mkdir or config files
            return _failed(config, error)
        if ret.status == JobStatus.FAILED and isinstance(ret._return_value, OSError):
            return _failed(config, ret._return_value)
        return ret

    run_job_guarded.__wrapped__ = run_job  # type: ignore[attr-defined]
    return run_job_guarded


def _guarded_ours(run_job: Any) -> Any:
    """The same for :func:`flows.run_job.run_job` (``hydra_context`` comes first)."""

    def run_job_guarded(hydra_context: Any, task_function: Any, config: Any) -> Any:
        inner = _guarded(lambda task, cfg: run_job(hydra_context, task, cfg))
        return inner(task_function, config)

    run_job_guarded.__wrapped__ = run_job  # type: ignore[attr-defined]
    return run_job_guarded


def guard_jobs() -> None:
    """Wrap ``run_job`` where the launchers call it (once): Hydra's (the basic launcher,
    a single run) and the twostep launcher's (:mod:`flows.launcher`; its workers are
    forked from this process, wrapped already)."""
    import hydra._internal.core_plugins.basic_launcher as basic
    import hydra._internal.hydra as hydra_main
    import hydra.core.utils as utils

    for module in (utils, basic, hydra_main):
        current = getattr(module, "run_job", None)
        if current is not None and not hasattr(current, "__wrapped__"):
            module.run_job = _guarded(current)  # type: ignore[attr-defined]
    import flows.launcher as launcher

    current = getattr(launcher, "run_job", None)
    if current is not None and not hasattr(current, "__wrapped__"):
        launcher.run_job = _guarded_ours(current)  # type: ignore[attr-defined]
