"""Load-time bench: how long twostep takes to read a task (parse + ground) beside Fast
Downward's translator on the same files, and a 65-object AlfWorld-shaped problem cold.

For every problem of the corpus, ``--repeats`` times, the two side by side (alternating, so
both see the same machine load):

* **twostep**: ``twostep-score DOMAIN PROBLEM EMPTY_PLAN --no-cache``, twostep's load-only
  command line (it reads and grounds the task, then checks an empty plan), on a cold
  parsed-task cache; then with a cache folder, once to fill it and ``--repeats`` times warm
  (the parsed-task cache). Process wall times, start to end: they include the process's
  start-up, printed once as the wall time of ``twostep-score --help``.
* **Fast Downward**: ``python -m fast_downward.translate`` from the up-fast-downward wheel
  (the process's wall time, start-up included, and the translator's own "Done!" wall-clock
  time: parse, ground, write ``output.sas``).

In-process load times of the ``twostep`` command (``orchestration.task_load_s``) are in the
conformance bench's rows (``bench/bench_conformance.py``, column "load s").

Reports per problem the medians, then the median and max over the corpus and the ratio.
The AlfWorld-shaped problem is ``tests/fixtures/constructs/exists_goal/p02.pddl`` (our own
domain in alfred.pddl's shape, 65 objects with AlfWorld's names). Timings depend on the
machine's load: the load average is printed before and after.

    .venv/bin/python bench/bench_load.py --corpus ../shared/ipc-sample --repeats 3
    .venv/bin/python bench/bench_load.py --alfworld-only --repeats 5

``--out`` writes the rows as a bench record (:mod:`tools.record`);
:func:`evaluation.load_time.section` is the part of the conformance results page made from
it (``make results``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from checkers import fast_downward as fd  # noqa: E402
from evaluation.conformance import ProblemFiles, find_problems  # noqa: E402
from evaluation.load_time import fmt, summary  # noqa: E402
from tools import record  # noqa: E402

ALFWORLD_SHAPE = REPO / "tests" / "fixtures" / "constructs" / "exists_goal"
EXIT_BAD_INPUT = 2  # twostep-score: the files do not load


def score_command() -> str:
    beside = Path(sys.executable).parent / "twostep-score"
    return str(beside) if beside.is_file() else "twostep-score"


def timed(
    command: list[str], env: dict[str, str] | None = None
) -> tuple[float, subprocess.CompletedProcess[str]]:
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env, check=False)
    return time.perf_counter() - start, done


def load_average() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def startup_baseline(repeats: int) -> float:
    return statistics.median(timed([score_command(), "--help"])[0] for _ in range(max(3, repeats)))


def measure(files: ProblemFiles, repeats: int, tmp: Path) -> dict[str, Any]:
    empty = tmp / "empty.plan"
    empty.write_text("")
    cold: list[float] = []
    warm: list[float] = []
    fd_wall: list[float] = []
    fd_own: list[float] = []
    errors: dict[str, str] = {}
    for _ in range(repeats):
        command = [score_command(), str(files.domain), str(files.problem), str(empty), "--no-cache"]
        wall, done = timed(command)
        if done.returncode == EXIT_BAD_INPUT:
            errors["twostep"] = (done.stderr.strip().splitlines() or ["exit 2"])[-1][:200]
        else:
            cold.append(wall)
        try:
            translation = fd.translate(files.domain, files.problem, options=())
        except fd.TranslateError as failure:
            errors["Fast Downward"] = str(failure)
            continue
        fd_wall.append(translation.wall_s)
        if translation.translator_s is not None:
            fd_own.append(translation.translator_s)
    error = "; ".join(f"{who}: {text}" for who, text in errors.items())
    if cold:
        with tempfile.TemporaryDirectory() as cache:
            command = [score_command(), str(files.domain), str(files.problem), str(empty)]
            command += ["--cache-dir", cache]
            timed(command)  # fills the cache
            warm = [timed(command)[0] for _ in range(repeats)]

    def median(values: list[float]) -> float | None:
        return round(statistics.median(values), 3) if values else None

    load, translate = median(cold), median(fd_wall)
    return {"key": files.key, "twostep_load_s": load, "twostep_warm_s": median(warm),
            "fd_translate_wall_s": translate, "fd_translate_own_s": median(fd_own),
            "ratio": round(load / translate, 1) if load is not None and translate else None,
            "error": error}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--corpus", type=Path, help="LLM+P layout or any tree of domain.pddl + problems"
    )
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", help="comma-separated domain folders")
    parser.add_argument(
        "--alfworld-only", action="store_true", help="only the 65-object AlfWorld-shaped problem"
    )
    parser.add_argument(
        "--alfworld",
        nargs=2,
        type=Path,
        metavar=("DOMAIN", "PROBLEM"),
        help="another AlfWorld problem for the AlfWorld line (default: our 65-object fixture)",
    )
    parser.add_argument("--out", type=Path, help="write the rows as JSON")
    args = parser.parse_args(argv)
    run = record.started(None if argv is None else ["bench/bench_load.py", *argv])

    problems: list[ProblemFiles] = []
    if args.corpus and not args.alfworld_only:
        problems = find_problems(args.corpus.resolve())
        if args.only:
            wanted = {d.strip() for d in args.only.split(",")}
            problems = [p for p in problems if p.domain_name in wanted]
    alf_domain, alf_problem = args.alfworld or (
        ALFWORLD_SHAPE / "domain.pddl",
        ALFWORLD_SHAPE / "p02.pddl",
    )
    alfworld = ProblemFiles("alfworld", alf_domain, alf_problem, None)
    print(f"load average before: {load_average()}", flush=True)
    baseline = startup_baseline(args.repeats)
    print(f"twostep-score start-up (--help, median wall): {baseline:.2f} s", flush=True)
    print("process wall times, medians of the repeats:", flush=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for files in [*problems, alfworld]:
            row = measure(files, args.repeats, Path(tmp))
            rows.append(row)
            print(
                f"{row['key']:45s} twostep {fmt(row['twostep_load_s'])} s (warm {fmt(row['twostep_warm_s'])})"
                f" | FD translate {fmt(row['fd_translate_wall_s'])} s (own {fmt(row['fd_translate_own_s'])})"
                f"{' | ' + row['error'] if row['error'] else ''}",
                flush=True,
            )
    print(f"load average after: {load_average()}")
    print("\n".join(summary(rows)))
    if args.out:
        record.write(args.out, run, rows, repeats=args.repeats, baseline_s=baseline)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
