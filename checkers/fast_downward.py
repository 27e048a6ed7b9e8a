"""Fast Downward on the original files: its translator (grounding) and its planner, as
subprocesses of the copy inside the up-fast-downward wheel (GPL-3, kept at arm's length).

Nothing here comes from twostep: the paths are found from the wheel itself.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from .sas import SASTask, parse_sas

# Options for a validator: keep every fact, variable and operator the search would drop,
# and make every atom its own binary variable (so agent facts can be copied per agent).
VALIDATION_OPTIONS = (
    "--keep-unimportant-variables",
    "--keep-unreachable-facts",
    "--keep-no-ops",
    "--invariant-generation-max-candidates",
    "0",
)

# The driver's exit codes this module reads (Fast Downward's driver/returncodes.py).
SUCCESS = 0
SEARCH_UNSOLVABLE = 11
SEARCH_UNSOLVED_INCOMPLETE = 12
SEARCH_OUT_OF_MEMORY = 22
SEARCH_OUT_OF_TIME = 23
TRANSLATE_CRITICAL_ERROR = 31
STATUS_BY_EXIT_CODE = {
    SUCCESS: "solved",
    SEARCH_UNSOLVABLE: "unsolvable",
    SEARCH_UNSOLVED_INCOMPLETE: "incomplete",
    SEARCH_OUT_OF_MEMORY: "out of memory",
    SEARCH_OUT_OF_TIME: "timeout",
}

OPTIMAL_SEARCH = ("--search", "astar(blind())")  # exact and needs no heuristic support


class TranslateError(RuntimeError):
    """Fast Downward's translator rejected the files (the message is its last words)."""


def downward_dir() -> Path:
    spec = importlib.util.find_spec("up_fast_downward")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("up-fast-downward is not installed")
    return Path(next(iter(spec.submodule_search_locations))) / "downward"


def driver_path() -> Path:
    return downward_dir() / "fast-downward.py"


def _translator_env() -> dict[str, str]:
    env = dict(os.environ)
    bin_dir = str(downward_dir() / "builds" / "release" / "bin")
    env["PYTHONPATH"] = bin_dir + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _last_words(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    interesting = [
        line for line in lines if re.search(r"error|undefined|duplicate|not|unknown", line, re.I)
    ]
    return (interesting or lines or ["no output"])[-1][:300]


@dataclass(frozen=True)
class Translation:
    task: SASTask
    wall_s: float  # the translator process, start to end
    translator_s: float | None  # the translator's own "Done!" wall-clock time


def translate(
    domain: Path,
    problem: Path,
    options: tuple[str, ...] = VALIDATION_OPTIONS,
    timeout_s: float = 600,
) -> Translation:
    """Ground ``domain`` + ``problem`` with Fast Downward's translator."""
    domain, problem = Path(domain).resolve(), Path(problem).resolve()
    with tempfile.TemporaryDirectory(prefix="fd-translate-") as tmp:
        sas = Path(tmp) / "output.sas"
        command = [sys.executable, "-m", "fast_downward.translate", str(domain), str(problem)]
        start = time.perf_counter()
        try:
            done = subprocess.run(
                [*command, "--sas-file", str(sas), *options],
                env=_translator_env(),
                cwd=tmp,
                capture_output=True,
                text=True,
                timeout=timeout_s,
                check=False,
            )
        except subprocess.TimeoutExpired:
            raise TranslateError(f"translator timed out after {timeout_s:g} s") from None
        wall = time.perf_counter() - start
        if done.returncode != 0 or not sas.is_file():
            raise TranslateError(
                f"translator exit {done.returncode}: {_last_words(done.stdout + done.stderr)}"
            )
        match = re.search(r"Done! \[[\d.]+s CPU, ([\d.]+)s wall-clock\]", done.stdout)
        own = float(match.group(1)) if match else None
        return Translation(parse_sas(sas.read_text()), wall, own)


@dataclass(frozen=True)
class PlannerRun:
    status: str  # solved, timeout, unsolvable, incomplete, error
    plan: tuple[str, ...] | None
    cost: int | None
    wall_s: float
    message: str = ""


def read_plan_file(text: str) -> tuple[tuple[str, ...], int] | None:
    """A plan file's actions and cost; None unless complete (its ``; cost = N`` trailer)."""
    match = re.search(r"^; cost = (\d+)", text, re.M)
    if not match:
        return None
    steps = tuple(
        line.strip() for line in text.splitlines() if line.strip() and not line.startswith(";")
    )
    return steps, int(match.group(1))


def plan(
    domain: Path,
    problem: Path,
    search: tuple[str, ...] = ("--alias", "lama-first"),
    time_limit_s: float = 30,
) -> PlannerRun:
    """Run Fast Downward on the files as they are; the last complete plan counts."""
    domain, problem = Path(domain).resolve(), Path(problem).resolve()
    with tempfile.TemporaryDirectory(prefix="fd-plan-") as tmp:
        alias = list(search[:2]) if search[0] == "--alias" else []
        rest = list(search[2:]) if alias else list(search)
        command = [
            sys.executable,
            str(driver_path()),
            *alias,
            "--search-time-limit",
            f"{max(1, int(time_limit_s))}s",
            "--plan-file",
            "plan",
            str(domain),
            str(problem),
            *rest,
        ]
        start = time.perf_counter()
        try:
            done = subprocess.run(
                command,
                cwd=tmp,
                capture_output=True,
                text=True,
                timeout=time_limit_s * 2 + 60,
                check=False,
            )
        except subprocess.TimeoutExpired:
            return PlannerRun("timeout", None, None, time.perf_counter() - start, "wall clock")
        wall = time.perf_counter() - start
        files = sorted(Path(tmp).glob("plan*"), key=lambda p: (len(p.name), p.name))
        for path in reversed(files):
            read = read_plan_file(path.read_text())
            if read is not None:
                return PlannerRun("solved", read[0], read[1], wall)
        status = STATUS_BY_EXIT_CODE.get(done.returncode, "error")
        if status == "solved":
            status = "error"
        message = f"exit {done.returncode}: {_last_words(done.stdout + done.stderr)}"
        return PlannerRun(status, None, None, wall, message)
