"""The default launcher of a sweep: every core, one Python process per core for the
whole sweep, job configs composed once per set of group choices.

``hydra/launcher=twostep`` (``conf/hydra/launcher/twostep.yaml``, the default):

* ``n_jobs``: worker processes (null: every core this process may use; 1: the jobs run
  one after the other in the launching process, as Hydra's basic launcher runs them).
* ``backend``: ``processes`` (worker processes on this machine, started once for the
  sweep: each imports the library, Prefect and MLflow once, not once per job) or ``dask``
  (each job is a task on a Dask cluster: ``dask_address`` of a running scheduler, or a
  ``LocalCluster`` of ``n_jobs`` worker processes started for the sweep). A Dask worker
  needs this environment and the output root on a shared file system.

Every job still runs through Hydra's ``run_job`` (its directory, its saved config, the
job callbacks) and the ``twostep`` app; only where it runs and how its config is composed
change (:class:`flows.compose.SweepComposer`). Jobs are handed out one at a time, in
order, to whichever worker is free. A worker dies with the launching process (``kill -9``
of the sweep stops its jobs, as it stops a job of the basic launcher); a re-run resumes
from the job store.
"""

from __future__ import annotations

import contextlib
import copy
import importlib
import logging
import os
import pickle
import sys
import threading
import time
from collections.abc import Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from hydra.core.singleton import Singleton
from hydra.core.utils import JobReturn, JobStatus, configure_log, setup_globals
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, open_dict

from flows.compose import SweepComposer
from flows.faults import adopt_faults
from flows.run_job import run_job

