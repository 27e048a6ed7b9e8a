"""Fast Downward's programs as children that cannot outlive or outgrow the job.

Every run of the translator (grounding, :mod:`twostep.pddl.translator`) and of the
planner's driver (:mod:`twostep.planner.driver`) goes through :func:`run_guarded`: the
program runs under a small guard process (``twostep/programs/_guard.py``) that

- limits its address space (the memory limit) and its CPU time (the time limit);
- ends its whole process group and removes its temporary folder when twostep is gone:
  a ``kill -9`` of the job (the kernel tells the guard: ``PR_SET_PDEATHSIG``), a SIGTERM
  or a Ctrl-C (twostep stops the guard on its way out);
- is stopped, with the program, by a wall-clock guard for a machine too loaded to give
  the program its CPU time.

The limits (:class:`Limit`) and the parameters that set them:

- memory (default :data:`DEFAULT_MEMORY_LIMIT_MB`): each of Fast Downward's processes,
  the translator that grounds the task (``GroundingLimits.memory_mb``) and the planner's
  own translator and search (``PlannerSettings.memory_limit_mb``);
- grounding time (``GroundingLimits.time_s``): CPU seconds of the translator that grounds
  the task.

A limit that ends a run is a :class:`LimitReached`: which limit, its value, what was
needed when known, and a message naming the parameter that raises it. The message names
the library's own parameter; a caller with settings of its own names them instead
(:meth:`LimitReached.message`). A grounding that reaches a limit raises it as a
:class:`ResourceLimitError`; a planner call returns it on its result.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

DEFAULT_MEMORY_LIMIT_MB = 4096
"""The memory limit of each Fast Downward process when none is set (4 GiB)."""
MIN_MEMORY_LIMIT_MB = 64
"""The smallest memory limit that can be set: Python and the translator start in 32 MB."""
PARAMETER = "{parameter}"
"""Where a :class:`LimitReached`'s words name the parameter that raises the limit."""
_GUARD = Path(__file__).with_name("_guard.py")
_STOP_WAIT_S = 10.0  # how long the guard may take to end its program and clean up


class Limit(Enum):
    """Which resource limit a run reached."""

    MEMORY = "memory"  # MB of address space of a Fast Downward process
    GROUNDING_TIME = "grounding_time"  # CPU seconds of the translator that grounds a task


@dataclass(frozen=True)
class LimitReached:
    """A run that a resource limit ended: which :attr:`limit`, its :attr:`value` (MB or
    CPU seconds), what was :attr:`needed` when known (MB), and the :attr:`words` that say
    so, with :data:`PARAMETER` where the setting that raises it is named (by default
    :attr:`parameter`, the library's own, e.g. ``GroundingLimits.memory_mb``)."""

    limit: Limit
    value: float
    needed: float | None
    words: str
    parameter: str

    def message(self, parameter: str | None = None) -> str:
        """The words, naming ``parameter`` (None: the library's :attr:`parameter`)."""
        return self.words.replace(PARAMETER, parameter or self.parameter)

    def where(self, prefix: str) -> LimitReached:
        """The same limit, its message after ``prefix`` (e.g. the task's files)."""
        return LimitReached(
            self.limit, self.value, self.needed, f"{prefix}{self.words}", self.parameter
        )


class ResourceLimitError(Exception):
    """A grounding that a resource limit ended (:attr:`reached`: which limit, its value,
    what was needed); its message names the library's parameter that raises the limit.
    A job fails with status ``resource_limit``."""

    def __init__(self, reached: LimitReached) -> None:
        super().__init__(reached.message())
        self.reached = reached

    def __reduce__(self) -> tuple[type[ResourceLimitError], tuple[LimitReached]]:
        return type(self), (self.reached,)  # pickled whole (a Dask worker's error)


@dataclass(frozen=True)
class Finished:
    """How a guarded run ended: its exit code (a negative code: the signal that ended
    it; None: the wall-clock guard stopped it), everything it printed, its wall time."""

    code: int | None
    output: str
    wall_s: float


def memory_limit_mb(value: int | None) -> int:
    """The memory limit in MB a setting stands for (None: :data:`DEFAULT_MEMORY_LIMIT_MB`)."""
    return DEFAULT_MEMORY_LIMIT_MB if value is None else int(value)


def run_guarded(
    command: Sequence[str],
    cwd: Path,
    wall_s: float,
    env: Mapping[str, str] | None = None,
    memory_mb: int | None = None,
    cpu_s: float | None = None,
    temporary: bool = True,
) -> Finished:
    """Run ``command`` in ``cwd`` under the guard of the module docstring: ``memory_mb``
    (address space) and ``cpu_s`` (CPU time) limit it (None: no limit), ``wall_s`` stops
    it; with ``temporary``, ``cwd`` is the run's own temporary folder, which the guard
    removes should twostep die first."""
    guard = [
        sys.executable,
        "-I",
        "-S",
        str(_GUARD),
        str(os.getpid()),
        str(cwd) if temporary else "",
        str(0 if memory_mb is None else int(memory_mb) * 2**20),
        str(0 if cpu_s is None else max(1, round(cpu_s))),
        "--",
        *command,
    ]
    start = time.perf_counter()
    process = subprocess.Popen(
        guard,
        cwd=cwd,
        env=None if env is None else dict(env),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        errors="replace",
        start_new_session=True,  # the terminal's Ctrl-C reaches twostep, which stops it
    )
    try:
        output, _ = process.communicate(timeout=wall_s)
        code: int | None = process.returncode
    except subprocess.TimeoutExpired:
        _stop(process)
        output, code = _rest(process), None
    except BaseException:  # Ctrl-C, SIGTERM turned into an exception, an error: no orphan
        _stop(process)
        raise
    if code is not None and code > 128:
        code = 128 - code  # the guard's 128 + N: the program ended by signal N
    return Finished(code, output, time.perf_counter() - start)


def _stop(process: subprocess.Popen[str]) -> None:
    """Stop the guard (it ends its program's group and removes the folder); kill it if it
    does not end in time."""
    with contextlib.suppress(OSError):
        process.send_signal(signal.SIGTERM)
    try:
        process.wait(timeout=_STOP_WAIT_S)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(OSError):
            os.killpg(process.pid, signal.SIGKILL)
        process.wait()


def _rest(process: subprocess.Popen[str]) -> str:
    """What a stopped guard's program printed."""
    try:
        output, _ = process.communicate(timeout=_STOP_WAIT_S)
    except (subprocess.TimeoutExpired, ValueError):
        return ""
    return output or ""
