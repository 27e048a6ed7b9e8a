"""Fast Downward, run from the driver that ships inside the ``up-fast-downward`` wheel.

One entry point, :func:`plan`, for every planner call of the project. It writes the
problem as PDDL into a private temporary folder, runs the driver with a CPU search time
limit and a wall-clock guard, and returns a :class:`PlanResult`: the plan (best one for
anytime aliases), its cost, the planner's own reported time, the wall time, and a status.
A timeout, an unsolvable task or a crash is a status, never an exception.

Exit codes and aliases are data (below), named as in Fast Downward's ``driver/``.
"""

from __future__ import annotations

import enum
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from twostep.pddl import Problem, domain_to_pddl, problem_to_pddl


class Status(enum.StrEnum):
    SOLVED = "solved"
    TIMEOUT = "timeout"
    UNSOLVABLE = "unsolvable"
    ERROR = "error"


# Fast Downward driver exit codes (driver/returncodes.py).
PLAN_FOUND = {0: "success", 1: "plan found, out of memory", 2: "plan found, out of time",
              3: "plan found, out of memory and time"}  # fmt: skip
UNSOLVABLE = {10: "translator proved unsolvable", 11: "search proved unsolvable",
              12: "search space exhausted (incomplete search)", 13: "unsolvable within bound"}  # fmt: skip
OUT_OF_TIME = {21: "translator out of time", 23: "search out of time",
               24: "search out of memory and time"}  # fmt: skip
FAILURE = {20: "translator out of memory", 22: "search out of memory",
           30: "translator critical error", 31: "translator input error",
           32: "search critical error", 33: "search input error", 34: "search unsupported",
           35: "driver critical error", 36: "driver input error", 37: "driver unsupported"}  # fmt: skip

# Our alias name -> Fast Downward driver arguments. Anytime aliases write plan.1, plan.2,
# ... with improving costs; the last one is the best.
ALIASES: dict[str, tuple[str, ...]] = {
    "lama": ("--alias", "seq-sat-lama-2011"),  # the paper's setting: anytime LAMA
    "lama-first": ("--alias", "lama-first"),  # first plan of LAMA's first iteration
    "seq-sat-lama-2011": ("--alias", "seq-sat-lama-2011"),
    "seq-opt-lmcut": ("--alias", "seq-opt-lmcut"),  # optimal; used for the example plans
}
ANYTIME_ALIASES = frozenset({"lama", "seq-sat-lama-2011"})


def driver_path() -> Path:
    """The ``fast-downward.py`` driver inside the installed up-fast-downward wheel."""
    import up_fast_downward

    return Path(up_fast_downward.__file__).resolve().parent / "downward" / "fast-downward.py"


@dataclass(frozen=True)
class PlannerSettings:
    alias: str = "lama-first"
    search_time_limit_s: float = 60.0  # CPU time of the search component
    wall_time_limit_s: float | None = None  # guard on the whole call; default: derived
    memory_limit_mb: int | None = None

    def wall_guard(self) -> float:
        if self.wall_time_limit_s is not None:
            return self.wall_time_limit_s
        return self.search_time_limit_s * 1.25 + 15.0

    def with_time_limit(self, seconds: float) -> PlannerSettings:
        return PlannerSettings(self.alias, seconds, None, self.memory_limit_mb)


@dataclass(frozen=True)
class PlanResult:
    status: Status
    plan: tuple[str, ...] | None
    planner_time_s: float  # the driver's reported planner time (wall time if killed)
    wall_time_s: float
    message: str = ""
    exit_code: int | None = None
    plans_found: int = 0

    @property
    def solved(self) -> bool:
        return self.status is Status.SOLVED

    @property
    def cost(self) -> int | None:
        return len(self.plan) if self.plan is not None else None

    def to_dict(self) -> dict[str, object]:
        return {
            "status": self.status.value,
            "plan": list(self.plan) if self.plan is not None else None,
            "cost": self.cost,
            "planner_time_s": round(self.planner_time_s, 4),
            "wall_time_s": round(self.wall_time_s, 4),
            "message": self.message,
            "exit_code": self.exit_code,
            "plans_found": self.plans_found,
        }