log = logging.getLogger(__name__)


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity), at least 1."""
    with contextlib.suppress(AttributeError, OSError):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def worker_count(n_jobs: int | None, jobs: int | None = None) -> int:
    """Worker processes for ``n_jobs`` (None or 0: every core; -k: all but k-1, as in
    joblib), never more than the jobs there are."""
    cores = available_cores()
    if n_jobs is None or n_jobs == 0:
        count = cores
    elif n_jobs < 0:
        count = max(1, cores + 1 + n_jobs)
    else:
        count = n_jobs
    return max(1, min(count, jobs)) if jobs else max(1, count)


@dataclass
class LaunchContext:
    """What every worker needs, sent once per worker (not once per job)."""

    hydra_context: HydraContext
    config: DictConfig  # the sweep's master config
    task_function: Any  # the function, or (module, name) of the Hydra-decorated app
    singleton_state: dict[str, Any]
    composer: SweepComposer
    argv: list[str]
    # The sweep's first job will be computed: workers import what jobs use before their
    # first job (meanwhile the server starts), so that no job's time holds the imports.
    warm_first: bool = False


# ----------------------------------------------------------------- what a job reports


@dataclass
class JobLaunch:
    """How the launcher ran the current job (read by the app for its sweep record)."""

    worker: int  # the worker's PID
    worker_index: int  # the n-th job this worker ran (0: its first)
    compose_s: float  # composing the job's config
    launched_at: float  # time.time() when the worker took the job
    cpu_at_launch: float  # time.process_time() then (this process, all its threads)


_CURRENT: JobLaunch | None = None


def current_launch() -> JobLaunch | None:
    """The job being launched in this process by the twostep launcher (None: another
    launcher, or a single run)."""
    return _CURRENT


def launch_fields() -> dict[str, Any]:
    """How the current job was launched, for its sweep record: the process that ran it
    and, with the twostep launcher, which of its jobs this was, when it took the job, how
    long composing the job's config took and the CPU time this process spent on the job
    so far (not its planner's, which runs in a process of its own)."""
    fields: dict[str, Any] = {"worker": os.getpid()}
    if _CURRENT is not None:
        fields.update(
            worker_job=_CURRENT.worker_index,
            launched_at=_CURRENT.launched_at,
            compose_s=_CURRENT.compose_s,
            cpu_s=time.process_time() - _CURRENT.cpu_at_launch,
        )
    return fields


# ----------------------------------------------------------------- in a worker

_WORKER: LaunchContext | None = None
_WORKER_JOBS = 0


def _task_reference(function: TaskFunction) -> Any:
    """The task function as (module, name) when the module holds it under Hydra's
    decorator (the worker imports it), else the function itself (pickled by value)."""
    module, name = getattr(function, "__module__", None), getattr(function, "__qualname__", "")
    holder = getattr(sys.modules.get(module or ""), name, None)
    if holder is not None and getattr(holder, "__wrapped__", None) is function:
        return (module, name)
    return function


def _task_function(reference: Any) -> TaskFunction:
    if isinstance(reference, tuple):
        import importlib

        module, name = reference
        function: TaskFunction = getattr(importlib.import_module(module), name).__wrapped__
        return function
    return reference  # type: ignore[no-any-return]


def _die_with_parent() -> None:
    """Linux: this process gets SIGTERM when the launching process dies (even kill -9)."""
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL("libc.so.6", use_errno=True)
            libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
            if os.getppid() == 1:  # the parent died before prctl
                os._exit(1)


def _at_exit() -> None:
    """A worker's end: what its jobs queued for the Prefect server (logs, events) is sent
    before the server stops (a forked worker ends without running ``atexit``)."""
    if "flows.prefect_flow" in sys.modules:
        from flows.prefect_flow import flush_to_server

        flush_to_server()


def init_forked_worker() -> None:
    """A forked worker's start: it holds the launching process's state already."""
    import multiprocessing.util

    _die_with_parent()
    multiprocessing.util.Finalize(None, _at_exit, exitpriority=10)


def init_worker(payload: bytes) -> None:
    """A worker's start: the sweep's Hydra state, once; what its jobs will import is
    imported meanwhile (:func:`warm_up`)."""
    global _WORKER
    import multiprocessing.util

    _die_with_parent()
    multiprocessing.util.Finalize(None, _at_exit, exitpriority=10)
    context: LaunchContext = pickle.loads(payload)
    sys.argv = list(context.argv)  # what the runs record as their source
    setup_globals()
    Singleton.set_state(context.singleton_state)
    context.task_function = _task_function(context.task_function)
    configure_log(context.config.hydra.hydra_logging, context.config.hydra.verbose)
    _WORKER = context
    if context.warm_first:
        warm_up(context.config)
    else:  # maybe nothing to compute: the first job does not wait for it
        threading.Thread(target=warm_up, args=(context.config,), daemon=True).start()


def warm_up(config: DictConfig) -> None:
    """Import what the sweep's jobs use (the library; Prefect's flow and MLflow's client
    when the sweep uses them), in a thread beside the worker's first job: the first job
    waits for a module only if it needs it before the import is done (Python's import
    lock), and a sweep whose jobs are all reused pays no wait for it."""
    from flows.sweep_state import SweepState

    state = SweepState.load(Path(str(config.hydra.sweep.dir)))
    modules = ["flows.job", "twostep.methods.twostep"]
    if state is not None and (state.server or state.prefect_api_url):
        # with the engines a flow run imports at its first run
        modules += ["flows.prefect_flow", "prefect.flow_engine", "prefect.task_engine"]
    if state is not None and state.tracking_uri:
        modules += ["mlflow.tracking", "mlflow.store.tracking.sqlalchemy_store"]
    for module in modules:
        with contextlib.suppress(Exception):
            importlib.import_module(module)


def start_server_early(context: LaunchContext, first: tuple[int, list[str]]) -> bool:
    """Whether the sweep's first job will be computed; if so, start the sweep's Prefect
    server now (when it starts one), while the workers start. A sweep whose first job is
    in the job store starts none here: its first job that needs it does."""
    from flows.sweep_state import SweepState

    state = SweepState.load(Path(str(context.config.hydra.sweep.dir)))
    if state is None:
        return False
    from hydra.core.hydra_config import HydraConfig

    from flows.servers import sweep_server
    from flows.store import stored

    index, overrides = first
    config = context.composer.compose(context.config, overrides)
    with open_dict(config):
        config.hydra.job.id = index
        config.hydra.job.num = index
    hydra = HydraConfig.instance()
    previous = hydra.cfg
    hydra.set_config(config)  # for ${hydra:...} in the job's paths
    try:
        task_cfg = copy.deepcopy(config)
        with open_dict(task_cfg):
            del task_cfg["hydra"]
        needed = not stored(task_cfg)
    except Exception:  # the job will say what is wrong with it
        needed = False
    finally:
        hydra.cfg = previous
    if needed and state.server is not None:
        with contextlib.suppress(Exception):  # the first job then tries and reports
            sweep_server(state)
    return needed


def run_in_worker(index: int, overrides: Sequence[str]) -> JobReturn:
    """One job in this worker process (:func:`init_worker` ran first)."""
    assert _WORKER is not None, "worker not initialised"
    result = _run_one(_WORKER, index, overrides)
    return _portable(result)


def _run_one(context: LaunchContext, index: int, overrides: Sequence[str]) -> JobReturn:
    folder = os.environ.get(PROFILE_ENV)
    if not folder:
        return _run_job(context, index, overrides)
    import cProfile

    profile = _PROFILES.setdefault(os.getpid(), cProfile.Profile())
    try:
        result: JobReturn = profile.runcall(_run_job, context, index, overrides)
        return result
    finally:  # the whole process's jobs so far, one file per process
        profile.dump_stats(str(Path(folder) / f"jobs-{os.getpid()}.prof"))


PROFILE_ENV = "TWOSTEP_PROFILE_DIR"  # bench/bench_sweep.py --profile: cProfile every job
_PROFILES: dict[int, Any] = {}


def _run_job(context: LaunchContext, index: int, overrides: Sequence[str]) -> JobReturn:
    global _CURRENT, _WORKER_JOBS
    launched_at, cpu = time.time(), time.process_time()
    start = time.perf_counter()
    config = context.composer.compose(context.config, list(overrides))
    with open_dict(config):
        config.hydra.job.id = index
        config.hydra.job.num = index
    compose_s = time.perf_counter() - start
    _CURRENT = JobLaunch(os.getpid(), _WORKER_JOBS, compose_s, launched_at, cpu)
    _WORKER_JOBS += 1
    try:
        return run_job(context.hydra_context, context.task_function, config)
    finally:
        _CURRENT = None


def _portable(result: JobReturn) -> JobReturn:
    """What the launching process needs of a job's return (its configs stay here), with
    an error that cannot be pickled replaced by its text."""
    value = result._return_value
    if isinstance(value, BaseException):
        try:
            pickle.dumps(value)
        except Exception:
            value = RuntimeError(f"{type(value).__name__}: {value}")
    return JobReturn(
        overrides=result.overrides,
        working_dir=result.working_dir,
        task_name=result.task_name,
        status=result.status,
        _return_value=value,
    )


# ----------------------------------------------------------------- the launching side


def _payload(context: LaunchContext) -> bytes:
    import cloudpickle

    return bytes(cloudpickle.dumps(context))


def _failed(overrides: Sequence[str], error: BaseException) -> JobReturn:
    return JobReturn(overrides=list(overrides), status=JobStatus.FAILED, _return_value=error)


def launch(
    hydra_context: HydraContext,
    task_function: TaskFunction,
    config: DictConfig,
    composer: SweepComposer,
    job_overrides: Sequence[Sequence[str]],
    initial_job_idx: int,
    n_jobs: int | None = None,
    backend: str = "processes",
    dask_address: str | None = None,
) -> list[JobReturn]:
    """Run the batch ``job_overrides`` (indices from ``initial_job_idx``); see the module
    docstring. Returns the jobs' returns in batch order."""
    setup_globals()
    configure_log(config.hydra.hydra_logging, config.hydra.verbose)
    Path(str(config.hydra.sweep.dir)).mkdir(parents=True, exist_ok=True)
    context = LaunchContext(
        hydra_context=hydra_context,
        config=config,
        task_function=task_function,
        singleton_state=Singleton.get_state(),
        composer=composer,
        argv=list(sys.argv),
    )
    jobs = [(initial_job_idx + i, list(o)) for i, o in enumerate(job_overrides)]
    returns = _launch(context, jobs, n_jobs, backend, dask_address)
    adopt_faults(returns)  # records a worker could not write (a full disk): kept here
    return returns


def _launch(
    context: LaunchContext,
    jobs: list[tuple[int, list[str]]],
    n_jobs: int | None,
    backend: str,
    dask_address: str | None,
) -> list[JobReturn]:
    config = context.config
    if backend == "dask":
        return _launch_dask(context, jobs, n_jobs, dask_address)
    workers = worker_count(n_jobs, len(jobs))
    if workers == 1:
        log.info(f"Launching {len(jobs)} jobs in this process")
        returns = []
        for index, overrides in jobs:
            returns.append(_run_one(context, index, overrides))
            configure_log(config.hydra.hydra_logging, config.hydra.verbose)
        return returns
    log.info(f"Launching {len(jobs)} jobs on {workers} worker processes")
    context.warm_first = start_server_early(context, jobs[0])
    pool = _pool(context, workers)
    futures: list[Future[JobReturn]] = []
    try:
        futures = [pool.submit(run_in_worker, index, overrides) for index, overrides in jobs]
        return [
            _result(future, overrides)
            for future, (_, overrides) in zip(futures, jobs, strict=False)
        ]
    except BaseException:  # Ctrl-C: no new job starts; the running ones were interrupted too
        for future in futures:
            future.cancel()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    finally:
        pool.shutdown(wait=True)


def _pool(context: LaunchContext, workers: int) -> ProcessPoolExecutor:
    """The worker processes: forked from this one where that is safe (Linux, no other
    thread here), so that they start with what this process imported and composed (with
    the sweep's first job to compute, it imports what the jobs use first: once for all
    workers, while the server starts); otherwise started fresh (``spawn``), each given the
    sweep's Hydra state and importing what it needs."""
    global _WORKER
    if context.warm_first:
        warm_up(context.config)
    if sys.platform.startswith("linux") and threading.active_count() == 1:
        _WORKER = context  # the forked workers' copy of this process holds it
        return ProcessPoolExecutor(
            max_workers=workers, mp_context=get_context("fork"), initializer=init_forked_worker
        )
    context.task_function = _task_reference(context.task_function)
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=get_context("spawn"),
        initializer=init_worker,
        initargs=(_payload(context),),
    )


