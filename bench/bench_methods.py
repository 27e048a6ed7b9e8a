"""SA vs MA vs TwoStep (every registered decomposer) over the benchmark and larger tasks.

For every data root, domain, task and N: SA (N = 1), MA (compiled N-agent PDDL) and
TwoStep with each decomposer named in ``--methods``. TwoStep runs get the SA plan of the
same task (plan-split reads it; ``fallback_if_longer`` compares against it, on unless
``--no-fallback``), and its planner time counts in theirs. Every joint schedule is
re-validated by simulation against the original task (``check_run``). At N = 1 every
method is the SA plan: those rows are shown as such, never run.

Prints, per data root, a side-by-side table per domain and N (mean execution length,
mean of the per-task ratios exec length / SA length, mean planning time, and TwoStep
planning time / MA planning time), then the macro exec/SA per N (mean over domains)
against the targets of issue 11, and per method the domains where it is no longer than MA.

Runs are long (the 100 tasks x N = 1..4 take about an hour), so: progress goes to stderr
(per planned method, and task i/n with the elapsed time); rows are written to ``--out``
after every task (atomically: a crash or a stop keeps the finished tasks); ``--resume``
skips the rows already in ``--out``; ``--reuse`` takes the SA and MA rows of earlier runs
(lama-first is deterministic, so only new methods need planning). A row is reused only
for the same data root, domain, task, N and method, planned with the same planner alias
and time limit (and, for TwoStep, the same ``fallback_if_longer``).

    .venv/bin/python bench/bench_methods.py --domains blocksworld --tasks 1-5 --agents 2
    .venv/bin/python bench/bench_methods.py --data data data/large --workers 2 \
        --reuse docs/bench/methods_deal.json --out outputs/bench/methods_all.json
    .venv/bin/python bench/bench_methods.py --report outputs/bench/methods_all.json

``--out`` is a bench record (:mod:`tools.record`: the rows with the command, date, commit,
machine and load of the run; rows files of earlier runs, bare lists, are read as well);
:mod:`evaluation.method_tables` turns records into the results pages (``make results``).

The runs are :mod:`evaluation.methods`': a new subgoal source joins the bench with one line in
its ``SUBGOAL_SOURCES``; every method runs through the registry
(:func:`twostep.methods.method_for`).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterable
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.method_tables import report_all
from evaluation.methods import (
    METHODS,
    REUSED_BY_DEFAULT,
    Job,
    Row,
    data_label,
    offline_default,
    reusable_rows,
    row_key,
    run_job,
    say,
    task_ids,
)
from tools import record
from twostep.generators import DOMAINS as BENCHMARK_DOMAINS
from twostep.tasks.benchmark import DEFAULT_DATA_ROOT, list_domains, list_tasks
from twostep.util.files import read_yaml_file


def _load_rows(paths: Iterable[str]) -> list[Row]:
    return [r for p in paths for r in record.rows_of(Path(p))]


def _clock(seconds: float) -> str:
    minutes, secs = divmod(int(seconds), 60)
    return f"{minutes // 60}:{minutes % 60:02d}:{secs:02d}"


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", nargs="+", default=[str(DEFAULT_DATA_ROOT)], help="data roots")
    parser.add_argument("--domains", nargs="*", help=f"default: {' '.join(BENCHMARK_DOMAINS)}")
    parser.add_argument("--tasks", default="1-20", help="a range 1-20 or a list 1,6,11,16")
    parser.add_argument("--agents", nargs="*", type=int, default=[1, 2, 3, 4])
    parser.add_argument("--methods", nargs="*", default=list(METHODS), choices=METHODS)
    parser.add_argument("--no-fallback", action="store_true", help="fallback_if_longer=false")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--alias", default="lama-first")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default="outputs/bench/methods.json")
    parser.add_argument("--resume", action="store_true", help="keep the rows already in --out")
    parser.add_argument("--reuse", nargs="*", default=[], help="rows JSON files of earlier runs")
    parser.add_argument(
        "--reuse-methods",
        nargs="*",
        default=list(REUSED_BY_DEFAULT),
        help="methods whose rows --reuse takes (default: sa ma, which no decomposer changes)",
    )
    parser.add_argument(
        "--agent-predicates",
        type=Path,
        help="YAML: domain -> agent predicates, for domains conf/domain/ does not have or "
        "names differently (default: conf/domain/<domain>.yaml)",
    )
    parser.add_argument(
        "--report", nargs="*", help="print the tables of these rows JSON files, run nothing"
    )
    parser.add_argument(
        "--plot", type=Path, help="with --report: the macro exec/SA against N and time (PNG)"
    )
    args = parser.parse_args()
    ns = sorted(set(args.agents) | {1})
    if args.report:
        # one row per key: a later file's row replaces an earlier one's
        shown = list({row_key(r): r for r in _load_rows(args.report)}.values())
        if args.domains:
            shown = [r for r in shown if r["domain"] in args.domains]
        print(f"# {' '.join(sys.argv)}\n")
        methods = [m for m in METHODS if m in args.methods]
        print(report_all(shown, methods, ns, offline_default(), args.plot))
        return 0

    fallback, out = not args.no_fallback, Path(args.out)
    old = _load_rows(args.reuse)
    known = reusable_rows(old, args.reuse_methods, args.alias, args.time_limit, fallback)
    for row in known.values():
        row.setdefault("reused_from", "--reuse")
    earlier: list[Row] = record.rows_of(out) if args.resume and out.is_file() else []
    run = record.started()
    # rows of this very run: every method
    known.update(reusable_rows(earlier, ("sa", *METHODS), args.alias, args.time_limit, fallback))
    given = read_yaml_file(args.agent_predicates) if args.agent_predicates else {}
    jobs = []
    for data in args.data:
        label = data_label(Path(data))
        available = list_domains(Path(data))
        domains = [d for d in (args.domains or BENCHMARK_DOMAINS) if d in available]
        for domain in domains:
            for t in task_ids(args.tasks, list_tasks(domain, Path(data))):
                of_task = tuple(r for k, r in known.items() if k[:3] == (label, domain, t))
                preds = tuple(given[domain]) if domain in given else None
                jobs.append(Job(data, label, domain, t, tuple(ns), tuple(args.methods), args.alias,
                                args.time_limit, fallback, of_task, preds))  # fmt: skip
    # task-major order (a run stopped early still covers every domain), larger roots last
    jobs.sort(key=lambda j: (args.data.index(j.data), j.task, j.domain))
    # a resumed --out keeps its rows of tasks outside this run (other roots, domains, tasks)
    ours = {(j.label, j.domain, j.task) for j in jobs}
    rows: list[Row] = [r for r in earlier if row_key(r)[:3] not in ours]
    start = time.perf_counter()
    say(f"{len(jobs)} tasks, {sum(len(j.known) for j in jobs)} earlier rows known; rows to {out}")
    with ProcessPoolExecutor(args.workers) as pool:
        futures = {pool.submit(run_job, job): job for job in jobs}
        for done, future in enumerate(as_completed(futures), start=1):
            job = futures[future]
            try:
                got = future.result()
            except Exception as error:  # e.g. an unreadable task: the others go on
                say(
                    f"[{done}/{len(jobs)}] {job.label}:{job.domain}/p{job.task:02d} FAILED: {error}"
                )
                continue
            rows += got
            record.write(out, run, rows)  # finished tasks survive a crash or a stop
            reused = sum(r in job.known for r in got)
            elapsed = time.perf_counter() - start
            # rough: later tasks are larger, so the estimate errs short
            left = elapsed / done * (len(jobs) - done)
            say(f"[{done}/{len(jobs)}] {job.label}:{job.domain}/p{job.task:02d}: "
                 f"{len(got) - reused} rows planned, {reused} reused; "
                 f"elapsed {_clock(elapsed)}, left ~{_clock(left)}")  # fmt: skip
    methods = [m for m in METHODS if m in args.methods]
    print(f"# {' '.join(sys.argv)}")
    print(f"# planner {args.alias}, search time limit {args.time_limit:g} s (TwoStep: limit/N per "
          f"agent); fallback_if_longer={fallback}; tasks {args.tasks}; "
          f"{sum('reused_from' in r for r in rows)} rows reused\n")  # fmt: skip
    print(report_all(rows, methods, ns, offline_default()))
    unsolved = sum(not r["valid"] for r in rows)
    # a timeout is a result; a schedule that fails re-validation or a crash is a bug
    broken = [
        r
        for r in rows
        if r["status"] == "error" or r.get("message", "").startswith("schedule invalid")
    ]
    inexact = sum(r.get("exact") is False for r in rows)
    print(f"\nrows: {len(rows)}; not valid: {unsolved} (of which invalid schedules or crashes: "
          f"{len(broken)}); scored inexactly (node budget: the length is an upper bound): "
          f"{inexact}")  # fmt: skip
    return 1 if broken else 0


if __name__ == "__main__":
    raise SystemExit(main())
