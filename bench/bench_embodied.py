"""Benchmark: the embodied executor's speed, the independent trace check over many seeds,
the pictures' render time, and a real AlfWorld problem on its AI2-THOR layout.

    .venv/bin/python bench/bench_embodied.py [--sections speed,check,render,real]
        [--repeats 5] [--size 24] [--seeds 30]

speed   For the four kitchen tasks (``data/alfworld``) and one generated larger kitchen
        (``--size`` objects), TwoStep plans (goal-split) for N = 2, 4 and 8 (planning not
        timed; bodies without a helper plan still stand in the kitchen); mean wall time of
        :func:`twostep.embodied.execute` over ``--repeats`` seeds, steps, steps per second;
        ``ground ms``: grounding the task with its N bodies the first time (Fast
        Downward's translator), timed apart; the executions timed after it reuse the
        translation the process caches (a job's single execution pays it).
        Goal: a 4-agent, 300-step execution in under 0.5 s.
check   MA and TwoStep (goal-split) on the four tasks, N = 2 and 3, seeds 0..``--seeds``-1:
        every trace replayed by :mod:`checkers.trace_check` (its own floor-plan and PDDL
        reading); traces, commands, interactions, interactions out of reach, violations.
render  The GIF and the timeline of task 1, MA, N = 2, seed 0 (``write_pictures``), the
        first time in the process (matplotlib's import included) and again.
        Goal: at most 2 s per run.
real    Our FloorPlan14 problem (``tests/fixtures/alfred_scene``, AlfWorld's format) with the
        wheel's ``alfred.pddl``, on the scene's layout: SA, MA and TwoStep (plan-deal and
        goal-split), N = 2 and 3, seeds 0-4: embodied lengths, the trace check, and
        AlfWorld's own engine on every trace when ``make alfworld-engine`` has run.

Every section prints the machine's load average beside its timings. ``--json FILE`` also
writes every section's rows as a bench record (:mod:`tools.record`); :func:`evaluation.pages.embodied.page` turns it
into the results page (``make results``):

    .venv/bin/python bench/bench_embodied.py --json docs/bench/embodied.json
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from random import Random
from typing import Any

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from checkers.trace_check import TraceReport, check_trace, read_kitchen_file, who_plays
from tools import record as bench_record
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.embodied import (
    ExecutorSettings,
    FloorPlan,
    execute,
    execute_plans,
    floor_plan_from_dict,
    load_floor_plan,
    task_floor_plan,
    write_pictures,
)
from twostep.embodied.executor import embody
from twostep.embodied.run import TRACE_KEY, embodied_fields
from twostep.generators.alfworld import scaled_task
from twostep.methods import (
    MethodRequest,
    RunResult,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)
from twostep.pddl import Problem, parse_problem
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import BenchmarkTask, load_task

ROOT = Path(__file__).resolve().parent.parent
KITCHEN = ROOT / "data" / "alfworld" / "kitchen.yaml"
AGENT_PREDICATES = ("at", "handempty", "holding")
ALFRED_PREDICATES = ("atlocation", "holds", "holdsany", "holdsanyreceptacleobject")
PLANNER = PlannerSettings(alias="lama-first", search_time_limit_s=120)
AGENTS = (2, 4, 8)


def load() -> str:
    return "load average " + ", ".join(f"{x:.2f}" for x in os.getloadavg())


def kitchen_tasks(size: int) -> list[tuple[str, Problem, FloorPlan, BenchmarkTask]]:
    floor = load_floor_plan(KITCHEN)
    out = []
    for index in range(1, 5):
        task = load_task("alfworld", index, ROOT / "data")
        out.append((f"p{index:02d}", task.problem, floor, task))
    spec, kitchen = scaled_task(f"alfworld-s{size}", size, Random(f"0:alfworld:bench{size}"))
    problem = parse_problem(
        (ROOT / "data" / "alfworld" / "domain.pddl").read_text(), spec.to_pddl()
    )
    big_floor = floor_plan_from_dict(yaml.safe_load(kitchen.floor_plan_yaml()), kitchen.name)
    template = load_task("alfworld", 1, ROOT / "data")
    out.append((f"s{size}", problem, big_floor, replace(template, problem=problem, task_id=0)))
    return out


def twostep_plans(task: BenchmarkTask, agents: int) -> list[list[str]]:
    decomposer = GoalSplitDecomposer(AGENT_PREDICATES)
    run = run_twostep(MethodRequest(task, agents, PLANNER, AGENT_PREDICATES, decomposer))
    plans = [run.plans[a] for a in run.agent_order]
    return plans + [[] for _ in range(agents - len(plans))]


Rows = list[dict[str, Any]]


def speed(repeats: int, size: int, recorded: Rows | None = None) -> None:
    print(f"\n== speed ({load()})")
    header = (
        f"{'task':6} {'N':>2} {'plans':>5} {'actions':>7} {'steps':>7} {'waits':>6} "
        f"{'backoffs':>8} {'ok':>4} {'time ms':>8} {'ground ms':>9} {'steps/s':>9}"
    )
    print(header)
    print("-" * len(header))
    for name, problem, floor, task in kitchen_tasks(size):
        for agents in AGENTS:
            plans = twostep_plans(task, agents)
            start = time.perf_counter()  # the first grounding of the N bodies' task
            bodies = embody(problem, plans, [f"agent{i}" for i in range(len(plans))])
            assert bodies.problem.grounded.actions
            ground = time.perf_counter() - start
            times, steps, waits, backoffs, ok = [], [], [], [], 0
            for seed in range(repeats):
                start = time.perf_counter()
                result = execute(problem, plans, floor, settings=ExecutorSettings(seed=seed))
                times.append(time.perf_counter() - start)
                steps.append(result.steps)
                waits.append(result.waits)
                backoffs.append(result.backoffs)
                ok += result.success
            mean_time, mean_steps = statistics.mean(times), statistics.mean(steps)
            if recorded is not None:
                recorded.append({"section": "speed", "task": name, "agents": agents,
                             "plans": sum(bool(p) for p in plans),
                             "actions": sum(len(p) for p in plans), "steps": mean_steps,
                             "waits": statistics.mean(waits), "backoffs": statistics.mean(backoffs),
                             "ok": ok, "repeats": repeats, "time_ms": 1000 * mean_time,
                             "ground_ms": 1000 * ground, "load": list(os.getloadavg())})  # fmt: skip
            print(
                f"{name:6} {agents:>2} {sum(bool(p) for p in plans):>5} "
                f"{sum(len(p) for p in plans):>7} {mean_steps:>7.1f} "
                f"{statistics.mean(waits):>6.1f} {statistics.mean(backoffs):>8.1f} "
                f"{ok:>2}/{repeats} {1000 * mean_time:>8.2f} {1000 * ground:>9.2f} "
                f"{mean_steps / mean_time:>9.0f}"
            )


def method_run(
    task: BenchmarkTask, method: str, agents: int, predicates: tuple[str, ...]
) -> RunResult:
    if method == "sa":
        return run_single_agent(MethodRequest(task, 1, PLANNER))
    if method == "ma":
        return run_multi_agent(MethodRequest(task, agents, PLANNER, predicates))
    if method == "plan-deal":
        from twostep.methods.plan_deal import run_plan_deal

        return run_plan_deal(MethodRequest(task, agents, PLANNER, predicates))
    decomposer = GoalSplitDecomposer(predicates)
    return run_twostep(MethodRequest(task, agents, PLANNER, predicates, decomposer))


def replayed(
    task: BenchmarkTask, run: RunResult, floor: FloorPlan, seed: int, own_floor: object
) -> tuple[object, TraceReport, dict[str, object]]:
    result = execute_plans(
        task.problem, run.plans, run.agent_order, floor, ExecutorSettings(seed=seed)
    )
    record = embodied_fields(result, floor)[TRACE_KEY]
    report = check_trace(
        record, run.plans, task.domain_path.read_text(), task.problem_path.read_text(),
        own_floor,  # type: ignore[arg-type]
    )  # fmt: skip
    return result, report, record


def check(seeds: int, recorded: Rows | None = None) -> None:
    print(f"\n== trace check: 4 tasks x MA, TwoStep (goal-split) x N = 2, 3 x {seeds} seeds")
    floor, own = load_floor_plan(KITCHEN), read_kitchen_file(KITCHEN)
    totals = {"traces": 0, "failed runs": 0, "commands": 0, "interactions": 0,
              "out of reach": 0, "violations": 0}  # fmt: skip
    start = time.perf_counter()
    for task_id in range(1, 5):
        task = load_task("alfworld", task_id, ROOT / "data")
        for method in ("ma", "goal-split"):
            for agents in (2, 3):
                run = method_run(task, method, agents, AGENT_PREDICATES)
                for seed in range(seeds):
                    result, report, _ = replayed(task, run, floor, seed, own)
                    totals["traces"] += 1
                    totals["failed runs"] += not result.success  # type: ignore[attr-defined]
                    totals["commands"] += report.commands
                    totals["interactions"] += report.interactions
                    totals["out of reach"] += report.out_of_reach
                    totals["violations"] += len(report.violations)
                    for violation in report.violations[:3]:
                        print(f"  p{task_id} {method} N={agents} seed {seed}: {violation}")
    print("  " + ", ".join(f"{k} {v}" for k, v in totals.items()))
    print(f"  {time.perf_counter() - start:.1f} s with planning ({load()})")
    if recorded is not None:
        recorded.append({"section": "check", "seeds": seeds, **totals,
                     "seconds": time.perf_counter() - start, "load": list(os.getloadavg())})  # fmt: skip


def render(recorded: Rows | None = None) -> None:
    floor = load_floor_plan(KITCHEN)
    task = load_task("alfworld", 1, ROOT / "data")
    run = method_run(task, "ma", 2, AGENT_PREDICATES)
    result = execute_plans(
        task.problem, run.plans, run.agent_order, floor, ExecutorSettings(seed=0)
    )
    fields = embodied_fields(result, floor)
    print(
        f"\n== render: task 1, MA, N = 2, seed 0 ({result.steps} steps, {len(result.agents)} agents)"
    )
    with tempfile.TemporaryDirectory() as folder:
        for label in ("first (imports matplotlib)", "again"):
            start = time.perf_counter()
            written = write_pictures(fields, folder)
            took = time.perf_counter() - start
            sizes = ", ".join(f"{k} {p.stat().st_size // 1024} kB" for k, p in written.items())
            print(f"  {label}: {took:.2f} s ({sizes}; {load()})")
            if recorded is not None:
                recorded.append({"section": "render", "run": label, "seconds": took,
                             "steps": result.steps,
                             "kb": {k: p.stat().st_size // 1024 for k, p in written.items()},
                             "load": list(os.getloadavg())})  # fmt: skip


def real(seeds: int, recorded: Rows | None = None) -> None:
    from checkers.alfworld_engine import engine_python, replay_trace
    from checkers.trace_check import alfworld_layouts_folder

    layouts = alfworld_layouts_folder()
    if layouts is None:
        print("\n== real: skipped (the alfworld wheel, extra 'embodied', is not installed)")
        if recorded is not None:
            recorded.append({"section": "real", "skipped": "the alfworld wheel is not installed"})
        return
    root = Path(tempfile.mkdtemp(prefix="twostep-alfred-"))
    (root / "alfred").mkdir()
    shutil.copy(layouts.parent.parent / "data" / "alfred.pddl", root / "alfred" / "domain.pddl")
    fixture = ROOT / "tests" / "fixtures" / "alfred_scene" / "alfred" / "p01.pddl"
    shutil.copy(fixture, root / "alfred" / "p01.pddl")
    task = load_task("alfred", 1, root)
    floor = task_floor_plan(task.problem, task.problem_path.parent)
    engine = engine_python() is not None
    print(f"\n== real: {fixture.relative_to(ROOT)} on {floor.name} ({len(floor.free_cells())} "
          f"reachable cells), seeds 0-{seeds - 1}; AlfWorld's engine: {'yes' if engine else 'not installed'}")  # fmt: skip
    print(f"  {'method':12} {'N':>2} {'actions':>7}  {'embodied lengths':28} {'mean':>6} "
          f"{'check':>7} {'engine':>7}")  # fmt: skip
    problem_text = task.problem_path.read_text()
    rows = [("sa", 1)] + [(m, n) for n in (2, 3) for m in ("ma", "plan-deal", "goal-split")]
    for method, agents in rows:
        run = method_run(task, method, agents, ALFRED_PREDICATES)
        plays = who_plays(task.domain_path.read_text(), problem_text, run.plans)
        lengths, checked, judged = [], 0, 0
        for seed in range(seeds):
            result, report, record = replayed(task, run, floor, seed, None)
            lengths.append(result.embodied_length if result.success else -1)  # type: ignore[attr-defined]
            checked += report.ok and report.out_of_reach == 0
            if engine:
                judged += replay_trace(record, problem_text, plays).ok
        actions = sum(len(p) for p in run.plans.values())
        if recorded is not None:
            recorded.append({"section": "real", "problem": str(fixture.relative_to(ROOT)),
                         "floor_plan": floor.name, "method": method, "agents": agents,
                         "actions": actions, "lengths": lengths, "checked": checked,
                         "engine": judged if engine else None, "seeds": seeds})  # fmt: skip
        print(f"  {method:12} {agents:>2} {actions:>7}  {lengths!s:28} "
              f"{statistics.mean(lengths):>6.1f} {checked:>3}/{seeds} "
              f"{(f'{judged}/{seeds}' if engine else '-'):>7}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sections", default="speed,check,render,real")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--size", type=int, default=24, help="objects of the larger kitchen")
    parser.add_argument("--seeds", type=int, default=30, help="seeds of the trace check")
    parser.add_argument("--json", type=Path, help="also write the rows here (a bench record)")
    args = parser.parse_args()
    run = bench_record.started()
    recorded: Rows = []
    sections = set(args.sections.split(","))
    print(f"python {platform.python_version()}, {os.cpu_count()} cpus ({load()})")
    if "speed" in sections:
        speed(args.repeats, args.size, recorded)
    if "check" in sections:
        check(args.seeds, recorded)
    if "render" in sections:
        render(recorded)
    if "real" in sections:
        real(min(args.seeds, 5), recorded)
    if args.json:
        bench_record.write(args.json, run, recorded, sections=sorted(sections), size=args.size)


if __name__ == "__main__":
    main()
