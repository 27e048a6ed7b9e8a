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
  imports of the ``twostep`` app, composing the config, reading the task (from the
  parsed-task cache ``<output.root>/cache/tasks`` once the warm-up run filled it), the planner,
  MLflow (logging: waiting for the helper process that imports MLflow and logs through
  ``MlflowClient`` while the job runs), Prefect (import, flow and task runs), the rest (job key, job store,
  files, checks).
* **CPU**: user + system seconds of the command (with the processes it waits for: the
  planner, an MLflow helper; not a server's) and of the driver's phases. On a shared
  machine wall time depends on the load; CPU time much less.

(c) ``logged``: the default run on its warm store, each time a job the store has no run
for (a new seed), so that its MLflow run is created and logged (in (a) the job's run is
already in the store: a re-run computes the job again but logs nothing).

(d) ``cold``: the first run on a fresh ``output.root`` each time, whose MLflow store does
not exist yet (it is copied from the environment's template store, made by MLflow at
``make setup``, or, without one, created and migrated by MLflow).

(e) ``refusals``: a command the tool must refuse (a value out of range, an unknown task, a
typo'd key with and without ``+``, an unknown option), each on a fresh ``output.root``:
its wall time, exit code, whether anything was written (a folder under ``output.root``)
and its stderr line count. Goal: exit 2 in under 1 s, one line, nothing written.
``--source DIR`` runs another checkout's code (the console script's entry point
imported from DIR, this environment), e.g. the main branch's for a before/after.

    .venv/bin/python bench/bench_startup.py                 # default and services, 3 runs each
    .venv/bin/python bench/bench_startup.py --repeat 5 --scenarios default,logged,cold
    .venv/bin/python bench/bench_startup.py --repeat 3 --scenarios default,logged,cold,services \
        --json docs/bench/startup.json            # the results page's rows

    .venv/bin/python bench/bench_startup.py --repeat 5 --scenarios refusals [--source DIR]

``--json FILE`` also writes the scenarios' rows as a bench record (:mod:`tools.record`);
:func:`evaluation.pages.startup.page` turns it into the results page (``make results``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.pages.startup import GOALS, JOB, REFUSAL_GOAL_S
from flows.environment import DEFAULTS
from tools import record

REPO = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
DRIVER = """
import json, resource, sys, time
def cpu(who=resource.RUSAGE_SELF):
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime
start, start_cpu = time.perf_counter(), cpu()
from hydra import compose, initialize_config_dir
import flows.cli  # the app's own imports: Hydra, the schema, the job module
imported, imported_cpu = time.perf_counter(), cpu()
from flows.job import execute_job
with initialize_config_dir(config_dir=sys.argv[1], version_base="1.3"):
    cfg = compose("config", overrides=sys.argv[3:])
composed, composed_cpu = time.perf_counter(), cpu()
outcome = execute_job(cfg, __import__("pathlib").Path(sys.argv[2]), tracking_worker=True)
done, done_cpu = time.perf_counter(), cpu()
print(json.dumps({"imports": imported - start, "config": composed - imported,
                  "job": done - composed, "total": done - start, "status": outcome.status,
                  "cpu": {"imports": imported_cpu - start_cpu, "config": composed_cpu - imported_cpu,
                          "job": done_cpu - composed_cpu, "total": done_cpu - start_cpu,
                          "children": cpu(resource.RUSAGE_CHILDREN)},
                  "timings": outcome.timings, "stats": outcome.stats.to_dict()}), flush=True)
import os; os._exit(0)  # as the twostep command ends a single run (flows.cli._fast_exit)
"""


def environment() -> dict[str, str]:
    env = {**os.environ, **DEFAULTS}  # the offline-safe settings, as the command sets them
    env.pop("PREFECT_API_URL", None)
    return env


def overrides(root: Path, extra: list[str]) -> list[str]:
    return [*JOB, f"output.root={root}", f"data.root={REPO / 'data'}", *extra]


def children_cpu() -> float:
    """CPU seconds (user + system) of this process's finished children so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_command(root: Path, extra: list[str]) -> tuple[float, float, float]:
    """(wall seconds, planner wall seconds, CPU seconds) of one ``twostep`` run; the CPU
    time includes the processes it waits for (planner, MLflow worker), not a server's."""
    before = set(root.glob("runs/*/*/result.json"))
    start, start_cpu = time.perf_counter(), children_cpu()
    done = subprocess.run(
        [str(BIN / "twostep"), *overrides(root, ["orchestration.reuse_results=false", *extra])],
        capture_output=True, text=True, env=environment(), cwd=REPO,
    )  # fmt: skip
    wall, cpu = time.perf_counter() - start, children_cpu() - start_cpu
    if done.returncode != 0:
        raise SystemExit(f"twostep failed:\n{done.stdout}\n{done.stderr}")
    (result,) = set(root.glob("runs/*/*/result.json")) - before
    orchestration = json.loads(result.read_text())["orchestration"]
    return wall, float(orchestration["planner_wall_s"]), cpu


def run_driver(root: Path, extra: list[str], job_dir: Path) -> dict[str, Any]:
    start, start_cpu = time.perf_counter(), children_cpu()
    done = subprocess.run(
        [sys.executable, "-c", DRIVER, str(REPO / "conf"), str(job_dir),
         *overrides(root, ["orchestration.reuse_results=false", *extra])],
        capture_output=True, text=True, env=environment(), cwd=REPO,
    )  # fmt: skip
    wall, cpu = time.perf_counter() - start, children_cpu() - start_cpu
    if done.returncode != 0:
        raise SystemExit(f"driver failed:\n{done.stdout}\n{done.stderr}")
    data: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    data["wall"], data["cpu"]["process"] = wall, cpu
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


def cpu_breakdown(data: dict[str, Any]) -> dict[str, float]:
    """CPU seconds (user + system) by phase: what shared load does not inflate."""
    cpu = data["cpu"]
    return {
        "python start + exit": max(0.0, cpu["process"] - cpu["total"] - cpu["children"]),
        "imports (app)": cpu["imports"],
        "config (compose)": cpu["config"],
        "job, this process": cpu["job"],
        "job, child processes (planner, ...)": cpu["children"],
        "total": cpu["process"],
    }


def scenario(name: str, root: Path, extra: list[str], repeat: int) -> dict[str, Any]:
    run_command(root, extra)  # warm: the stores exist, the server knows the flow
    runs = [run_command(root, extra) for _ in range(repeat)]
    walls = [w for w, _, _ in runs]
    planners = [p for _, p, _ in runs]
    overhead = statistics.median(w - p for w, p, _ in runs)
    drivers = [run_driver(root, extra, root / f"driver-{i}") for i in range(repeat)]
    parts = [breakdown(d) for d in drivers]
    cpu_parts = [cpu_breakdown(d) for d in drivers]
    return {
        "scenario": name,
        "wall_s": statistics.median(walls),
        "planner_s": statistics.median(planners),
        "overhead_s": overhead,
        "cpu_s": statistics.median(c for _, _, c in runs),
        "cpus": [c for _, _, c in runs],
        "goal_s": GOALS[name],
        "walls": walls,
        "breakdown": {k: statistics.median(p[k] for p in parts) for k in parts[0]},
        "cpu_breakdown": {k: statistics.median(p[k] for p in cpu_parts) for k in cpu_parts[0]},
    }


def report(result: dict[str, Any]) -> str:
    met = "met" if result["overhead_s"] <= result["goal_s"] else "MISSED"
    lines = [
        f"== {result['scenario']}: twostep {' '.join(JOB)}",
        f"   wall {result['wall_s']:.2f} s (runs: "
        + ", ".join(f"{w:.2f}" for w in result["walls"])
        + f"), planner {result['planner_s']:.2f} s",
        f"   wall - planner = {result['overhead_s']:.2f} s (goal <= {result['goal_s']:.0f} s: {met})",
        f"   CPU {result['cpu_s']:.2f} s, planner included (runs: "
        + ", ".join(f"{c:.2f}" for c in result["cpus"])
        + f") | load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores",
        "   breakdown (driver process, median):  wall",
    ]
    for part, seconds in result["breakdown"].items():
        lines.append(f"     {part:<36} {seconds:6.2f} s")
    lines.append("   CPU (driver process, median):")
    for part, seconds in result["cpu_breakdown"].items():
        lines.append(f"     {part:<36} {seconds:6.2f} s")
    return "\n".join(lines)


def runs_against_goal(
    name: str, title: str, runs: list[tuple[float, float, float]]
) -> dict[str, Any]:
    """Print a scenario's median wall - planner time against the default goal; its row."""
    overhead = statistics.median(w - p for w, p, _ in runs)
    met = "met" if overhead <= GOALS["default"] else "MISSED"
    print(
        f"== {name}: {title}\n"
        f"   wall - planner = {overhead:.2f} s (goal <= {GOALS['default']:.0f} s: {met});"
        " runs: "
        + ", ".join(f"{w:.2f} s wall, {p:.2f} s planner, {c:.2f} s CPU" for w, p, c in runs)
        + f" | load average {os.getloadavg()[0]:.1f}",
        flush=True,
    )
    return {"scenario": name, "overhead_s": overhead, "runs": runs}


# Commands the tool must refuse before any work (issue 37), with what the refusal names.
REFUSALS: tuple[tuple[str, ...], ...] = (
    ("task=99",),
    ("agents=0",),
    ("score_mode=bogus",),
    ("agnets=2",),
    ("+agnets=3", "method=twostep", "decomposer=goal-split"),
    ("domain=nosuch",),
)
# The `twostep` console script's entry point, imported from the current directory (the
# checkout the refusals scenario runs).
RUN_COMMAND = "import sys; sys.argv[0] = 'twostep'; from flows.command import main; main()"


def refusals(root: Path, repeat: int, source: Path) -> dict[str, Any]:
    """Wall time, exit code, stderr lines and what was written, per refused command."""
    rows = []
    for arguments in REFUSALS:
        walls, cpus, codes, lines, written = [], [], set(), set(), False
        for attempt in range(repeat):
            out = root / f"refused-{len(rows)}-{attempt}"
            command = [sys.executable, "-c", RUN_COMMAND, *arguments]
            command += [f"output.root={out}", f"data.root={REPO / 'data'}"]
            start, start_cpu = time.perf_counter(), children_cpu()
            done = subprocess.run(
                command, capture_output=True, text=True, env=environment(), cwd=source
            )
            walls.append(time.perf_counter() - start)
            cpus.append(children_cpu() - start_cpu)  # with the MLflow helper it stopped
            codes.add(done.returncode)
            lines.add(len([line for line in done.stderr.splitlines() if line.strip()]))
            written |= out.exists()
        median = statistics.median(walls)
        met = "met" if median < REFUSAL_GOAL_S and codes == {2} and not written else "MISSED"
        print(
            f"   {' '.join(arguments):<50} exit {sorted(codes)}, {max(lines)} stderr line(s), "
            f"{'WROTE under output.root' if written else 'nothing written'}, median "
            f"{median:.2f} s ({', '.join(f'{w:.2f}' for w in walls)}), CPU "
            f"{statistics.median(cpus):.2f} s: {met}",
            flush=True,
        )
        rows.append({"command": list(arguments), "walls": walls, "cpus": cpus,
                     "codes": sorted(codes), "lines": max(lines), "written": written})  # fmt: skip
    return {"scenario": "refusals", "source": str(source), "rows": rows}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--scenarios", default="default,services")
    parser.add_argument("--root", type=Path, default=None, help="output root (default: temp)")
    parser.add_argument("--json", type=Path, help="also write the rows here (a bench record)")
    parser.add_argument(
        "--source", type=Path, default=REPO, help="refusals: the checkout whose code runs"
    )
    args = parser.parse_args()
    run = record.started()
    root = args.root or Path(tempfile.mkdtemp(prefix="bench-startup-"))
    root.mkdir(parents=True, exist_ok=True)
    wanted = args.scenarios.split(",")
    print(
        f"output root: {root} | PYTHONDONTWRITEBYTECODE={os.environ.get('PYTHONDONTWRITEBYTECODE')}"
    )
    results = []
    if "default" in wanted:
        results.append(scenario("default", root / "default", [], args.repeat))
        print(report(results[-1]), flush=True)
    if "logged" in wanted:
        logged_root = root / "default"
        run_command(logged_root, [])  # the store exists (as after (a))
        runs = [run_command(logged_root, [f"seed={1000 + i}"]) for i in range(args.repeat)]
        title = "a job new to the warm store (its MLflow run created and logged)"
        results.append(runs_against_goal("logged", title, runs))
    if "cold" in wanted:
        runs = [run_command(root / f"cold-{i}", []) for i in range(args.repeat)]
        title = "the first run on a fresh output.root (the MLflow store is new)"
        results.append(runs_against_goal("cold", title, runs))
    if "refusals" in wanted:
        print(
            f"== refusals: exit 2 in under {REFUSAL_GOAL_S:.0f} s, one line, nothing written "
            f"(code of {args.source}; load average {os.getloadavg()[0]:.1f})",
            flush=True,
        )
        results.append(refusals(root, args.repeat, args.source))
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
    if args.json:
        record.write(args.json, run, results, job=JOB, repeat=args.repeat, goals=GOALS)
    return 0


if __name__ == "__main__":
    sys.exit(main())
