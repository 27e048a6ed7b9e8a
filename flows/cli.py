"""The ``twostep`` command: a Hydra app that runs one job, or a sweep with ``-m``.

Before Hydra runs, the command line's keys and options are checked against the schema and
the configs (:func:`flows.config.override_problem`): a typo'd key, with or without ``+``,
or an unknown option is one line (``unknown key 'agnets': did you mean 'agents'?``) and
exit 2. Values are checked by the Hydra callback before any folder exists
(:mod:`flows.checks`).
Single run: prints a one-line summary (and the joint schedule), writes result.json in
the Hydra run directory; bad input (a command line Hydra cannot compose, a value out of
range, an unknown task, malformed PDDL) or an unusable MLflow store prints one line and
exits 2, a job that crashed prints one line and exits 1. ``--version`` and ``--help``
print the tool's own text.
Sweep: one progress line per finished job; failures are recorded and the sweep goes on
(:mod:`flows.sweep_callback` prints the summary and sets the exit code).
"""

from __future__ import annotations

import logging
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig

from flows.artifacts import picture_paths
from flows.config import agents_run, override_problem, register
from flows.console import format_schedule, format_summary
from flows.environment import quiet_defaults
from flows.faults import FAULTED, guard_jobs, quiet_store_errors
from flows.launcher import launch_fields, register_plugins
from flows.replay_sweeper import expose_plugin
from flows.sweep_callback import SweepCallback
from twostep.cli import ReaderGoneSafe, console_main
from twostep.util.outcome import JobStatus

if TYPE_CHECKING:
    from flows.job import JobOutcome

# The configs are installed with the package (conf/ of the source tree, see pyproject.toml):
# the command finds them from any directory; --config-dir adds a folder of the user's own.
CONFIG_PACKAGE = "pkg://flows.conf"
JOB_LOG = "twostep.run"  # the job log's own logger (the summary, not the console)

quiet_defaults()
register()
expose_plugin()  # experiment=paper_replay's sweeper (hydra/sweeper=bundle), before the scan
register_plugins()  # the default launcher and sweeper of a sweep (flows/launcher.py)

# Set by a single run once its job is recorded: the process may then end without
# tearing down every imported module (about a second for MLflow + unified-planning).
_SINGLE_RUN_DONE = False


@hydra.main(config_path=CONFIG_PACKAGE, config_name="config", version_base="1.3")
def app(cfg: DictConfig) -> None:
    from flows.job import execute_job
    from flows.sweep_state import SweepState, record_job
    from flows.tracking.runs import TrackingError

    hydra_cfg = HydraConfig.get()
    job_dir = Path(hydra_cfg.runtime.output_dir)
    multirun = hydra_cfg.mode == RunMode.MULTIRUN
    sweep = SweepState.load(Path(hydra_cfg.sweep.dir)) if multirun else None
    try:
        outcome = execute_job(cfg, job_dir, sweep, tracking_worker=not multirun)
    except TrackingError as error:
        print(f"error: {error}", file=sys.stderr, flush=True)
        if not multirun:
            sys.exit(2)
        record = {"num": hydra_cfg.job.num, "name": job_dir.name, "status": JobStatus.FAILED.value,
                  "error": str(error)}  # fmt: skip
        record_job(Path(hydra_cfg.sweep.dir), hydra_cfg.job.num, record)
        return
    global _SINGLE_RUN_DONE
    _SINGLE_RUN_DONE = not multirun
    line = format_summary(outcome.result, outcome.name)
    if outcome.reused:
        line += " | reused (job store)"
    elif outcome.stats.plan_cache_hits:
        hits, runs = outcome.stats.plan_cache_hits, outcome.stats.plan_calls
        line += f" | planner cache: {hits} hit(s), {runs} run"
    _job_log(outcome, line, job_dir)
    if not multirun:
        _finish_single_run(outcome, line, job_dir)
        return
    record_job(Path(hydra_cfg.sweep.dir), hydra_cfg.job.num, _sweep_record(outcome))
    if cfg.orchestration.progress and sweep is not None:
        from flows.console import progress_line

        line = f"{progress_line(sweep)} {line}"
    print(line, flush=True)


