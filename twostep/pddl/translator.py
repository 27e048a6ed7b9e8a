"""Grounding a task with Fast Downward's own translator, run as a program.

One semantics with the planner: what twostep plans, progresses and scores is the task
Fast Downward grounds from the same files, so the grounding is the planner's own. The
translator ships with the up-fast-downward wheel (:mod:`twostep.programs.downward`); it is GPL-3
like the planner, so it runs at arm's length, as a subprocess writing ``output.sas``,
which :mod:`twostep.pddl.sas` reads (0.1-0.6 s per IPC task here, start-up included).

Options, and why:

- ``--full-encoding``: every value is named after its atom (the facts of the model);
- ``--keep-unimportant-variables``: keep facts that do not lead to the goal (a helper's
  subgoal or a hand-off state may need them);
- ``--keep-no-ops``: keep actions without effects (a plan may name them);
- ``--invariant-generation-max-candidates 0``: no mutex invariants, so every variable is
  one atom, true or false, and every delete effect a single fact, exactly as in PDDL
  (multi-valued variables would only say "the variable's atom that held", which states
  assembled from two agents' facts need not respect);
- ``--skip-variable-reordering``: the order of variables does not matter here.

A goal that is not reachable even when deletes are ignored makes the translator write an
empty, unsolvable task; the grounding is then redone with an empty goal, so that the
actions are still there (a hand-off problem or a subgoal may well be solvable).

Grounding is bounded (:class:`GroundingLimits`): the translator runs under the guard of
:mod:`twostep.programs.processes` with a memory limit (``GroundingLimits.memory_mb``, default
4 GiB) and a CPU-time limit (``GroundingLimits.time_s``, default the planner's time limit),
and never outlives the job; a limit it hits is a
:class:`~twostep.programs.processes.ResourceLimitError` saying which limit, its value and
the parameter that raises it. The limits are set per job (:func:`grounding_limits`) and
read by every grounding in the process.
"""

from __future__ import annotations

import contextlib
import functools
import os
import signal
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from twostep.pddl.errors import PDDLError
from twostep.programs.downward import translator_path
from twostep.programs.processes import (
    PARAMETER,
    Limit,
    LimitReached,
    ResourceLimitError,
    memory_limit_mb,
    run_guarded,
)

TRANSLATOR_OPTIONS = (
    "--full-encoding",
    "--keep-unimportant-variables",
    "--keep-no-ops",
    "--invariant-generation-max-candidates",
    "0",
    "--skip-variable-reordering",
)
DEFAULT_GROUNDING_TIME_S = 60.0
"""The translator's CPU-time limit when none is set: the planner's default time limit."""
WALL_FACTOR, WALL_OFFSET_S = 4.0, 60.0
"""The wall-clock guard of a grounding: its CPU limit x 4 + 60 s (a loaded machine)."""
TRANSLATE_OUT_OF_MEMORY, TRANSLATE_OUT_OF_TIME = 20, 21  # the translator's own exit codes
MODEL_BYTES_PER_SAS_BYTE = 24
"""What the grounded model (:mod:`twostep.pddl.sas`) takes in memory per byte of the
``output.sas`` it is read from: 22 measured (59,049 ground actions: 10.6 MB of SAS, 238 MB
in the model), about what the translator itself needed."""
_UNREACHABLE_GOAL = "No relaxed solution"


@dataclass(frozen=True)
class GroundingLimits:
    """What one grounding may use: ``memory_mb`` of address space (None:
    :data:`~twostep.programs.processes.DEFAULT_MEMORY_LIMIT_MB`) and ``time_s`` of CPU time."""

    memory_mb: int | None = None
    time_s: float = DEFAULT_GROUNDING_TIME_S

    @property
    def wall_s(self) -> float:
        return self.time_s * WALL_FACTOR + WALL_OFFSET_S


_limits = GroundingLimits()


def current_limits() -> GroundingLimits:
    """The limits every grounding in this process runs under now."""
    return _limits


@contextlib.contextmanager
def grounding_limits(limits: GroundingLimits | None) -> Iterator[GroundingLimits]:
    """Ground under ``limits`` while the block runs (None: leave them as they are)."""
    global _limits
    before = _limits
    _limits = limits or before
    try:
        yield _limits
    finally:
        _limits = before


@dataclass(frozen=True)
class Translation:
    """The translator's output for one domain and problem."""

    sas: str
    """The text of ``output.sas``."""
    goal_unreachable: bool
    """Whether the translator found the goal unreachable (the task it wrote is empty)."""


