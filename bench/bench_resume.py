"""Resume benchmark: a sweep, then the same command again, which reuses every finished job.

Runs a 4-job TwoStep sweep (``twostep -m domain=blocksworld,grippers task=1,2 agents=2
method=twostep decomposer=goal-split hydra/launcher=joblib``) in a fresh output root, then
the same command again, and prints both wall times (the ``twostep`` command, start to
exit) with what the second run reused (its sweep summary). The second run reads every
job back from the job store: no planner call, no Prefect server.

    .venv/bin/python bench/bench_resume.py
    .venv/bin/python bench/bench_resume.py --repeats 3      # medians of 3 fresh roots
    .venv/bin/python bench/bench_resume.py --repeats 3 --json docs/bench/resume.json

``tests/test_sweep.py`` checks that the second run computes nothing; how long each takes
is this bench's.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tools import record

REPO = Path(__file__).resolve().parent.parent
TWOSTEP = Path(sys.executable).parent / "twostep"
GRID = [
    "-m", "domain=blocksworld,grippers", "task=1,2", "agents=2", "method=twostep",
    "decomposer=goal-split", "hydra/launcher=joblib",
]  # fmt: skip


def timed_run(command: list[str], env: dict[str, str]) -> float:
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=REPO)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"sweep failed ({done.returncode}):\n{done.stdout}\n{done.stderr}")
    return wall


def latest_summary(out: Path) -> dict[str, Any]:
    sweeps = sorted(out.glob("multiruns/*/*/.twostep/summary.json"))
    return dict(json.loads(sweeps[-1].read_text()))


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", type=Path, default=REPO / "data")
    parser.add_argument("--repeats", type=int, default=1, help="fresh output roots")
    parser.add_argument("--keep", action="store_true", help="keep the output folders")
    parser.add_argument("--json", type=Path, help="also write what it prints as a record here")
    args = parser.parse_args()
    with record.capture(args.json, title="A sweep, then the same command again"):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    if not all((args.data / d / "p02.pddl").is_file() for d in ("blocksworld", "grippers")):
        raise SystemExit(f"need blocksworld and grippers p01, p02 under {args.data}")
    env = dict(os.environ)
    env.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")
    env.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
    print(f"# {' '.join(sys.argv)}")
    print(f"# load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")

    firsts, seconds = [], []
    for repeat in range(args.repeats):
        out = Path(tempfile.mkdtemp(prefix="twostep-bench-resume-"))
        command = [str(TWOSTEP), *GRID, f"data.root={args.data}", f"output.root={out}"]
        first = timed_run(command, env)
        second = timed_run(command, env)
        facts = latest_summary(out)
        firsts.append(first)
        seconds.append(second)
        print(
            f"run {repeat + 1}: first {first:.1f} s, same command again {second:.1f} s "
            f"({second / first:.0%}) | reused {facts['jobs_reused']}/{facts['jobs_done']} | "
            f"planner calls run: {facts['planner_calls_run']} | "
            f"server started: {facts['prefect_server_started']}"
        )
        if args.keep:
            print(f"  output: {out}")
        else:
            shutil.rmtree(out, ignore_errors=True)

    first_s, second_s = statistics.median(firsts), statistics.median(seconds)
    print()
    print(
        f"4-job TwoStep sweep: {first_s:.1f} s, its re-run {second_s:.1f} s "
        f"({second_s / first_s:.0%})"
        + (f" (medians of {args.repeats})" if args.repeats > 1 else "")
    )
    print(f"command: {shlex.join(['twostep', *GRID])} data.root=... output.root=<fresh>")
    return 0


if __name__ == "__main__":
    sys.exit(main())