def _result(future: Future[JobReturn], overrides: Sequence[str]) -> JobReturn:
    try:
        return future.result()
    except Exception as error:  # the worker died (killed, out of memory): a failed job
        return _failed(overrides, error)


# ----------------------------------------------------------------- Dask

_DASK_CONTEXTS: dict[str, LaunchContext] = {}


def prepare_dask_worker(payload: bytes, digest: str) -> None:
    """A Dask worker's start for this sweep: its Hydra state, and (the sweep's first job to
    compute) what the jobs use imported, before any job."""
    global _WORKER
    context = _DASK_CONTEXTS.get(digest)
    if context is None:
        context = pickle.loads(payload)
        sys.argv = list(context.argv)
        setup_globals()
        Singleton.set_state(context.singleton_state)
        context.task_function = _task_function(context.task_function)
        configure_log(context.config.hydra.hydra_logging, context.config.hydra.verbose)
        _DASK_CONTEXTS[digest] = context
        if context.warm_first:
            warm_up(context.config)
    _WORKER = context


def run_on_dask_worker(payload: bytes, digest: str, index: int, overrides: list[str]) -> JobReturn:
    """One job on a Dask worker (prepared once per worker: :func:`prepare_dask_worker`)."""
    prepare_dask_worker(payload, digest)
    assert _WORKER is not None
    return _portable(_run_one(_WORKER, index, overrides))


