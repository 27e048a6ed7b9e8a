"""Planner benchmark: per task, parse time, plan time, and our wrapper's overhead.

For every task: the time to read it (our reader, Fast Downward's translator), the time of
``twostep.planner.plan`` (writes PDDL, runs the driver, reads the plan), the planner's own
time as the driver reports it (less sensitive to a loaded machine), and the time of
the Fast Downward driver called directly on the original files with the same alias and
limit. The overhead ratio is wrapper wall time / direct wall time; the script prints the
median ratio (goal: at most 1.10) and validates every plan with unified-planning.

    .venv/bin/python bench/bench_planner.py                  # all 100 tasks, lama-first
    .venv/bin/python bench/bench_planner.py --domains blocksworld --tasks 1-5 --repeats 3
    .venv/bin/python bench/bench_planner.py --json docs/bench/planner.json   # the results page's rows

``--json FILE`` also writes the rows as a bench record (:mod:`tools.record`);
:func:`evaluation.pages.planner.page` turns it into the results page (``make results``).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tools import record
from twostep.planner import ALIASES, PlannerSettings, Status, driver_path, plan
from twostep.tasks.benchmark import DEFAULT_DATA_ROOT, list_domains, list_tasks, load_task
from twostep.verify.validation import validate_plan


def direct_driver(domain: Path, problem: Path, alias: str, limit: float) -> float:
    """Wall time of the bare driver on the original files (what a user would run by hand)."""
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, str(driver_path()), *ALIASES[alias], "--search-time-limit", f"{int(limit)}s",
             "--plan-file", "plan", str(domain), str(problem)],
            cwd=tmp, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False,
        )  # fmt: skip
        return time.perf_counter() - start


def parse_range(text: str | None, available: list[int]) -> list[int]:
    if not text:
        return available
    lo, _, hi = text.partition("-")
    return [t for t in available if int(lo) <= t <= int(hi or lo)]


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA_ROOT)
    parser.add_argument("--domains", nargs="*")
    parser.add_argument("--tasks", help="range like 1-20")
    parser.add_argument("--alias", default="lama-first")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--repeats", type=int, default=1, help="timing repeats per task (median)")
    parser.add_argument("--json", type=Path, help="also write the rows here (a bench record)")
    args = parser.parse_args()
    run = record.started()
    rows: list[dict[str, Any]] = []
    args.data = args.data.resolve()  # the direct driver runs in a scratch folder
    settings = PlannerSettings(args.alias, args.time_limit)
    print(f"# {' '.join(sys.argv)}")
    print(
        f"{'task':<18}{'parse s':>9}{'plan s':>9}{'planner s':>10}{'direct s':>10}{'ratio':>7}"
        f"{'length':>8}  status"
    )
    ratios: list[float] = []
    failures = 0
    for domain in args.domains or list_domains(args.data):
        for task_id in parse_range(args.tasks, list_tasks(domain, args.data)):
            start = time.perf_counter()
            task = load_task(domain, task_id, args.data)
            parse_s = time.perf_counter() - start
            ours, direct = [], []
            result = None
            for _ in range(args.repeats):
                result = plan(task.problem, settings)
                ours.append(result.wall_time_s)
                direct.append(
                    direct_driver(task.domain_path, task.problem_path, args.alias, args.time_limit)
                )
            assert result is not None
            ok = result.status is Status.SOLVED and result.plan is not None
            valid = ok and validate_plan(task.problem, result.plan or ()).valid
            failures += not valid
            ratio = statistics.median(ours) / statistics.median(direct)
            if result.plan:  # tasks whose goal already holds never reach the driver
                ratios.append(ratio)
            length = len(result.plan) if result.plan is not None else "-"
            status = "valid" if valid else f"{result.status.value} {result.message}"
            rows.append({"domain": domain, "task": task_id, "name": task.name, "parse_s": parse_s,
                         "plan_s": statistics.median(ours), "planner_s": result.planner_time_s,
                         "direct_s": statistics.median(direct), "ratio": ratio,
                         "length": len(result.plan) if result.plan is not None else None, "valid": valid,
                         "status": status})  # fmt: skip
            print(f"{task.name:<18}{parse_s:>9.3f}{statistics.median(ours):>9.3f}"
                  f"{result.planner_time_s:>10.3f}{statistics.median(direct):>10.3f}"
                  f"{ratio:>7.3f}{length!s:>8}  {status}")  # fmt: skip
    if ratios:
        print(f"\nmedian wrapper/direct wall-time ratio over {len(ratios)} tasks: "
              f"{statistics.median(ratios):.3f} (goal <= 1.10)")  # fmt: skip
    print(f"tasks not solved+validated: {failures}")
    if args.json:
        settings_row = {
            "alias": args.alias,
            "time_limit_s": args.time_limit,
            "repeats": args.repeats,
        }
        record.write(args.json, run, rows, settings=settings_row)
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
