"""Sweep benchmark: what a user waits for in a ``twostep -m`` sweep, end to end.

Runs sweeps of small jobs (SA and TwoStep on the smallest blocksworld and grippers tasks, so
that orchestration dominates) through the ``twostep`` command as a user runs it, each in a
fresh output root, and reads every job's record (``<sweep>/.twostep/jobs/*.json``). For
each sweep it prints:

* the total wall time (the command, start to exit), the planner's own time summed over the
  jobs (the wall time of every fresh Fast Downward call), jobs per minute;
* **per job beyond planning**: the time a job held its worker (from the previous job's end
  on the same worker to its own end) minus its planner time; median and p90 over the jobs,
  the first job of each worker apart (it also pays the worker's start and first imports);
* where a job's time goes (medians): composing its config, Hydra's ``run_job`` before the
  app, the app's setup (config, key, checks, job store lookup), reading the task, the
  planner, the method's own steps (with Prefect: its flow and task runs and their API
  calls), saving to the job store, writing its files, MLflow logging, and what is left
  between two jobs of a worker (the sweep record, the progress line, Hydra's job end);
* growth: the overhead's trend over the sweep (seconds per 100 jobs, least squares), and
  across sweep sizes.

Variants: Prefect on/off x MLflow on/off (``on``: both, ``prefect``, ``mlflow``, ``off``), launchers
``basic`` (Hydra's: one process), ``one`` (the twostep launcher with ``n_jobs=1``) and
``all`` (the default: every core), ``w1``/``w2`` (n_jobs 1 and 2: jobs/minute), ``dask2``
(a local Dask cluster of 2 worker processes). Also the start of a fresh Prefect server
(a new output root) and of a warm one. ``--profile`` adds a cProfile of one sweep's jobs,
time by package (Hydra/OmegaConf, Prefect, MLflow, the library, waits).

    .venv/bin/python bench/bench_sweep.py --save docs/bench/sweep.txt --json docs/bench/sweep.json
    .venv/bin/python bench/bench_sweep.py --jobs 20 100 400 --variants on off --launchers all basic \
        --basic-max-jobs 20 --on-max-jobs 400 --no-small-scaling \
        --save docs/bench/sweep.txt --json docs/bench/sweep.json        # the docs' run (shared machine)
    .venv/bin/python bench/bench_sweep.py --quick                      # 20 and 100 jobs, fewer variants
    .venv/bin/python bench/bench_sweep.py --jobs 100 --variants on off --launchers all one

Every line it prints goes to ``--save`` too (the command first), and one JSON row per sweep
to ``--json``. The machine, its load average before and after every sweep, and each sweep's
command are printed with the figures: on a shared machine the load says what they are worth.

If this environment turns Python's bytecode cache off (``PYTHONDONTWRITEBYTECODE``), every
process compiles twostep's own modules from source; as for any normal install, the sweeps
here cache bytecode (``__pycache__`` beside the sources, git-ignored; ``--as-is`` keeps the
environment). A first sweep with Prefect and MLflow on (not timed) warms that cache.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import pstats
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from evaluation.pages.sweep import targets  # noqa: E402
from evaluation.prefect_server import server_startup  # noqa: E402
from tools import record as bench_record  # noqa: E402

TWOSTEP = Path(sys.executable).parent / "twostep"
COMMAND = TWOSTEP  # --command: another build's twostep (e.g. to compare two versions)
VARIANTS = {  # Prefect and MLflow: both on (the default), one of them, none
    "on": [],
    "prefect": ["mlflow.enabled=false"],
    "mlflow": ["orchestration.prefect=false"],
    "off": ["orchestration.prefect=false", "mlflow.enabled=false"],
}
LAUNCHERS = {
    "all": [],  # the default: the twostep launcher on every core
    "one": ["hydra.launcher.n_jobs=1"],
    "basic": ["hydra/launcher=basic"],
    "w1": ["hydra.launcher.n_jobs=1"],
    "w2": ["hydra.launcher.n_jobs=2"],
    "dask2": ["hydra.launcher.backend=dask", "hydra.launcher.n_jobs=2"],
}
PHASES = (
    "compose",
    "hydra",
    "setup",
    "task",
    "planner",
    "steps",
    "store",
    "files",
    "mlflow",
    "between",
    "cpu",
)
# Jobs where the planner dominates: termes SA on its slowest tasks (1-17 s of Fast Downward
# each here), each with three time limits that all let it finish (distinct jobs and planner
# cache keys: every job plans). 15 jobs.
PLANNER_GRID = ["domain=termes", "method=sa", "task=5,6,9,10,14", "planner.time_limit_s=60,61,62"]


def paper_grid(domain: str) -> list[str]:
    """The paper's grid (``experiment=paper``: 20 tasks x N = 1..4 x SA, MA, TwoStep x 3
    seeds) on one domain, offline: ``lama-first`` and plan-deal stand in for anytime LAMA
    and TwoStep with GPT-4o. 720 jobs; SA's and the planner's repeats over N and the seeds
    are the planner cache's, as in the paper's grid."""
    return ["experiment=paper", f"domain={domain}", "planner=lama-first", "method=sa,ma,plan-deal"]


def grid(jobs: int) -> list[str]:
    """A grid of exactly ``jobs`` small jobs: 2 domains x {SA, TwoStep} x tasks x seeds, the
    seed varying slowest (Hydra's order is the command line's): every block of jobs is the
    same mix, so a trend over the sweep is growth, not a change of jobs."""
    if jobs % 4:
        raise SystemExit(f"--jobs {jobs}: a multiple of 4 (2 domains x 2 methods x tasks x seeds)")
    cells = jobs // 4
    tasks = next(t for t in (10, 5, 4, 2, 1) if cells % t == 0 and cells // t <= 40)
    seeds = cells // tasks
    return [
        f"seed=range(0,{seeds})",
        "domain=blocksworld,grippers",
        "method=sa,plan-deal",
        f"task=range(1,{tasks + 1})",
        "agents=2",
    ]


def machine() -> dict[str, Any]:
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    memory = ""
    try:
        kb = int(Path("/proc/meminfo").read_text().split()[1])
        memory = f"{kb / 1024**2:.0f} GB"
    except (OSError, ValueError, IndexError):
        pass
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count() or 1
    return {
        "cpu": model,
        "cores": cores,
        "memory": memory,
        "python": platform.python_version(),
        "system": f"{platform.system()} {platform.release()}",
    }


def load() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


def environment(folder: Path, as_is: bool) -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")
    env.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
    env.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    env.pop("PREFECT_API_URL", None)
    if not as_is:  # as any normal install: compiled modules are cached (next to them)
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def adopt_orphans() -> None:
    """Linux: processes the sweep leaves to run on their own (its Prefect server's
    watchdog) become this process's children when their parent ends, so that their CPU
    time is counted with the sweep's (:func:`children_cpu`)."""
    if sys.platform.startswith("linux"):
        import ctypes

        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(36, 1)  # PR_SET_CHILD_SUBREAPER