def _launch_dask(
    context: LaunchContext,
    jobs: list[tuple[int, list[str]]],
    n_jobs: int | None,
    address: str | None,
) -> list[JobReturn]:
    import hashlib

    from distributed import Client, LocalCluster

    context.warm_first = start_server_early(context, jobs[0])
    context.task_function = _task_reference(context.task_function)
    payload = _payload(context)
    digest = hashlib.sha256(payload).hexdigest()
    # Dask's own lines (workers started and stopped, comms closing) would go to the
    # console with Hydra's prefix: only its errors do.
    logging.getLogger("distributed").setLevel(logging.ERROR)
    cluster = None
    if address:
        client = Client(address)  # type: ignore[no-untyped-call]
        where = address
    else:
        workers = worker_count(n_jobs)
        cluster = LocalCluster(  # type: ignore[no-untyped-call]
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
        )
        client = Client(cluster)  # type: ignore[no-untyped-call]
        where = f"a local Dask cluster of {workers} worker processes"
    log.info(f"Launching {len(jobs)} jobs on {where}")
    try:
        shared = client.scatter(payload, broadcast=True)  # type: ignore[no-untyped-call]
        # Every worker set up (and importing what jobs use) at once, while the server starts.
        client.run(prepare_dask_worker, payload, digest)  # type: ignore[no-untyped-call]
        futures = [
            client.submit(
                run_on_dask_worker, shared, digest, index, overrides, pure=False, key=f"job-{index}"
            )
            for index, overrides in jobs
        ]
        returns = []
        for future, (_, overrides) in zip(futures, jobs, strict=False):
            try:
                returns.append(future.result())
            except Exception as error:
                returns.append(_failed(overrides, error))
        return returns
    finally:
        client.close()  # type: ignore[no-untyped-call]
        if cluster is not None:
            cluster.close()  # type: ignore[no-untyped-call]


def register_plugins() -> None:
    """Make the twostep launcher and sweeper known to Hydra: its plugin scan finds them
    in an installed wheel, not in an editable install (its ``hydra_plugins`` path is a
    placeholder that the scan does not walk)."""
    from hydra.core.plugins import Plugins

    # The scan first: it executes Hydra's own plugin modules again, which redefines the
    # basic sweeper our sweeper derives from.
    plugins = Plugins.instance()
    from hydra_plugins.twostep_launcher.twostep_launcher import TwostepLauncher, TwostepSweeper

    for plugin in (TwostepLauncher, TwostepSweeper):
        plugins.register(plugin)
