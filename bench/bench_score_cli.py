"""Benchmark: wall time of the ``twostep-score`` command on four 60-step plans.

    .venv/bin/python -m compileall -q .venv/lib     # once: PYTHONDONTWRITEBYTECODE=1 here
    .venv/bin/python bench/bench_score_cli.py [--repeats 5] [--json docs/bench/score_cli.json]

The plans are bench_execution.py's ``independent`` case: four agents, each driving its own
cart 60 cells along a private track (the search itself takes milliseconds, so the time is
the process: start-up, imports, reading the PDDL). The first row reads the parsed task from
``--cache-dir`` (filled by one untimed call first), the others parse every time. Each run is a fresh process, timed from
outside; CPU is the child's user + system time, which the other jobs on a shared machine
do not inflate. The ``engines imported`` row imports unified-planning's engine factory
first (what reading PDDL cost before the lazy environment of
:mod:`twostep.verify.up_environment`). ``--json FILE`` also writes the rows (every run's wall
and CPU seconds) as a bench record (:mod:`tools.record`), which ``make results`` renders
(:func:`evaluation.pages.score_cli.page`).
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.pages.score_cli import GOAL_S
from evaluation.tracks import AGENT_PREDICATES, CASES, PLAN_LENGTH, TRACKS, build
from tools import record

SCORE = "from twostep.cli.score import main; raise SystemExit(main())"
ENGINES_FIRST = "import unified_planning.engines; " + SCORE


def write_instance(folder: Path) -> list[str]:
    """Domain, problem and four plan files in ``folder``; the command's arguments."""
    instance = build(CASES[0], PLAN_LENGTH)
    (folder / "domain.pddl").write_text(TRACKS)
    (folder / "problem.pddl").write_text(instance.single_agent_problem)
    plans = []
    for agent, plan in enumerate(instance.plans):
        path = folder / f"agent{agent}.plan"
        path.write_text("\n".join(plan) + "\n")
        plans.append(str(path))
    return [
        str(folder / "domain.pddl"),
        str(folder / "problem.pddl"),
        *plans,
        "--agent-predicates",
        ",".join(AGENT_PREDICATES),
    ]


def time_process(command: list[str]) -> tuple[float, float]:
    """(wall seconds, child CPU seconds) of one run; the run must succeed."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs per row")
    parser.add_argument("--json", type=Path, help="also write the rows here (a bench record)")
    args = parser.parse_args(argv)
    run = record.started()
    measured: list[dict[str, Any]] = []
    executable = Path(sys.executable).parent / "twostep-score"
    print(f"$ python bench/bench_score_cli.py --repeats {args.repeats}")
    print(
        f"python {platform.python_version()}, {os.cpu_count()} CPUs, load average "
        f"{os.getloadavg()[0]:.1f}; 4 agents x {PLAN_LENGTH} steps; median of {args.repeats}"
    )
    with tempfile.TemporaryDirectory(prefix="bench-score-") as tmp:
        arguments = write_instance(Path(tmp))
        cache = ["--cache-dir", str(Path(tmp) / "cache")]
        rows = {
            "twostep-score, parsed task cached (2nd call on)": [
                str(executable),
                *arguments,
                *cache,
            ],
            "twostep-score --no-cache (every call parses)": [
                str(executable),
                *arguments,
                "--no-cache",
            ],
            "engines imported, no cache": [
                sys.executable,
                "-c",
                ENGINES_FIRST,
                *arguments,
                "--no-cache",
            ],
        }
        time_process(rows["twostep-score, parsed task cached (2nd call on)"])  # fills the cache
        print("\n| command | wall s | CPU s |\n|---|---|---|")
        for name, command in rows.items():
            times = [time_process(command) for _ in range(args.repeats)]
            wall = statistics.median(t[0] for t in times)
            cpu = statistics.median(t[1] for t in times)
            print(f"| {name} | {wall:.2f} | {cpu:.2f} |")
            measured.append({"command": name, "wall_s": [t[0] for t in times],
                             "cpu_s": [t[1] for t in times]})  # fmt: skip
    if args.json:
        record.write(args.json, run, measured, repeats=args.repeats, agents=4,
                     steps=PLAN_LENGTH, goal_s=GOAL_S)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
