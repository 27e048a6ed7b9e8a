"""Running Fast Downward's driver (shipped in the ``up-fast-downward`` wheel) on a task.

It writes the problem as PDDL into a private temporary folder, runs the driver with a CPU
search time limit, a memory limit for its translator and search
(``PlannerSettings.memory_limit_mb``, default 4 GiB) and a wall-clock guard, under the guard process of :mod:`twostep.programs.processes`
(nothing of it outlives the job), reads the last complete plan file and turns the
exit code into a :class:`~twostep.planner.results.Status` (a search or translator out of
memory: an error whose :attr:`~twostep.planner.results.PlanResult.limit` says so). The planner's own limit ends a
search (its exit code says so); the guard is a safety net whose stops are flagged apart
(:attr:`~twostep.planner.results.PlanResult.guard_stopped`).
"""

from __future__ import annotations

import re
import sys
import tempfile
import time
from pathlib import Path

from twostep.pddl import Problem, planner_input
from twostep.planner import returncodes
from twostep.planner.aliases import ALIASES
from twostep.planner.plan_files import PlanFile, complete_plans, plan_files
from twostep.planner.results import PlanResult, Status
from twostep.planner.settings import PlannerSettings
from twostep.programs.downward import driver_path
from twostep.programs.processes import (
    PARAMETER,
    Limit,
    LimitReached,
    memory_limit_mb,
    run_guarded,
)

_PLANNER_TIME = re.compile(r"Planner time: ([0-9.]+)s")
MEMORY_PARAMETER = "PlannerSettings.memory_limit_mb"
"""The parameter a planner call's memory-limit message names (:class:`PlannerSettings`)."""


def status_for(code: int | None, plan: PlanFile | None) -> tuple[Status, str]:
    """The status of a run that ended with exit ``code`` (None: killed by the guard)."""
    if code is None:
        stopped = "wall-clock guard stopped the planner before its own time limit ended it"
        return (Status.SOLVED if plan is not None else Status.TIMEOUT), stopped
    message = returncodes.meaning(code)
    ended_with_plans = returncodes.PLAN_FOUND | returncodes.OUT_OF_TIME | returncodes.OUT_OF_MEMORY
    if plan is not None and code in ended_with_plans:
        return Status.SOLVED, message
    if code in returncodes.PLAN_FOUND:
        return Status.ERROR, f"{message}, but no complete plan file"
    if code in returncodes.PROVEN_UNSOLVABLE:
        return Status.UNSOLVABLE, message
    if code in returncodes.INCOMPLETE:
        return Status.INCOMPLETE, message
    if code in returncodes.OUT_OF_TIME:
        return Status.TIMEOUT, message
    return Status.ERROR, message


def run_driver(
    domain_file: Path,
    problem_file: Path,
    settings: PlannerSettings,
    workdir: Path,
    temporary: bool = False,
) -> PlanResult:
    """Run the driver on PDDL files in ``workdir`` (which receives plan and SAS files;
    ``temporary``: the call's own folder, removed should the job die during the call)."""
    if settings.alias not in ALIASES:
        known = ", ".join(sorted(ALIASES))
        return PlanResult(
            Status.ERROR,
            None,
            0.0,
            0.0,
            f"unknown planner alias '{settings.alias}' (known: {known})",
        )
    command = [sys.executable, str(driver_path())]
    memory = memory_limit_mb(settings.memory_limit_mb)
    command += ["--overall-memory-limit", f"{memory}M"]  # its translator and search each
    alias = ALIASES[settings.alias]
    # driver options go before the input files, a search configuration after them
    driver_options, search_options = (alias, ()) if alias[0] != "--search" else ((), alias)
    command += [
        *driver_options,
        "--search-time-limit",
        f"{max(1, round(settings.search_time_limit_s))}s",
    ]
    command += ["--plan-file", "plan", str(domain_file), str(problem_file), *search_options]
    start = time.perf_counter()
    # Under the guard (twostep.programs.processes): the driver, its translator and its search end
    # with the job, and the wall-clock guard stops them together.
    done = run_guarded(command, workdir, settings.wall_guard(), temporary=temporary)
    output, code = done.output, done.code
    wall = time.perf_counter() - start
    plans = complete_plans(workdir)
    best = plans[-1] if plans else None
    status, message = status_for(code, best)
    incomplete = len(plan_files(workdir)) - len(plans)
    if incomplete and status is not Status.SOLVED:
        message = f"{message} ({incomplete} incomplete plan file(s) ignored)"
    limit = None
    if status is Status.ERROR and code in returncodes.OUT_OF_MEMORY:
        words = f"{message} (the {memory} MB of {PARAMETER}: raise it)"
        limit = LimitReached(Limit.MEMORY, memory, None, words, MEMORY_PARAMETER)
        message = limit.message()
    elif status is Status.ERROR:
        tail = [line for line in output.splitlines() if line.strip()][-3:]
        message = f"{message}: {' | '.join(tail)}" if tail else message
    reported = [float(m) for m in _PLANNER_TIME.findall(output)]
    solved = status is Status.SOLVED and best is not None
    return PlanResult(
        status,
        best.actions if solved and best is not None else None,
        reported[-1] if reported else wall,
        wall,
        message,
        code,
        len(plans),
        best.cost if solved and best is not None else None,
        guard_stopped=code is None,
        limit=limit,
    )


def plan_pddl(domain_pddl: str, problem_pddl: str, settings: PlannerSettings) -> PlanResult:
    """Solve a task given as PDDL text (deterministic inputs: a good cache key)."""
    with tempfile.TemporaryDirectory(prefix="twostep-fd-") as tmp:
        folder = Path(tmp)
        (folder / "domain.pddl").write_text(domain_pddl)
        (folder / "problem.pddl").write_text(problem_pddl)
        return run_driver(
            folder / "domain.pddl", folder / "problem.pddl", settings, folder, temporary=True
        )


def plan(problem: Problem, settings: PlannerSettings | None = None) -> PlanResult:
    """Solve ``problem`` with Fast Downward. A goal that already holds gives an empty plan."""
    settings = settings or PlannerSettings()
    if problem.goal.holds(problem.init):
        return PlanResult(Status.SOLVED, (), 0.0, 0.0, "goal holds in the initial state", 0, 0, 0)
    return plan_pddl(*planner_input(problem), settings)