def _job_log(outcome: JobOutcome, line: str, job_dir: Path) -> None:
    """The job's summary, schedule and files in its job log (``<job dir>/cli.log``, the
    ``twostep.run`` logger of conf/hydra/job_logging/twostep.yaml)."""
    lines = [f"error: {outcome.error}"] if "error" in outcome.result else [line]
    table = format_schedule(outcome.result)
    if table:
        lines.append(table)
    lines.append(f"result: {job_dir / 'result.json'}")
    logging.getLogger(JOB_LOG).info("\n".join(lines))


def _finish_single_run(outcome: JobOutcome, line: str, job_dir: Path) -> None:
    """Print what a single run did; exit 2 for bad input, 1 for a crash or no plan."""
    if "error" in outcome.result:  # the job raised: one line, no traceback
        print(f"error: {outcome.error}", file=sys.stderr, flush=True)
        sys.exit(2 if outcome.input_error else 1)
    print(line)
    table = format_schedule(outcome.result)
    if table:
        print(table)
    print(f"result: {job_dir / 'result.json'}")
    for label, path in picture_paths(job_dir):
        print(f"{label}: {path}")
    if outcome.status != JobStatus.SUCCESS:  # no plan (unsolvable, timeout): scripts see it
        sys.exit(1)


def _sweep_record(outcome: JobOutcome) -> dict[str, Any]:
    """The job's record in its sweep (``.twostep/jobs/<num>.json``): what it ran (the N
    it ran: 1 for SA), how it ended, its results and timings."""
    result = outcome.result
    method = result.get("method")
    return {
        "num": HydraConfig.get().job.num,
        "name": outcome.name,
        "domain": result.get("domain"),
        "task": result.get("task"),
        "method": method,
        "decomposer": result.get("decomposer") if method == "twostep" else None,
        "agents": agents_run(str(method), result.get("agents")),
        "seed": result.get("seed"),
        "success": result.get("success") is True,
        "exec_length": result.get("exec_length"),
        "planning_time_s": result.get("planning_time_s"),
        "job_key": outcome.key,
        "status": outcome.status,
        "error": outcome.error,
        "reused": outcome.reused,
        "finished_at": time.time(),
        "mlflow_run_id": outcome.mlflow_run_id,
        "tracking_error": outcome.tracking_error,
        "store_refused": outcome.refused_entries,  # stored entries not used: not this job's
        "not_stored": outcome.not_stored,  # why the job store could not keep it
        **outcome.stats.to_dict(),
        **outcome.timings,
        "phases": outcome.phases,  # where the job's time went (bench/bench_sweep.py)
        "launch": launch_fields(),
    }


@console_main
def main() -> None:
    if "--version" in sys.argv[1:]:  # ours, not Hydra's
        from flows.console import version_text

        print(version_text())
        return
    # A closed stdout (`twostep ... | head -1`) never turns recorded jobs into a traceback.
    sys.stdout = ReaderGoneSafe(sys.stdout)  # type: ignore[assignment]
    quiet_store_errors()  # a full disk: one line per job, not MLflow's tracebacks
    guard_jobs()  # ... and a run directory that cannot be written is one failed job
    problem = override_problem(sys.argv[1:])  # a typo'd key never runs
    if problem is not None:
        print(f"error: {problem}", file=sys.stderr, flush=True)
        code: Any = 2
    else:
        try:  # flows.command (the console script) has started the MLflow logging process
            app()
        except SystemExit as stop:
            code = stop.code
        else:
            code = 0
    if "flows.tracking.worker" in sys.modules:
        from flows.tracking.worker import TrackingWorker

        TrackingWorker.discard_prestarted()  # no job took it (bad input, MLflow off, ...)
    if code == 1 and not SweepCallback.composed:
        code = 2  # Hydra refused the command line (its message is printed): bad input
    if code == 0 and FAULTED:
        code = 1  # a single run whose run directory could not be written (its line says)
    if _SINGLE_RUN_DONE:
        _fast_exit(code if isinstance(code, int) else 1)
    sys.exit(code)


def _fast_exit(code: int) -> None:
    """End a finished single run: flush what is still buffered, skip module teardown.

    Everything the run writes is on disk already (result.json, the job store, the MLflow
    run); log handlers are flushed, and Prefect's queued logs and events are sent.
    """
    import logging
    import os

    if "flows.prefect_flow" in sys.modules:
        from flows.prefect_flow import flush_to_server

        flush_to_server()
    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    main()