def children_cpu() -> float:
    """CPU seconds (user + system) of every finished descendant, after reaping any left."""
    import resource

    while True:
        try:
            pid, _ = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            break
        if pid == 0:
            break
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_sweep(
    root: Path, jobs: int | list[str], extra: list[str], env: dict[str, str], data: Path | None
) -> dict[str, Any]:
    """One sweep (``jobs``: a number of small jobs, or a grid) in a fresh output root."""
    overrides = grid(jobs) if isinstance(jobs, int) else list(jobs)
    command = [str(COMMAND), "-m", *overrides, f"output.root={root}", *extra]
    if data is not None:
        command.append(f"data.root={data}")
    before = load()
    cpu_before = children_cpu()
    start = time.time()
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=root.parent)
    wall = time.time() - start
    after = load()
    time.sleep(0.5)  # the server's watchdog ends after the command; reap it
    cpu = children_cpu() - cpu_before
    if done.returncode != 0:
        tail = "\n".join((done.stdout + done.stderr).splitlines()[-15:])
        raise SystemExit(f"sweep failed ({done.returncode}): {shlex.join(command)}\n{tail}")
    (sweep,) = root.glob("multiruns/*/*/.twostep/sweep.json")
    state = json.loads(sweep.read_text())
    records = [json.loads(p.read_text()) for p in sweep.parent.glob("jobs/*.json")]
    summary = json.loads((sweep.parent / "summary.json").read_text())
    if isinstance(jobs, int) and len(records) != jobs:
        raise SystemExit(f"{len(records)} job records for {jobs} jobs: {shlex.join(command)}")
    shown = [str(TWOSTEP.name), *command[1:]]
    return {
        "command": shlex.join(shown),
        "wall_s": wall,
        "start": start,
        "state": state,
        "summary": summary,
        "records": records,
        "load_before": before,
        "load_after": after,
        "cpu_s": cpu,
    }


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def slope_per_100(values: list[float]) -> float:
    """Least-squares trend of ``values`` over their order, in seconds per 100 jobs."""
    n = len(values)
    if n < 3:
        return 0.0
    mean_x, mean_y = (n - 1) / 2, statistics.fmean(values)
    num = sum((i - mean_x) * (v - mean_y) for i, v in enumerate(values))
    den = sum((i - mean_x) ** 2 for i in range(n))
    return 100 * num / den


