"""Orchestration benchmark: what Hydra + Prefect + MLflow add to each job of a sweep.

Runs a 20-job SA sweep (``twostep -m method=sa domain=blocksworld task=range(1,21)``,
basic launcher: one process, so imports are paid once) in a fresh output root, and
reads every job's record (``<sweep>/.twostep/jobs/*.json``). Per job:

    orchestration overhead = job wall time - server wait - fresh planner time - LLM time

where the job wall time runs from the job function's start to the end of its MLflow
logging. It includes reading and parsing the task (shown apart as ``parse``), the Prefect
flow and task runs, the job store and MLflow. The goal is a median under 0.5 s.
Reported apart: the import cost of each layer (fresh processes) and the Prefect server's
start-up on a fresh and on a warm database.

Variants: ``prefect+mlflow`` (the default configuration) and ``library+mlflow``
(``orchestration.prefect=false``), which shows Prefect's share.

    .venv/bin/python bench/bench_orchestration.py                 # both variants, 20 jobs
    .venv/bin/python bench/bench_orchestration.py --jobs 10 --variants prefect+mlflow

If this environment turns Python's bytecode cache off (``PYTHONDONTWRITEBYTECODE``), every
import compiles from source, several times slower than any normal install: the bench
then lets its own subprocesses cache bytecode under its output folder
(``PYTHONPYCACHEPREFIX``; the venv is not touched). ``--as-is`` keeps the environment.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.prefect_server import server_startup
from tools import record

REPO = Path(__file__).resolve().parent.parent
TWOSTEP = Path(sys.executable).parent / "twostep"
VARIANTS = {
    "prefect+mlflow": [],
    "library+mlflow": ["orchestration.prefect=false"],
    "prefect-only": ["mlflow.enabled=false"],
}
IMPORTS = {
    "hydra app (flows.cli)": "import flows.cli",
    "prefect + flow (flows.prefect_flow)": "import flows.prefect_flow",
    "mlflow client": "from mlflow.tracking import MlflowClient",
    "twostep library (pipeline)": "import twostep.methods.twostep",
}


def environment(out: Path, as_is: bool) -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")
    env.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
    env.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    if not as_is and env.get("PYTHONDONTWRITEBYTECODE"):
        env.pop("PYTHONDONTWRITEBYTECODE")
        env["PYTHONPYCACHEPREFIX"] = str(out / "pycache")
    return env


def import_seconds(statement: str, env: dict[str, str], repeats: int) -> float:
    code = f"import time; t = time.perf_counter(); {statement}; print(time.perf_counter() - t)"
    times = []
    for _ in range(repeats):
        done = subprocess.run(
            [sys.executable, "-c", code],
            capture_output=True,
            text=True,
            env=env,
            cwd=REPO,
            check=True,
        )
        times.append(float(done.stdout.strip().splitlines()[-1]))
    return statistics.median(times)


def run_sweep(
    out: Path, data: Path, jobs: int, extra: list[str], env: dict[str, str]
) -> tuple[list[str], float, list[dict[str, Any]]]:
    command = [
        str(TWOSTEP), "-m", "method=sa", "domain=blocksworld", f"task=range(1,{jobs + 1})",
        f"data.root={data}", f"output.root={out}", "orchestration.progress=false", *extra,
    ]  # fmt: skip
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=REPO)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"sweep failed ({done.returncode}):\n{done.stdout}\n{done.stderr}")
    records = []
    for path in out.glob("multiruns/*/*/.twostep/jobs/*.json"):
        records.append(json.loads(path.read_text()))
    records.sort(key=lambda r: r["num"])
    return command, wall, records


def pct(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", type=Path, default=REPO / "data")
    parser.add_argument("--jobs", type=int, default=20)
    parser.add_argument(
        "--variants",
        nargs="*",
        default=["prefect+mlflow", "library+mlflow"],
        choices=list(VARIANTS),
    )
    parser.add_argument("--import-repeats", type=int, default=3)
    parser.add_argument("--as-is", action="store_true", help="keep PYTHONDONTWRITEBYTECODE")
    parser.add_argument("--keep", action="store_true", help="keep the output folder")
    parser.add_argument("--json", type=Path, help="also write what it prints as a record here")
    args = parser.parse_args()
    with record.capture(args.json, title="A sweep's orchestration cost"):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    if not (args.data / "blocksworld" / f"p{args.jobs:02d}.pddl").is_file():
        raise SystemExit(
            f"need blocksworld p01..p{args.jobs:02d} under {args.data} (twostep-data generate)"
        )
    out = Path(tempfile.mkdtemp(prefix="twostep-bench-orch-"))
    env = environment(out, args.as_is)
    print(f"# {' '.join(sys.argv)}")
    print(f"# output: {out}  load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    if "PYTHONPYCACHEPREFIX" in env and "PYTHONPYCACHEPREFIX" not in os.environ:
        print("# bytecode cache was off here: subprocesses cache it under the output folder")

    # Warm the bytecode cache and the disk before anything is timed.
    import_seconds("; ".join(IMPORTS.values()), env, 1)

    rows = []
    for variant in args.variants:
        command, wall, records = run_sweep(
            out / variant, args.data, args.jobs, VARIANTS[variant], env
        )
        overhead = [r["orchestration_overhead_s"] for r in records]
        rows.append(
            {
                "variant": variant,
                "jobs": len(records),
                "failed": sum(1 for r in records if r["status"] == "failed"),
                "sweep_s": wall,
                "job_s": statistics.median(r["job_wall_time_s"] for r in records),
                "planner_s": statistics.median(r["planner_wall_s"] for r in records),
                "parse_s": statistics.median(r.get("task_load_s", 0.0) for r in records),
                "overhead_s": statistics.median(overhead),
                "p90_s": pct(overhead, 0.9),
                "first_s": overhead[0],
                "server_wait_s": max(r["server_wait_s"] for r in records),
                "command": command,
            }
        )

    print()
    print(
        f"per-job orchestration overhead, {args.jobs}-job SA sweep (medians; goal: overhead < 0.5 s)"
    )
    header = (
        f"{'variant':<16} {'jobs':>4} {'fail':>4} {'sweep s':>8} {'job s':>6} {'planner':>7} "
        f"{'parse':>6} {'overhead':>8} {'p90':>6} {'1st job':>7} {'srv wait':>8}"
    )
    print(header)
    print("-" * len(header))
    for row in rows:
        print(
            f"{row['variant']:<16} {row['jobs']:>4} {row['failed']:>4} {row['sweep_s']:>8.1f} "
            f"{row['job_s']:>6.2f} {row['planner_s']:>7.2f} {row['parse_s']:>6.2f} "
            f"{row['overhead_s']:>8.2f} {row['p90_s']:>6.2f} {row['first_s']:>7.2f} "
            f"{row['server_wait_s']:>8.1f}"
        )
    print(
        "  overhead = job wall - server wait - fresh planner - LLM (includes parse); "
        "1st job: imports Prefect/MLflow lazily"
    )

    print()
    print(f"import cost in a fresh process (median of {args.import_repeats})")
    for name, statement in IMPORTS.items():
        print(f"  {name:<30} {import_seconds(statement, env, args.import_repeats):6.2f} s")

    print()
    print("Prefect server start-up (spawn to healthy API)")
    home = out / "server-home"
    print(f"  fresh database (migrations)    {server_startup(home, env):6.2f} s")
    print(f"  warm database                  {server_startup(home, env):6.2f} s")

    print()
    for row in rows:
        print(f"command ({row['variant']}): {shlex.join(row['command'])}")
    if not args.keep:
        import shutil

        shutil.rmtree(out, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