@functools.lru_cache(maxsize=32)
def translate(domain_text: str, problem_text: str) -> Translation:
    """Run the translator on a domain and a problem given as text.

    Raises :class:`PDDLError` with the translator's own last words when it rejects the
    input (tasks are checked by the lifted reader first, which names file and line).
    """
    limits = _limits
    with tempfile.TemporaryDirectory(prefix="twostep-translate-") as tmp:
        folder = Path(tmp)
        (folder / "domain.pddl").write_text(domain_text)
        (folder / "problem.pddl").write_text(problem_text)
        env = dict(os.environ, PYTHONPATH=str(translator_path()))
        command = [
            sys.executable,
            "-m",
            "fast_downward.translate",
            "domain.pddl",
            "problem.pddl",
            "--sas-file",
            "output.sas",
            *TRANSLATOR_OPTIONS,
        ]
        done = run_guarded(
            command,
            folder,
            limits.wall_s,
            env=env,
            memory_mb=memory_limit_mb(limits.memory_mb),
            cpu_s=limits.time_s,
        )
        limit = _limit_hit(done.code, done.output, limits, done.wall_s)
        if limit is not None:
            raise limit
        sas = folder / "output.sas"
        if done.code == 0 and sas.is_file():
            _check_model_size(sas.stat().st_size, limits)
        if done.code != 0 or not sas.is_file():
            tail = [line.strip() for line in done.output.splitlines() if line.strip()][-2:]
            raise PDDLError(
                "Fast Downward's translator rejects the task"
                f" (exit {done.code}): {' | '.join(tail) or 'no output'}"
            )
        return Translation(sas.read_text(), _UNREACHABLE_GOAL in done.output)


def _check_model_size(sas_bytes: int, limits: GroundingLimits) -> None:
    """Refuse a grounding whose model would need more memory in the job's own process
    than the memory limit: :data:`MODEL_BYTES_PER_SAS_BYTE` per byte of ``output.sas``."""
    memory = memory_limit_mb(limits.memory_mb)
    needed = sas_bytes * MODEL_BYTES_PER_SAS_BYTE / 2**20
    if needed > memory:
        raise ResourceLimitError(
            _memory_reached(
                memory,
                needed,
                f"the grounded task is too large: its {sas_bytes / 2**20:.0f} MB of Fast "
                f"Downward's output would take about {needed:.0f} MB in twostep's model, more "
                f"than the {memory} MB of {PARAMETER} (raise it, e.g. "
                f"{PARAMETER}={2 * round(needed)})",
            )
        )


MEMORY_PARAMETER, TIME_PARAMETER = "GroundingLimits.memory_mb", "GroundingLimits.time_s"
"""The parameters a grounding's limit messages name (:class:`GroundingLimits`)."""


def _memory_reached(memory: int, needed: float | None, words: str) -> LimitReached:
    return LimitReached(Limit.MEMORY, memory, needed, words, MEMORY_PARAMETER)


def _limit_hit(
    code: int | None, output: str, limits: GroundingLimits, wall_s: float
) -> ResourceLimitError | None:
    """The limit that ended a translator run with exit ``code`` after ``wall_s`` seconds
    (None: none did; a SIGKILL before its CPU time can have run out is no limit's)."""
    memory = memory_limit_mb(limits.memory_mb)
    no_memory = ("MemoryError", "failed to map segment", "Cannot allocate memory")
    if code == TRANSLATE_OUT_OF_MEMORY or (
        code not in (0, None) and any(words in output for words in no_memory)
    ):
        return ResourceLimitError(
            _memory_reached(
                memory,
                None,
                f"grounding ran out of memory: Fast Downward's translator needs more than the "
                f"{memory} MB of {PARAMETER} (raise it, e.g. {PARAMETER}={2 * memory})",
            )
        )
    seconds = f"{limits.time_s:g}"
    killed = code == -signal.SIGKILL and wall_s >= limits.time_s  # the hard CPU limit
    if code in (TRANSLATE_OUT_OF_TIME, -signal.SIGXCPU) or killed:
        words = (
            f"grounding ran out of time: Fast Downward's translator needs more than the "
            f"{seconds} s of CPU time of {PARAMETER} (raise it, e.g. "
            f"{PARAMETER}={2 * limits.time_s:g})"
        )
    elif code is None:
        words = (
            f"grounding did not finish in {limits.wall_s:g} s of wall-clock time (the "
            f"machine gave the translator too little of its {seconds} s of CPU time; raise "
            f"{PARAMETER}, or run fewer jobs at once)"
        )
    else:
        return None
    return ResourceLimitError(
        LimitReached(Limit.GROUNDING_TIME, limits.time_s, None, words, TIME_PARAMETER)
    )
