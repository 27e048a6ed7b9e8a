"""SA vs MA vs TwoStep (goal-split) over the benchmark: execution length and planning time.

For every domain, task and N = 1..4: SA (N = 1), MA (compiled N-agent PDDL) and TwoStep
with the goal-split decomposer. Every joint schedule is re-validated by simulation
against the original task (``check_run``). Prints, per domain and N, the mean
execution length and planning time of each method, the ratio execution length / SA
length, and the ratio TwoStep planning time / MA planning time; raw rows go to a JSON
file.

    .venv/bin/python bench/bench_methods.py --time-limit 60 --workers 2
    .venv/bin/python bench/bench_methods.py --domains blocksworld --tasks 1-5 --agents 2
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import yaml

from twostep.benchmark import DEFAULT_DATA_ROOT, list_domains, list_tasks, load_task
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.pipeline import RunResult, check_run, run_multi_agent, run_single_agent, run_twostep
from twostep.planner import PlannerSettings

CONF = Path(__file__).resolve().parent.parent / "conf" / "domain"


def agent_predicates(domain: str) -> list[str]:
    return list(yaml.safe_load((CONF / f"{domain}.yaml").read_text())["agent_predicates"])


def verify(task: Any, result: RunResult, preds: list[str]) -> bool:
    if not result.success:
        return False
    check_run(task.problem, result, preds)
    return True


def job(
    data: str, domain: str, task_id: int, agents_list: list[int], limit: float, alias: str
) -> list[dict[str, Any]]:
    task = load_task(domain, task_id, Path(data))
    preds = agent_predicates(domain)
    settings = PlannerSettings(alias, limit)
    sa = run_single_agent(task, settings)
    rows = [dict(domain=domain, task=task_id, method="sa", agents=1, exec_length=sa.exec_length,
                 planning_time_s=sa.planning_time_s, sa_length=sa.sa_length, valid=verify(task, sa, preds),
                 status=sa.status)]  # fmt: skip
    for n in agents_list:
        if n == 1:
            continue
        for method in ("ma", "twostep"):
            start = time.perf_counter()
            if method == "ma":
                result = run_multi_agent(task, n, preds, settings, sa_length=sa.sa_length)
            else:
                result = run_twostep(
                    task, n, GoalSplitDecomposer(preds), preds, settings, sa_length=sa.sa_length
                )
            try:
                valid = verify(task, result, preds)
            except Exception as error:  # report, do not stop the table
                valid, result.message = False, f"schedule invalid: {error}"
            rows.append(dict(domain=domain, task=task_id, method=method, agents=n, exec_length=result.exec_length,
                             planning_time_s=result.planning_time_s, sa_length=sa.sa_length, valid=valid,
                             status=result.status, fallback=result.fallback, message=result.message,
                             accepted=sum(s["status"] == "accepted" for s in result.subgoals),
                             wall_s=time.perf_counter() - start))  # fmt: skip
    return rows


def mean(values: list[float]) -> float:
    return statistics.fmean(values) if values else float("nan")


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", default=str(DEFAULT_DATA_ROOT))
    parser.add_argument("--domains", nargs="*")
    parser.add_argument("--tasks", default="1-20")
    parser.add_argument("--agents", nargs="*", type=int, default=[1, 2, 3, 4])
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--alias", default="lama-first")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default="outputs/bench/methods.json")
    args = parser.parse_args()
    lo, _, hi = args.tasks.partition("-")
    domains = args.domains or list_domains(Path(args.data))
    jobs = [
        (d, t)
        for d in domains
        for t in list_tasks(d, Path(args.data))
        if int(lo) <= t <= int(hi or lo)
    ]
    rows: list[dict[str, Any]] = []
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [
            pool.submit(job, args.data, d, t, args.agents, args.time_limit, args.alias)
            for d, t in jobs
        ]
        for done, future in enumerate(as_completed(futures), start=1):
            rows += future.result()
            print(f"\r{done}/{len(jobs)} tasks", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(rows, indent=1))
    print(f"# {' '.join(sys.argv)}")
    print(
        f"# planner {args.alias}, search time limit {args.time_limit:g} s (TwoStep: limit/N per agent)\n"
    )
    print(
        "| domain | N | SA len | MA len | TwoStep len | MA/SA | TwoStep/SA | SA time s | MA time s | TwoStep time s | TwoStep/MA time | invalid |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    by: dict[tuple[str, str, int], list[dict[str, Any]]] = defaultdict(list)
    for row in rows:
        by[(row["domain"], row["method"], row["agents"])].append(row)
    invalid_total = sum(not r["valid"] for r in rows)
    for domain in domains:
        sa = by[(domain, "sa", 1)]
        sa_len = mean([r["exec_length"] for r in sa if r["valid"]])
        sa_time = mean([r["planning_time_s"] for r in sa])
        for n in sorted(set(args.agents)):
            if n == 1:
                print(
                    f"| {domain} | 1 | {sa_len:.1f} | | | | | {sa_time:.2f} | | | | {sum(not r['valid'] for r in sa)} |"
                )
                continue
            ma, ts = by[(domain, "ma", n)], by[(domain, "twostep", n)]
            ma_len = mean([r["exec_length"] for r in ma if r["valid"]])
            ts_len = mean([r["exec_length"] for r in ts if r["valid"]])
            ma_t = mean([r["planning_time_s"] for r in ma])
            ts_t = mean([r["planning_time_s"] for r in ts])
            bad = sum(not r["valid"] for r in ma + ts)
            print(f"| {domain} | {n} | | {ma_len:.1f} | {ts_len:.1f} | {ma_len / sa_len:.3f} | {ts_len / sa_len:.3f} "
                  f"| | {ma_t:.2f} | {ts_t:.2f} | {ts_t / ma_t:.3f} | {bad} |")  # fmt: skip
    print(f"\nrows: {len(rows)}, not valid (failed or invalid schedule): {invalid_total}")
    return 1 if invalid_total else 0


if __name__ == "__main__":
    raise SystemExit(main())
