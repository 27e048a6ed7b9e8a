"""Start-up benchmark: what one ``twostep method=sa domain=grippers task=9`` costs besides
planning, (a) as a default single run (library path, MLflow logging to SQLite) and (b)
with the long-lived services up (``twostep-services up``) and ``orchestration.prefect=true``
(the job is a Prefect flow on the warm server).

For each scenario, on a warm install (compiled venv: ``make setup``) and a warm store
(one run first, not counted):

* **command**: the real ``twostep`` console script, ``--repeat`` times
  (``orchestration.reuse_results=false``: the job is computed every time); wall time
  and the planner's wall time from result.json (``orchestration.planner_wall_s``).
  Goals: wall minus planner <= 3 s (a), <= 5 s (b).
* **breakdown**: the same job in a driver process timing its phases: Python start,
  imports of the ``twostep`` app, composing the config, reading the task, the planner,
  MLflow (import, store, logging), Prefect (import, flow and task runs), the rest.

    .venv/bin/python bench/bench_startup.py                 # both scenarios, 3 runs each
    .venv/bin/python bench/bench_startup.py --repeat 5 --scenarios default
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
JOB = ["method=sa", "domain=grippers", "task=9"]
GOALS = {"default": 3.0, "services": 5.0}

DRIVER = """
import json, sys, time
start = time.perf_counter()
from hydra import compose, initialize_config_dir
import flows.cli  # the app's own imports: Hydra, the schema, the job module
imported = time.perf_counter()
from flows.runner import execute_job
with initialize_config_dir(config_dir=sys.argv[1], version_base="1.3"):
    cfg = compose("config", overrides=sys.argv[3:])
composed = time.perf_counter()
outcome = execute_job(cfg, __import__("pathlib").Path(sys.argv[2]), tracking_worker=True)
done = time.perf_counter()
print(json.dumps({"imports": imported - start, "config": composed - imported,
                  "job": done - composed, "total": done - start, "status": outcome.status,
                  "timings": outcome.timings, "stats": outcome.stats.to_dict()}), flush=True)
import os; os._exit(0)  # as the twostep command ends a single run (flows.cli._fast_exit)
"""


def environment() -> dict[str, str]:
    env = dict(os.environ)
    env.update(
        MLFLOW_DISABLE_TELEMETRY="true",
        PREFECT_SERVER_ANALYTICS_ENABLED="false",
        LITELLM_LOCAL_MODEL_COST_MAP="True",
    )
    env.pop("PREFECT_API_URL", None)
    return env


def overrides(root: Path, extra: list[str]) -> list[str]:
    return [*JOB, f"output.root={root}", f"data.root={REPO / 'data'}", *extra]


def run_command(root: Path, extra: list[str]) -> tuple[float, float]:
    """(wall seconds, planner wall seconds) of one ``twostep`` run."""
    before = set(root.glob("runs/*/*/result.json"))
    start = time.perf_counter()
    done = subprocess.run(
        [str(BIN / "twostep"), *overrides(root, ["orchestration.reuse_results=false", *extra])],
        capture_output=True, text=True, env=environment(), cwd=REPO,
    )  # fmt: skip
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"twostep failed:\n{done.stdout}\n{done.stderr}")
    (result,) = set(root.glob("runs/*/*/result.json")) - before
    orchestration = json.loads(result.read_text())["orchestration"]
    return wall, float(orchestration["planner_wall_s"])


def run_driver(root: Path, extra: list[str], job_dir: Path) -> dict[str, Any]:
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", DRIVER, str(REPO / "conf"), str(job_dir),
         *overrides(root, ["orchestration.reuse_results=false", *extra])],
        capture_output=True, text=True, env=environment(), cwd=REPO,
    )  # fmt: skip
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"driver failed:\n{done.stdout}\n{done.stderr}")
    data: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    data["wall"] = wall
    return data


def breakdown(data: dict[str, Any]) -> dict[str, float]:
    timings, stats = data["timings"], data["stats"]
    planner = float(stats["planner_wall_s"])
    task = float(stats["task_load_s"])
    mlflow = float(timings.get("tracking_s", 0.0))
    prefect = max(0.0, float(timings.get("flow_wall_s", 0.0)) - planner - task)
    parts = {
        "python start + exit": data["wall"] - data["total"],
        "imports (app)": data["imports"],
        "config (compose)": data["config"],
        "task load": task,
        "planner": planner,
        "mlflow": mlflow,
        "prefect": prefect,
    }
    parts["rest (job store, files, checks)"] = max(
        0.0, data["job"] - task - planner - mlflow - prefect
    )
    return parts


def scenario(name: str, root: Path, extra: list[str], repeat: int) -> dict[str, Any]:
    run_command(root, extra)  # warm: the stores exist, the server knows the flow
    runs = [run_command(root, extra) for _ in range(repeat)]
    walls = [w for w, _ in runs]
    planners = [p for _, p in runs]
    overhead = statistics.median(w - p for w, p in runs)
    parts = [breakdown(run_driver(root, extra, root / f"driver-{i}")) for i in range(repeat)]
    median_parts = {k: statistics.median(p[k] for p in parts) for k in parts[0]}
    return {
        "scenario": name,
        "wall_s": statistics.median(walls),
        "planner_s": statistics.median(planners),
        "overhead_s": overhead,
        "goal_s": GOALS[name],
        "walls": walls,
        "breakdown": median_parts,
    }


def report(result: dict[str, Any]) -> str:
    met = "met" if result["overhead_s"] <= result["goal_s"] else "MISSED"
    lines = [
        f"== {result['scenario']}: twostep {' '.join(JOB)}",
        f"   wall {result['wall_s']:.2f} s (runs: "
        + ", ".join(f"{w:.2f}" for w in result["walls"])
        + f"), planner {result['planner_s']:.2f} s",
        f"   wall - planner = {result['overhead_s']:.2f} s (goal <= {result['goal_s']:.0f} s: {met})",
        "   breakdown (driver process, median):",
    ]
    for part, seconds in result["breakdown"].items():
        lines.append(f"     {part:<34} {seconds:6.2f} s")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--scenarios", default="default,services")
    parser.add_argument("--root", type=Path, default=None, help="output root (default: temp)")
    args = parser.parse_args()
    root = args.root or Path(tempfile.mkdtemp(prefix="bench-startup-"))
    wanted = args.scenarios.split(",")
    print(
        f"output root: {root} | PYTHONDONTWRITEBYTECODE={os.environ.get('PYTHONDONTWRITEBYTECODE')}"
    )
    results = []
    if "default" in wanted:
        results.append(scenario("default", root / "default", [], args.repeat))
        print(report(results[-1]), flush=True)
    if "services" in wanted:
        services_root = root / "services"
        start = time.perf_counter()
        subprocess.run(
            [str(BIN / "twostep-services"), "up", "--root", str(services_root)],
            check=True, env=environment(), cwd=REPO,
        )  # fmt: skip
        print(f"   (twostep-services up: {time.perf_counter() - start:.1f} s)")
        try:
            extra = ["orchestration.prefect=true"]
            results.append(scenario("services", services_root, extra, args.repeat))
            print(report(results[-1]), flush=True)
        finally:
            subprocess.run(
                [str(BIN / "twostep-services"), "down", "--root", str(services_root)],
                env=environment(), cwd=REPO,
            )  # fmt: skip
    (root / "bench_startup.json").write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