def analyse(run: dict[str, Any]) -> dict[str, Any]:
    """The figures of one sweep from its job records (see the module docstring)."""
    records = sorted(run["records"], key=lambda r: r["finished_at"])
    started = run["start"]
    by_worker: dict[Any, list[dict[str, Any]]] = defaultdict(list)
    for record in records:
        by_worker[(record.get("launch") or {}).get("worker")].append(record)
    rows = []
    for worker_records in by_worker.values():
        previous = None
        for record in worker_records:
            planner = float(record.get("planner_wall_s") or 0) + float(
                record.get("llm_wall_s") or 0
            )
            end = float(record["finished_at"])
            slot = end - (previous["finished_at"] if previous else started)
            phases = dict(record.get("phases") or {})
            launch = record.get("launch") or {}
            job_start = end - float(record["job_wall_time_s"])
            compose = float(launch.get("compose_s") or 0.0)
            launched = launch.get("launched_at")
            hydra: float | None
            between: float | None
            if launched is not None:
                hydra = max(0.0, job_start - float(launched) - compose)
                between = float(launched) - previous["finished_at"] if previous else None
            else:  # another launcher: Hydra's part is what is left between two jobs
                hydra, between = None, None
            task = float(record.get("task_load_s") or 0.0)
            compute = float(phases.get("compute_s", 0.0))
            rows.append(
                {
                    "num": record["num"],
                    "first": previous is None,
                    "slot_s": slot,
                    "planner_s": planner,
                    "overhead_s": slot - planner,
                    "reused": bool(record.get("reused")),
                    "compose": compose if launched is not None else None,
                    "hydra": hydra,
                    "setup": phases.get("setup_s"),
                    "task": task,
                    "planner": planner,
                    "steps": max(
                        0.0, compute - task - planner - float(record.get("server_wait_s") or 0)
                    ),
                    "store": phases.get("store_s"),
                    "files": phases.get("files_s"),
                    "mlflow": phases.get("mlflow_s"),
                    "between": between,
                    "cpu": launch.get("cpu_s"),
                    "server_wait_s": float(record.get("server_wait_s") or 0.0),
                }
            )
            previous = record
    steady = [r for r in rows if not r["first"]] or rows
    overhead = [r["overhead_s"] for r in steady]
    in_order = [r["overhead_s"] for r in sorted(steady, key=lambda r: r["num"])]
    firsts = [r for r in rows if r["first"]]
    finishes = sorted(float(r["finished_at"]) for r in records)
    planner_total = sum(r["planner_s"] for r in rows)
    phase_medians = {}
    for phase in PHASES:
        values = [r[phase] for r in steady if r.get(phase) is not None]
        phase_medians[phase] = statistics.median(values) if values else None
    workers = len(by_worker)
    wall = run["wall_s"]
    return {
        "jobs": len(records),
        "workers": workers,
        "wall_s": wall,
        "sweep_wall_s": run["summary"].get("sweep_wall_time_s"),
        "planner_total_s": planner_total,
        "overhead_median_s": statistics.median(overhead),
        "overhead_p90_s": percentile(overhead, 0.9),
        "first_job_s": min(float(r["slot_s"]) for r in firsts) if firsts else None,
        "first_job_overhead_s": statistics.median(r["overhead_s"] for r in firsts)
        if firsts
        else None,
        "end_to_end_per_job_s": (wall - planner_total / max(1, workers)) / len(records),
        "trend_s_per_100_jobs": slope_per_100(in_order),
        "jobs_per_minute": 60 * len(records) / wall,
        "cpu_s": run["cpu_s"],
        "cpu_per_job_s": (run["cpu_s"] - planner_total) / len(records),
        "steady_jobs_per_minute": (
            60 * (len(finishes) - 1) / (finishes[-1] - finishes[0]) if len(finishes) > 2 else None
        ),
        "after_last_job_s": run["start"] + wall - finishes[-1],
        "server_wait_max_s": max(r["server_wait_s"] for r in rows),
        # each job (in job order): its overhead, its phases (the growth, the profile)
        "series": [
            {k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()}
            for r in sorted(rows, key=lambda r: r["num"])
        ],
        "reused": sum(1 for r in rows if r["reused"]),
        "failed": run["summary"].get("jobs_failed"),
        "phases": phase_medians,
    }


