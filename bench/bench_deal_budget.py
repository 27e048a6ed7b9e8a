"""plan-deal at large N: how far it deals (the plan's pieces), whether its work budget
stops it, and the CPU time it takes, on the SA plans stored in a methods bench run.

For each task and N: the length of the SA plan and of plan-deal's schedule, the number of
agents it dealt to (``deal_agents``: the pieces, when fewer than N), where the budget
stopped it (``deal_budget``), its work and its CPU seconds.

    .venv/bin/python bench/bench_deal_budget.py --agents 4 16 1000 \\
        --tasks blocksworld:1 blocksworld:20 barman:20 termes:20 tyreworld:20
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.methods import agent_predicates
from tools import record
from twostep.dealing import Dealer
from twostep.methods import MethodRequest
from twostep.methods.plan_deal import run_plan_deal
from twostep.planner.results import PlanResult, Status
from twostep.tasks.benchmark import load_task

REPO = Path(__file__).resolve().parent.parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=Path, default=REPO / "docs" / "bench" / "methods_deal.json")
    parser.add_argument("--data", default="data", help="the rows' data root label")
    parser.add_argument("--agents", nargs="+", type=int, default=[4, 16, 1000])
    parser.add_argument("--tasks", nargs="+", default=["blocksworld:1", "termes:20"])
    parser.add_argument("--save", type=Path, default=None, help="also write the table here")
    parser.add_argument("--json", type=Path, help="also write what it prints as a record here")
    args = parser.parse_args()
    with record.capture(args.json, title="plan-deal with many agents: the work budget"):
        _run(args)


def _run(args: argparse.Namespace) -> None:
    rows = json.loads(args.rows.read_text())
    made: list[Dealer] = []
    init = Dealer.__init__

    def counting(self: Dealer, *a: object, **k: object) -> None:
        init(self, *a, **k)  # type: ignore[arg-type]
        made.append(self)

    Dealer.__init__ = counting  # type: ignore[method-assign]
    lines = [
        "task | N | SA | plan-deal | dealt to | budget stop | work | CPU s",
        "---|" * 7 + "---",
    ]
    print("\n".join(lines), flush=True)
    for spec in args.tasks:
        domain, number = spec.split(":")
        row = next(r for r in rows if r["method"] == "sa" and r["data"] == args.data
                   and r["domain"] == domain and r["task"] == int(number))  # fmt: skip
        task = load_task(domain, int(number), REPO / args.data)
        sa = PlanResult(Status.SOLVED, tuple(row["plan"]), 0.0, 0.0)
        for agents in args.agents:
            made.clear()
            start = time.process_time()
            request = MethodRequest(task, agents, agent_predicates=agent_predicates(domain),
                                    sa_plan=sa)  # fmt: skip
            run = run_plan_deal(request)
            seconds = time.process_time() - start
            stop = run.extra.get("deal_budget")
            lines.append(
                f"{domain} p{int(number):02d} | {agents} | {len(sa.plan or ())} | {run.exec_length} | "
                f"{run.extra.get('deal_agents', agents)} | {'N=' + str(stop['agents']) if stop else '-'} | "
                f"{sum(d.work for d in made):,} | {seconds:.1f}"
            )
            print(lines[-1], flush=True)
    text = "\n".join(lines)
    if args.save:
        args.save.write_text(text + "\n")


if __name__ == "__main__":
    main()
