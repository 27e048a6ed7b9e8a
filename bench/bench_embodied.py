"""Benchmark: speed of the embodied executor (environment steps per second).

    .venv/bin/python bench/bench_embodied.py [--repeats 5] [--size 24]

For the paper's four kitchen tasks (``data/alfworld``) and one generated larger kitchen
(``--size`` objects, see :func:`twostep.generators.alfworld.scaled_task`), the per-agent
plans come from TwoStep with the ``goal-split`` decomposer for N = 2, 4 and 8 (planning
is not timed). When the decomposer finds fewer helpers than N - 1, the remaining bodies
get empty plans: they still stand in the kitchen and must make way, so N bodies are
always on the floor. Each execution runs with ``--repeats`` seeds (random start cells and
backoffs); the table shows the mean wall time of :func:`twostep.embodied.execute`, the
mean number of steps, and steps per second. The goal: a 4-agent, 300-step execution in
under 0.5 s.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path
from random import Random

import yaml

from twostep.benchmark import load_task
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.embodied import (
    ExecutorSettings,
    FloorPlan,
    execute,
    floor_plan_from_dict,
    load_floor_plan,
)
from twostep.generators.alfworld import scaled_task
from twostep.methods import MethodRequest, run_twostep
from twostep.pddl import Problem, parse_problem
from twostep.planner import PlannerSettings

ROOT = Path(__file__).resolve().parent.parent
AGENT_PREDICATES = ("at", "handempty", "holding")
AGENTS = (2, 4, 8)


def kitchen_tasks(size: int) -> list[tuple[str, Problem, FloorPlan, object]]:
    floor = load_floor_plan(ROOT / "data" / "alfworld" / "kitchen.yaml")
    out: list[tuple[str, Problem, FloorPlan, object]] = []
    for index in range(1, 5):
        task = load_task("alfworld", index, ROOT / "data")
        out.append((f"p{index:02d}", task.problem, floor, task))
    spec, kitchen = scaled_task(f"alfworld-s{size}", size, Random(f"0:alfworld:bench{size}"))
    domain = (ROOT / "data" / "alfworld" / "domain.pddl").read_text()
    problem = parse_problem(domain, spec.to_pddl())
    big_floor = floor_plan_from_dict(yaml.safe_load(kitchen.floor_plan_yaml()), kitchen.name)
    out.append((f"s{size}", problem, big_floor, None))
    return out


def agent_plans(name: str, problem: Problem, task: object, agents: int) -> list[list[str]]:
    from dataclasses import replace

    from twostep.benchmark import BenchmarkTask

    settings = PlannerSettings(alias="lama-first", search_time_limit_s=120)
    if isinstance(task, BenchmarkTask):
        bench_task = task
    else:
        template = load_task("alfworld", 1, ROOT / "data")
        bench_task = replace(template, problem=problem, task_id=0)
    run = run_twostep(
        MethodRequest(
            bench_task, agents, settings, AGENT_PREDICATES, GoalSplitDecomposer(AGENT_PREDICATES)
        )
    )
    plans = [run.plans[a] for a in run.agent_order]
    return plans + [[] for _ in range(agents - len(plans))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--size", type=int, default=24, help="objects of the larger kitchen")
    args = parser.parse_args()
    print(f"python {platform.python_version()}, {os.cpu_count()} cpus, repeats {args.repeats}")
    header = (
        f"{'task':6} {'N':>2} {'plans':>5} {'actions':>7} {'steps':>7} {'waits':>6} "
        f"{'backoffs':>8} {'ok':>4} {'time ms':>8} {'steps/s':>9}"
    )
    print(header)
    print("-" * len(header))
    for name, problem, floor, task in kitchen_tasks(args.size):
        for agents in AGENTS:
            plans = agent_plans(name, problem, task, agents)
            times, steps, waits, backoffs, ok = [], [], [], [], 0
            for seed in range(args.repeats):
                start = time.perf_counter()
                result = execute(problem, plans, floor, settings=ExecutorSettings(seed=seed))
                times.append(time.perf_counter() - start)
                steps.append(result.steps)
                waits.append(result.waits)
                backoffs.append(result.backoffs)
                ok += result.success
            mean_time = statistics.mean(times)
            mean_steps = statistics.mean(steps)
            print(
                f"{name:6} {agents:>2} {sum(bool(p) for p in plans):>5} "
                f"{sum(len(p) for p in plans):>7} {mean_steps:>7.1f} "
                f"{statistics.mean(waits):>6.1f} {statistics.mean(backoffs):>8.1f} "
                f"{ok:>2}/{args.repeats} {1000 * mean_time:>8.2f} "
                f"{mean_steps / mean_time:>9.0f}"
            )


if __name__ == "__main__":
    main()