CATEGORIES = (  # (what, path fragments), first match wins
    ("planner (Fast Downward, waited for)", ("/twostep/planner/",)),
    ("Hydra: compose, run_job, launch", ("/hydra/", "/omegaconf/", "/antlr4/", "/flows/compose", "/flows/run_job", "/flows/launcher")),
    ("Prefect: flow and task runs, API calls", ("/prefect/",)),
    ("MLflow: client, SQLite store", ("/mlflow/", "/sqlalchemy/", "/alembic/")),
    ("job store, job records", ("/flows/store", "/flows/sweep_state", "/twostep/util/files", "/flows/identity")),
    ("the library: task, method, scoring", ("/twostep/",)),
    ("the app and the rest of flows/", ("/flows/",)),
)  # fmt: skip


def _category(function: tuple[str, int, str]) -> str | None:
    path = function[0]
    return next((what for what, parts in CATEGORIES if any(p in path for p in parts)), None)


def profile_table(folder: Path) -> list[tuple[str, float]]:
    """The profiled jobs' time by what it was spent on: each function's own time goes to
    its package's line (:data:`CATEGORIES`); the time of Python's own and third-party
    helpers (waiting on a socket or a process, copying, JSON, YAML) goes to the callers
    that called them, in proportion, up to the first that has a line: waiting for the
    planner's process is the planner's, an HTTP call's reply is Prefect's."""
    files = [str(p) for p in folder.glob("*.prof")]
    if not files:
        return []
    stats = pstats.Stats(*files).stats  # type: ignore[attr-defined]
    unknown = "other (unattributed)"
    fixed = {f: _category(f) for f in stats if f[0] != "~"}
    shares: dict[Any, dict[str, float]] = {
        f: {category: 1.0} for f, category in fixed.items() if category is not None
    }
    # the others' callers by their time in the function (a function calling itself left out)
    weights = {}
    for function, (_, _, _, _, callers) in stats.items():
        if function in shares:
            continue
        callers = {c: t[3] for c, t in callers.items() if c != function and c in stats}
        total = sum(callers.values())
        weights[function] = {c: v / total for c, v in callers.items()} if total > 0 else {}
    for _ in range(60):  # each round passes the callers' shares one call further down
        updated = {}
        for function, callers in weights.items():
            result: dict[str, float] = defaultdict(float)
            for caller, weight in callers.items():
                for what, part in shares.get(caller, {}).items():
                    result[what] += part * weight
            updated[function] = dict(result)
        shares.update(updated)
    totals: dict[str, float] = defaultdict(float)
    for function, (_, _, own, _, _) in stats.items():
        known = shares.get(function, {})
        for what, part in known.items():
            totals[what] += own * part
        totals[unknown] += own * max(0.0, 1.0 - sum(known.values()))
    return sorted(totals.items(), key=lambda item: -item[1])


