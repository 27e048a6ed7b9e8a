"""SA vs MA vs TwoStep (goal-split, plan-split, portfolio) over the benchmark.

For every domain, task and N = 1..4: SA (N = 1), MA (compiled N-agent PDDL) and TwoStep
with each decomposer named in ``--methods``. TwoStep runs get the SA plan of the same task
(plan-split reads it; ``fallback_if_longer`` compares against it, on unless
``--no-fallback``), and its planner time counts in theirs. Every joint schedule is
re-validated by simulation against the original task (``check_run``). Prints, per domain
and N, the mean execution length and planning time of each method, the mean of the
per-task ratios execution length / SA length, and the ratio TwoStep planning time / MA
planning time; then the macro mean (over domains) of exec/SA per N against the targets of
issue 11 and the domains where each method is no longer than MA. Raw rows go to a JSON
file.

    .venv/bin/python bench/bench_methods.py --time-limit 60 --workers 2
    .venv/bin/python bench/bench_methods.py --domains blocksworld --tasks 1-5 --agents 2
    .venv/bin/python bench/bench_methods.py --tasks 1,6,11,16 --methods ma plan-split portfolio
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
from twostep.decomposers.base import Decomposer
from twostep.decomposers.goal_split import GoalSplitDecomposer
from twostep.decomposers.plan_split import PlanSplitDecomposer
from twostep.pipeline import RunResult, check_run, run_multi_agent, run_single_agent, run_twostep
from twostep.planner import PlannerSettings
from twostep.portfolio import Portfolio

CONF = Path(__file__).resolve().parent.parent / "conf" / "domain"
METHODS = ("ma", "goal-split", "plan-split", "portfolio")
TARGETS = {2: 0.70, 3: 0.58, 4: 0.50}  # issue 11: macro exec/SA of the offline default


def agent_predicates(domain: str) -> list[str]:
    return list(yaml.safe_load((CONF / f"{domain}.yaml").read_text())["agent_predicates"])


def decomposer(name: str, preds: list[str]) -> Decomposer:
    if name == "goal-split":
        return GoalSplitDecomposer(preds)
    if name == "plan-split":
        return PlanSplitDecomposer(preds)
    return Portfolio(preds)


def verify(task: Any, result: RunResult, preds: list[str]) -> bool:
    if not result.success:
        return False
    check_run(task.problem, result, preds)
    return True


def job(
    data: str,
    domain: str,
    task_id: int,
    agents_list: list[int],
    limit: float,
    alias: str,
    methods: list[str],
    fallback: bool,
) -> list[dict[str, Any]]:
    task = load_task(domain, task_id, Path(data))
    preds = agent_predicates(domain)
    settings = PlannerSettings(alias, limit)
    sa = run_single_agent(task, settings)
    sa_plan = sa.planner_calls[0].result
    rows = [dict(domain=domain, task=task_id, method="sa", agents=1, exec_length=sa.exec_length,
                 planning_time_s=sa.planning_time_s, sa_length=sa.sa_length, valid=verify(task, sa, preds),
                 status=sa.status)]  # fmt: skip
    for n in agents_list:
        if n == 1:
            continue
        for method in methods:
            start = time.perf_counter()
            if method == "ma":
                result = run_multi_agent(task, n, preds, settings, sa_length=sa.sa_length)
            else:
                result = run_twostep(
                    task, n, decomposer(method, preds), preds, settings, sa_length=sa.sa_length,
                    sa_plan=sa_plan, fallback_if_longer=fallback,
                )  # fmt: skip
            try:
                valid = verify(task, result, preds)
            except Exception as error:  # report, do not stop the table
                valid, result.message = False, f"schedule invalid: {error}"
            rows.append(dict(domain=domain, task=task_id, method=method, agents=n, exec_length=result.exec_length,
                             planning_time_s=result.planning_time_s, sa_length=sa.sa_length, valid=valid,
                             status=result.status, fallback=result.fallback, message=result.message,
                             accepted=sum(s["status"] == "accepted" for s in result.subgoals),
                             candidates=result.extra.get("candidates"),
                             wall_s=time.perf_counter() - start))  # fmt: skip
    return rows


def mean(values: list[float]) -> float:
    return statistics.fmean(values) if values else float("nan")


def task_ids(spec: str, available: list[int]) -> list[int]:
    """``1-20`` (a range) or ``1,6,11,16`` (a list)."""
    if "," in spec:
        wanted = {int(x) for x in spec.split(",")}
        return [t for t in available if t in wanted]
    lo, _, hi = spec.partition("-")
    return [t for t in available if int(lo) <= t <= int(hi or lo)]


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", default=str(DEFAULT_DATA_ROOT))
    parser.add_argument("--domains", nargs="*")
    parser.add_argument("--tasks", default="1-20", help="a range 1-20 or a list 1,6,11,16")
    parser.add_argument("--agents", nargs="*", type=int, default=[1, 2, 3, 4])
    parser.add_argument("--methods", nargs="*", default=list(METHODS), choices=METHODS)
    parser.add_argument("--no-fallback", action="store_true", help="fallback_if_longer=false")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--alias", default="lama-first")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default="outputs/bench/methods.json")
    parser.add_argument(
        "--reuse", help="rows JSON of an earlier run: its rows of methods not run now (e.g. MA)"
    )
    parser.add_argument(
        "--report", nargs="*", help="print the tables of these rows JSON files, run nothing"
    )
    args = parser.parse_args()
    domains = args.domains or list_domains(Path(args.data))
    if args.report:
        rows = [r for f in args.report for r in json.loads(Path(f).read_text())]
        done = {(r["domain"], r["task"]) for r in rows if r["method"] == "sa"}
        rows = [r for r in rows if (r["domain"], r["task"]) in done]
        methods = [m for m in args.methods if any(r["method"] == m for r in rows)]
        print(f"# {' '.join(sys.argv)}\n# {len(done)} tasks\n")
        print(report(rows, domains, sorted({r["agents"] for r in rows}), methods))
        return 0
    # task-major order: a run stopped early still covers every domain
    jobs = sorted(
        ((d, t) for d in domains for t in task_ids(args.tasks, list_tasks(d, Path(args.data)))),
        key=lambda job: (job[1], job[0]),
    )
    rows: list[dict[str, Any]] = []
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [
            pool.submit(job, args.data, d, t, args.agents, args.time_limit, args.alias,
                        args.methods, not args.no_fallback)
            for d, t in jobs
        ]  # fmt: skip
        for done, future in enumerate(as_completed(futures), start=1):
            rows += future.result()
            Path(args.out).write_text(json.dumps(rows, indent=1))  # partial results survive
            print(f"\r{done}/{len(jobs)} tasks", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    methods = list(args.methods)
    if args.reuse:
        ran = {(r["domain"], r["task"]) for r in rows}
        old = [
            r for r in json.loads(Path(args.reuse).read_text()) if (r["domain"], r["task"]) in ran
        ]
        rows += [r for r in old if r["method"] not in ("sa", *methods)]
        methods = [m for m in METHODS if m in methods or any(r["method"] == m for r in old)]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(rows, indent=1))
    print(f"# {' '.join(sys.argv)}")
    print(f"# planner {args.alias}, search time limit {args.time_limit:g} s (TwoStep: limit/N per "
          f"agent); fallback_if_longer={not args.no_fallback}; tasks {args.tasks}\n")  # fmt: skip
    if args.reuse:
        print(
            f"# rows of {', '.join(m for m in methods if m not in args.methods)} from {args.reuse}\n"
        )
    print(report(rows, domains, sorted(set(args.agents)), methods))
    invalid_total = sum(not r["valid"] for r in rows)
    print(f"\nrows: {len(rows)}, not valid (failed or invalid schedule): {invalid_total}")
    return 1 if invalid_total else 0


def report(
    rows: list[dict[str, Any]], domains: list[str], ns: list[int], methods: list[str]
) -> str:
    """The per-domain table, then the macro exec/SA per N (mean over domains)."""
    by: dict[tuple[str, str, int], list[dict[str, Any]]] = defaultdict(list)
    for row in rows:
        by[(row["domain"], row["method"], row["agents"])].append(row)

    def ratio(row: dict[str, Any]) -> float | None:
        ok = row["valid"] and row["sa_length"]
        return row["exec_length"] / row["sa_length"] if ok else None

    def mean_ratio(rs: list[dict[str, Any]]) -> float:
        return mean([x for x in map(ratio, rs) if x is not None])

    lines = []
    head = "| domain | N | " + " | ".join(f"{m} len" for m in ["sa", *methods])
    head += " | " + " | ".join(f"{m}/SA" for m in methods)
    head += " | SA time s | " + " | ".join(f"{m} time s" for m in methods)
    ts = [m for m in methods if m != "ma"]
    if "ma" in methods:
        head += " | " + " | ".join(f"{m}/MA time" for m in ts)
    head += " | longer than SA | invalid |"
    lines += [head, "|" + "---|" * (head.count("|") - 1)]
    macro: dict[tuple[str, int], list[float]] = defaultdict(list)
    for domain in domains:
        sa = by[(domain, "sa", 1)]
        sa_len = mean([r["exec_length"] for r in sa if r["valid"]])
        sa_time = mean([r["planning_time_s"] for r in sa])
        for n in ns:
            if n == 1:
                lines.append(f"| {domain} | 1 | {sa_len:.1f} |" + " |" * (head.count("|") - 4)
                             + f" {sum(not r['valid'] for r in sa)} |")  # fmt: skip
                continue
            group = {m: by[(domain, m, n)] for m in methods}
            lens = [mean([r["exec_length"] for r in group[m] if r["valid"]]) for m in methods]
            ratios = [mean_ratio(group[m]) for m in methods]
            for m, x in zip(methods, ratios, strict=True):
                macro[(m, n)].append(x)
            times = [mean([r["planning_time_s"] for r in group[m]]) for m in methods]
            cells = [f"{x:.1f}" for x in lens] + [f"{x:.3f}" for x in ratios]
            cells += [f"{sa_time:.2f}"] + [f"{x:.2f}" for x in times]
            if "ma" in methods:
                ma_t = times[methods.index("ma")]
                cells += [f"{times[methods.index(m)] / ma_t:.3f}" for m in ts]
            longer = sum(
                1 for m in ts for r in group[m] if r["valid"] and r["exec_length"] > r["sa_length"]
            )
            bad = sum(not r["valid"] for m in methods for r in group[m])
            lines.append(f"| {domain} | {n} | | " + " | ".join(cells) + f" | {longer} | {bad} |")
    lines += ["", "Macro exec/SA (mean over domains of the per-task mean):", ""]
    lines += ["| N | target | " + " | ".join(methods) + " | " + " | ".join(
        f"{m}: domains <= MA" for m in ts if "ma" in methods) + " |"]  # fmt: skip
    lines += ["|" + "---|" * (2 + len(methods) + (len(ts) if "ma" in methods else 0))]
    for n in ns:
        if n == 1:
            continue
        cells = [f"{statistics.fmean(macro[(m, n)]):.3f}" for m in methods]
        if "ma" in methods:
            ma = macro[("ma", n)]
            cells += [f"{sum(x <= y + 1e-9 for x, y in zip(macro[(m, n)], ma, strict=True))}/{len(ma)}"
                      for m in ts]  # fmt: skip
        lines.append(f"| {n} | {TARGETS.get(n, float('nan')):.2f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
