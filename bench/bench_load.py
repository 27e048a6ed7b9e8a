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

``--out`` writes the rows as a bench record (:mod:`tools.record`); :func:`section` is the
part of the conformance results page made from it (``make results``).
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

from bench.bench_conformance import ProblemFiles, find_problems  # noqa: E402
from checkers import fast_downward as fd  # noqa: E402
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


def fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def summary(rows: list[dict[str, Any]]) -> list[str]:
    """The corpus's medians and maxima and the AlfWorld-shaped problem's line (the last row)."""
    lines = []
    alf = rows[-1]
    corpus_rows = rows[:-1]
    both = [r for r in corpus_rows if r["twostep_load_s"] is not None and r["fd_translate_wall_s"]]
    fds = [r["fd_translate_wall_s"] for r in corpus_rows if r["fd_translate_wall_s"] is not None]
    if corpus_rows:
        lines.append(f"twostep loads {len(both)}/{len(corpus_rows)} problems")
    if both:
        loads = [r["twostep_load_s"] for r in both]
        worst = max(both, key=lambda r: r["twostep_load_s"])
        lines.append(
            f"on those {len(both)}: twostep load (process) median {statistics.median(loads):.2f} s, "
            f"max {max(loads):.2f} s ({worst['key']}), above 5 s: {sum(x > 5 for x in loads)}; "
            f"Fast Downward translate (process) median "
            f"{statistics.median(r['fd_translate_wall_s'] for r in both):.2f} s; "
            f"ratio median {statistics.median(r['ratio'] for r in both):.1f}x"
        )
    if fds:
        lines.append(
            f"Fast Downward translate (process), all {len(fds)}: median {statistics.median(fds):.2f} s, "
            f"max {max(fds):.2f} s"
        )
    lines.append(
        f"AlfWorld ({alf['key']}): twostep cold {fmt(alf['twostep_load_s'])} s, warm "
        f"{fmt(alf['twostep_warm_s'])} s; Fast Downward translate {fmt(alf['fd_translate_wall_s'])} s"
    )
    return lines


def section(data: dict[str, Any], figure: Any) -> list[str]:
    """The load-time part of the conformance results page, from an ``--out`` file."""
    from matplotlib.figure import Figure

    rows = data["rows"]
    baseline = data.get("baseline_s")
    lines = [
        "## Load time",
        "",
        f"Process wall times, start to end, medians of {data.get('repeats')} runs: twostep's "
        "load-only command (`twostep-score DOMAIN PROBLEM EMPTY_PLAN --no-cache`: read and "
        "ground the task), warm (the parsed-task cache), and Fast Downward's translator on "
        "the same files (process; own: its \"Done!\" time). The process start-up alone "
        f"(`twostep-score --help`): {baseline:.2f} s. The last row is the 65-object "
        "AlfWorld-shaped problem (`tests/fixtures/constructs/exists_goal/p02.pddl`).",
        "",
        *(f"- {line}" for line in summary(rows)),
        "",
        *record.table(
            ["problem", "twostep s", "twostep warm s", "FD translate s", "FD own s", "ratio", "error"],
            [[r["key"], fmt(r["twostep_load_s"]), fmt(r["twostep_warm_s"]),
              fmt(r["fd_translate_wall_s"]), fmt(r["fd_translate_own_s"]),
              "" if r["ratio"] is None else f"{r['ratio']:.1f}", r["error"]] for r in rows],
        ),
        "",
    ]  # fmt: skip
    fig = Figure(figsize=(9.0, 3.4), layout="constrained")
    axes = fig.subplots()
    shown = [r for r in rows if r["twostep_load_s"] is not None and r["fd_translate_wall_s"]]
    xs = range(len(shown))
    axes.bar([x - 0.2 for x in xs], [r["twostep_load_s"] for r in shown], 0.4, label="twostep")
    axes.bar([x + 0.2 for x in xs], [r["fd_translate_wall_s"] for r in shown], 0.4,
             label="Fast Downward translator")  # fmt: skip
    axes.set_xticks(list(xs), [r["key"].split("/")[0] for r in shown], rotation=90, fontsize=7)
    axes.set_ylabel("process wall s")
    axes.set_title("Reading and grounding each problem")
    axes.legend(fontsize=8)
    axes.grid(alpha=0.3, axis="y")
    lines += [
        figure(fig, "load", "Load time per problem, twostep and Fast Downward's translator"),
        "",
    ]
    return lines


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