def grid_line(row: dict[str, Any]) -> str:
    """A paper-grid sweep in one line, from the timing its own summary reports."""
    t = row["timing"]
    return (
        f"{t['jobs']} jobs, {t['workers']} workers: wall {t['wall_s'] / 60:.1f} min, Fast "
        f"Downward {t['planner_s'] / 60:.1f} min over the jobs, beyond it "
        f"{t['beyond_per_job_s']:.2f} s per job ({100 * t['overhead_share']:.0f} % of the "
        f"workers' time), {row['jobs_per_minute']:.0f} jobs/min  load "
        f"{row['load_before'][0]:.1f}/{row['load_after'][0]:.1f}"
    )


class Report:
    def __init__(self, save: Path | None) -> None:
        self.lines: list[str] = []
        self.save = save

    def __call__(self, line: str = "") -> None:
        print(line, flush=True)
        self.lines.append(line)
        self.write()  # as it goes: a run cut short keeps what it measured

    def write(self) -> None:
        if self.save is not None:
            self.save.parent.mkdir(parents=True, exist_ok=True)
            self.save.write_text("\n".join(self.lines) + "\n")


def fmt(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--jobs", type=int, nargs="*", default=[20, 100, 400])
    parser.add_argument("--variants", nargs="*", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument(
        "--launchers", nargs="*", default=["all", "one", "basic"], choices=list(LAUNCHERS)
    )
    parser.add_argument(
        "--scaling", nargs="*", default=["w1", "w2", "dask2"], choices=list(LAUNCHERS),
        help="launchers for jobs/minute (Prefect and MLflow on, the middle sweep size)",
    )  # fmt: skip
    parser.add_argument("--on-max-jobs", type=int, default=None,
                        help="Prefect and MLflow on (and one of them) only up to this many jobs")  # fmt: skip
    parser.add_argument("--no-small-scaling", dest="small_scaling", action="store_false",
                        help="the workers' scaling on the planner-dominated jobs only")  # fmt: skip
    parser.add_argument("--basic-max-jobs", type=int, default=100,
                        help="Hydra's basic launcher only up to this many jobs (it is slow)")  # fmt: skip
    parser.add_argument("--quick", action="store_true", help="20 and 100 jobs, fewer variants")
    parser.add_argument("--no-planner-grid", dest="planner_grid", action="store_false",
                        help="no workers' scaling on planner-dominated jobs")  # fmt: skip
    parser.add_argument("--profile", action="store_true", help="cProfile one sweep's jobs")
    parser.add_argument(
        "--paper-grid",
        nargs="*",
        default=[],
        metavar="DOMAIN",
        help="also run the paper's grid on these domains (experiment=paper, 720 jobs each, "
        "lama-first and plan-deal subgoals): its wall, planner and overhead share",
    )
    parser.add_argument("--servers", type=int, default=2, help="fresh/warm Prefect starts to time")
    parser.add_argument(
        "--data", type=Path, default=None, help="data.root (default: the package's)"
    )
    parser.add_argument("--save", type=Path, default=None, help="the report, command first")
    parser.add_argument("--json", type=Path, default=None, help="one JSON row per sweep")
    parser.add_argument("--keep", action="store_true", help="keep the output roots")
    parser.add_argument("--as-is", action="store_true", help="keep PYTHONDONTWRITEBYTECODE")
    parser.add_argument("--command", type=Path, default=TWOSTEP, help="the twostep to run")
    args = parser.parse_args()
    global COMMAND
    COMMAND = args.command
    if args.quick:
        args.jobs = [20, 100]
        args.launchers = ["all", "one"]
        args.scaling = ["w1", "w2"]
        args.servers = 1

    run_record = bench_record.started()
    out = Report(args.save)
    out(f"# {shlex.join(['python', *sys.argv])}")
    folder = Path(tempfile.mkdtemp(prefix="twostep-bench-sweep-"))
    adopt_orphans()
    env = environment(folder, args.as_is)
    host = machine()
    out(
        f"# machine: {host['cpu'] or 'unknown CPU'}, {host['cores']} cores, {host['memory']}, "
        f"Python {host['python']}, {host['system']}"
    )
    out(f"# started {time.strftime('%Y-%m-%d %H:%M:%S')}, load average {load()} (1, 5, 15 min)")
    if os.environ.get("PYTHONDONTWRITEBYTECODE") and "PYTHONDONTWRITEBYTECODE" not in env:
        out("# bytecode cache was off here (PYTHONDONTWRITEBYTECODE): the sweeps cache it")
    rows: list[dict[str, Any]] = []

    def sweep(
        jobs: int | list[str], variant: str, launcher: str, tag: str = "", kind: str = "planner"
    ) -> dict[str, Any]:
        size = jobs if isinstance(jobs, int) else "grid"
        root = folder / f"{variant}-{launcher}-{size}{tag}" / "outputs"
        root.parent.mkdir(parents=True, exist_ok=True)
        run = run_sweep(root, jobs, VARIANTS[variant] + LAUNCHERS[launcher], env, args.data)
        row = {
            "jobs_requested": size,
            "grid": "small" if isinstance(jobs, int) else kind,
            "variant": variant,
            "prefect": "orchestration.prefect=false" not in VARIANTS[variant],
            "mlflow": "mlflow.enabled=false" not in VARIANTS[variant],
            "launcher": launcher,
            "command": run["command"],
            "load_before": run["load_before"],
            "load_after": run["load_after"],
            "machine": host,
            "date": time.strftime("%Y-%m-%d %H:%M:%S"),
            "timing": run["summary"].get("timing"),  # the sweep's own timing line
            **analyse(run),
        }
        rows.append(row)
        if not args.keep:
            shutil.rmtree(root.parent, ignore_errors=True)
        return row

    # Warm the bytecode cache and the disk (nothing timed).
    sweep(4, "on", "basic", "-warmup")
    rows.clear()

    out()
    out("## Prefect server start (the sweep's kind: no UI, idle services off)")
    for i in range(args.servers):
        home = folder / f"server-{i}"
        fresh, before = server_startup(home, env), load()
        warm = server_startup(home, env)
        out(f"  fresh database {fresh:5.1f} s, warm {warm:5.1f} s   (load average {before})")
        rows.append({"kind": "prefect_server", "fresh_s": fresh, "warm_s": warm,
                     "load_before": before, "machine": host})  # fmt: skip

    out()
    out("## Sweeps: per job beyond planning (s), where it goes (medians, s)")
    out(
        "   overhead = time a job held its worker - its planner time (median, p90; the first "
        "job of each worker apart); e2e = (wall - planner/workers) / jobs"
    )
    header = (
        f"{'jobs':>4} {'P M':>3} {'launcher':<8} {'wrk':>3} {'wall s':>7} {'plan s':>7} "
        f"{'med':>5} {'p90':>5} {'1st':>5} {'end':>5} {'e2e':>5} {'trend':>6} {'j/min':>6} {'cpu/j':>5} "
        + " ".join(f"{p[:7]:>7}" for p in PHASES)
        + "  load before/after"
    )
    out(header)
    out("-" * len(header))

    def show(row: dict[str, Any]) -> None:
        flags = ("P" if row["prefect"] else "-") + ("M" if row["mlflow"] else "-")
        phases = " ".join(f"{fmt(row['phases'].get(p), 3):>7}" for p in PHASES)
        out(
            f"{row['jobs']:>4} {flags:>3} {row['launcher']:<8} {row['workers']:>3} "
            f"{row['wall_s']:>7.1f} {row['planner_total_s']:>7.1f} "
            f"{row['overhead_median_s']:>5.2f} {row['overhead_p90_s']:>5.2f} "
            f"{fmt(row['first_job_s'], 1):>5} {row['after_last_job_s']:>5.1f} "
            f"{row['end_to_end_per_job_s']:>5.2f} "
            f"{row['trend_s_per_100_jobs']:>+6.3f} {row['jobs_per_minute']:>6.0f} "
            f"{row['cpu_per_job_s']:>5.2f} {phases}"
            f"  {row['load_before'][0]:.1f}/{row['load_after'][0]:.1f}"
        )

    def sizes(chosen: list[int]) -> None:
        for jobs in chosen:
            for variant in args.variants:
                if variant != "off" and args.on_max_jobs and jobs > args.on_max_jobs:
                    continue
                for launcher in args.launchers:
                    if launcher == "basic" and jobs > args.basic_max_jobs:
                        continue
                    show(sweep(jobs, variant, launcher))

    def legend() -> None:
        out("   P M: Prefect, MLflow on (-: off); trend: overhead's change over the sweep, s per")
        out("   100 jobs; 1st: the first job's end after the command started (s); end: from the")
        out(
            "   last job's end to the command's (s: summary, report, MLflow parent run); cpu/j: CPU"
        )
        out("   seconds of every process of the sweep (with its servers) beyond the planner's")
        out("   wall time, per job")

    # The largest sweeps (growth) last: the others' figures come first.
    ordered = sorted(args.jobs)
    middle = ordered[len(ordered) // 2] if ordered else 100
    largest = [j for j in ordered if j > 100 and len(ordered) > 1]
    sizes([j for j in ordered if j not in largest])
    if ordered:
        legend()

    if args.scaling:
        for title, jobs in (
            (f"{middle} small jobs (orchestration dominates)", middle),
            ("15 termes jobs (the planner dominates)", PLANNER_GRID),
        ):
            if jobs is PLANNER_GRID and not args.planner_grid:
                continue
            if jobs is not PLANNER_GRID and not args.small_scaling:
                continue
            out()
            out(f"## Workers: jobs per minute, {title}, Prefect and MLflow on")
            base = None
            for launcher in args.scaling:
                row = sweep(jobs, "on", launcher, "-scaling")
                base = base or row["wall_s"]
                out(
                    f"  {launcher:<6} {row['workers']} worker(s): {row['jobs_per_minute']:6.1f} jobs/min"
                    f" (steady {fmt(row['steady_jobs_per_minute'], 1)}), wall {row['wall_s']:.1f} s"
                    f" (x{base / row['wall_s']:.2f}), planner {row['planner_total_s']:.1f} s, overhead"
                    f" median {row['overhead_median_s']:.2f} s  load {row['load_before'][0]:.1f}/"
                    f"{row['load_after'][0]:.1f}"
                )
            out(f"  {row['command']}  (+ the launcher's overrides)")

    if largest:
        out()
        out(f"## Sweeps of {', '.join(map(str, largest))} jobs (growth), as above")
        out(header)
        out("-" * len(header))
        sizes(largest)

    for domain in args.paper_grid:
        out()
        out(f"## The paper's grid on {domain} (offline), Prefect and MLflow on, every core")
        row = sweep(paper_grid(domain), "on", "all", f"-paper-{domain}", kind="paper")
        out(f"  {grid_line(row)}")
        out(f"  {row['command']}")

    out()
    out("## Commands (one per size and variant; the launchers add their overrides)")
    seen = set()
    for row in rows:
        if "command" in row and row["command"] not in seen:
            seen.add(row["command"])
            out(f"  {row['command']}")

    if args.profile:
        out()
        out(f"## Profile: {middle} jobs, Prefect and MLflow on, one process (cProfile of the jobs)")
        prof = folder / "profile"
        prof.mkdir()
        env["TWOSTEP_PROFILE_DIR"] = str(prof)
        row = sweep(middle, "on", "one", "-profile")
        env.pop("TWOSTEP_PROFILE_DIR")
        table = profile_table(prof)
        total = sum(t for _, t in table) or 1.0
        for label, seconds in table:
            out(f"  {label:<40} {seconds:7.2f} s  {100 * seconds / total:5.1f} %")
        out(f"  (profiled wall {row['wall_s']:.1f} s; cProfile slows Python code down)")

    out()
    out("## Targets (issue 38)")
    for line in targets(rows):
        out(f"  {line}")

    out()
    out(f"# finished {time.strftime('%Y-%m-%d %H:%M:%S')}, load average {load()}")
    out.write()
    if args.json is not None:
        bench_record.write(args.json, run_record, rows)
    if not args.keep:
        shutil.rmtree(folder, ignore_errors=True)
    else:
        print(f"outputs kept in {folder}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