_PLANNER_TIME = re.compile(r"Planner time: ([0-9.]+)s")


def _read_plan_file(path: Path) -> tuple[str, ...]:
    lines = (line.split(";", 1)[0].strip() for line in path.read_text().splitlines())
    return tuple(line for line in lines if line)


def _plan_files(folder: Path) -> list[Path]:
    single = folder / "plan"
    if single.is_file():
        return [single]
    numbered = [p for p in folder.glob("plan.*") if p.suffix[1:].isdigit()]
    return sorted(numbered, key=lambda p: int(p.suffix[1:]))


def _status_for(code: int | None, have_plan: bool) -> tuple[Status, str]:
    if code is None:
        return (
            Status.SOLVED if have_plan else Status.TIMEOUT
        ), "wall-clock guard stopped the planner"
    if code in PLAN_FOUND and have_plan:
        return Status.SOLVED, PLAN_FOUND[code]
    if code in UNSOLVABLE:
        return Status.UNSOLVABLE, UNSOLVABLE[code]
    if code in OUT_OF_TIME:
        return (Status.SOLVED if have_plan else Status.TIMEOUT), OUT_OF_TIME[code]
    if code in FAILURE:
        return (Status.SOLVED if have_plan and code in (20, 22) else Status.ERROR), FAILURE[code]
    return Status.ERROR, f"unexpected exit code {code}"


def run_driver(
    domain_file: Path, problem_file: Path, settings: PlannerSettings, workdir: Path
) -> PlanResult:
    """Run the driver on PDDL files in ``workdir`` (which receives plan and SAS files)."""
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
    if settings.memory_limit_mb is not None:
        command += ["--overall-memory-limit", f"{settings.memory_limit_mb}M"]
    command += [
        *ALIASES[settings.alias],
        "--search-time-limit",
        f"{max(1, round(settings.search_time_limit_s))}s",
    ]
    command += ["--plan-file", "plan", str(domain_file), str(problem_file)]
    start = time.perf_counter()
    process = subprocess.Popen(
        command,
        cwd=workdir,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,  # so the guard can stop translator and search together
    )
    try:
        output, _ = process.communicate(timeout=settings.wall_guard())
        code: int | None = process.returncode
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        output, _ = process.communicate()
        code = None
    wall = time.perf_counter() - start
    files = _plan_files(workdir)
    plan = _read_plan_file(files[-1]) if files else None
    status, message = _status_for(code, plan is not None)
    if status is Status.ERROR:
        tail = [line for line in output.splitlines() if line.strip()][-3:]
        message = f"{message}: {' | '.join(tail)}" if tail else message
    reported = [float(m) for m in _PLANNER_TIME.findall(output)]
    return PlanResult(
        status,
        plan if status is Status.SOLVED else None,
        reported[-1] if reported else wall,
        wall,
        message,
        code,
        len(files),
    )


def plan_pddl(domain_pddl: str, problem_pddl: str, settings: PlannerSettings) -> PlanResult:
    """Solve a task given as PDDL text (deterministic inputs: a good cache key)."""
    with tempfile.TemporaryDirectory(prefix="twostep-fd-") as tmp:
        folder = Path(tmp)
        (folder / "domain.pddl").write_text(domain_pddl)
        (folder / "problem.pddl").write_text(problem_pddl)
        return run_driver(folder / "domain.pddl", folder / "problem.pddl", settings, folder)


def planner_input(problem: Problem) -> tuple[str, str]:
    """The PDDL texts the planner receives for ``problem``."""
    extra = (":negative-preconditions",) if problem.goal.negative else ()
    return domain_to_pddl(problem.domain, extra), problem_to_pddl(problem)


def plan(problem: Problem, settings: PlannerSettings | None = None) -> PlanResult:
    """Solve ``problem`` with Fast Downward. A goal that already holds gives an empty plan."""
    settings = settings or PlannerSettings()
    if problem.goal.holds(problem.init):
        return PlanResult(Status.SOLVED, (), 0.0, 0.0, "goal holds in the initial state", 0, 0)
    return plan_pddl(*planner_input(problem), settings)
