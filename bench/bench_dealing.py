"""Which ways of dealing plan-deal needs: every cut, order and stealing rule, alone and in
sets, over the benchmark's SA plans.

For every task, the SA plan (from the ``sa`` rows of a methods bench run, ``--rows``, or
planned now) is dealt to 2, 3 and 4 agents in every :class:`~twostep.dealing.Way` of
the grid (cut x order x steal); each deal's length is the length of its own schedule. A set
of ways scores, per task and N, the shortest of its deals to 2..N agents and the cleaned SA
plan (as plan-deal keeps them). Prints the macro exec/SA per N of each way alone, of the set
plan-deal uses (:func:`twostep.dealing.ways`), of the whole grid, and of the best sets of
each size, with the dealing seconds per task.

    .venv/bin/python bench/bench_dealing.py --rows docs/bench/methods_deal.json
    .venv/bin/python bench/bench_dealing.py --domains termes --tasks 1-5
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.methods import agent_predicates, data_label, task_ids
from tools import record
from twostep.dealing import CUTS, ORDERS, Dealer, DealError, Way, ways
from twostep.generators import DOMAINS
from twostep.methods import MethodRequest, run_single_agent
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import DEFAULT_DATA_ROOT, list_tasks, load_task

GRID = tuple(Way(c, o, s) for c, o, s in itertools.product(CUTS, ORDERS, (False, True)))
AGENTS = (2, 3, 4)

Lengths = dict[tuple[int, Way], int | None]  # (agents, way) -> schedule length (None: failed)


def name(way: Way) -> str:
    return f"{way.cut}/{way.order}/{'steal' if way.steal else 'keep'}"


def deal_task(
    plan: Sequence[str], domain: str, task: int, root: Path
) -> tuple[Lengths, int, float]:
    """Every way's length for 2..4 agents, the cleaned SA plan's length, the seconds spent."""
    problem = load_task(domain, task, root).problem
    start = time.perf_counter()
    dealer = Dealer(problem, plan, agent_predicates(domain))
    lengths: Lengths = {}
    for agents in AGENTS:
        for way in GRID:
            try:
                lengths[(agents, way)] = len(
                    dealer.deal(agents, way.cut, way.order, way.steal).schedule
                )
            except DealError:
                lengths[(agents, way)] = None
    return lengths, len(dealer.cleaned), time.perf_counter() - start


def best(lengths: Lengths, cleaned: int, n: int, chosen: Sequence[Way]) -> int:
    """plan-deal's length with N agents when it tries ``chosen``: the shortest deal to
    2..N agents, or the cleaned SA plan."""
    found = [lengths[(k, w)] for k in range(2, n + 1) for w in chosen]
    return min([cleaned, *(x for x in found if x is not None)])


def macro(results: Sequence[Mapping[str, object]], n: int, chosen: Sequence[Way]) -> float:
    domains = sorted({str(r["domain"]) for r in results})
    per_domain = []
    for domain in domains:
        mine = [r for r in results if r["domain"] == domain]
        per_domain.append(statistics.fmean(
            best(r["lengths"], r["cleaned"], n, chosen) / r["sa"] for r in mine  # type: ignore[arg-type]
        ))  # fmt: skip
    return statistics.fmean(per_domain)


def line(label: str, results: Sequence[Mapping[str, object]], chosen: Sequence[Way]) -> str:
    return f"| {label} | " + " | ".join(f"{macro(results, n, chosen):.3f}" for n in AGENTS) + " |"


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--data", default=str(DEFAULT_DATA_ROOT))
    parser.add_argument("--domains", nargs="*", default=list(DOMAINS))
    parser.add_argument("--tasks", default="1-20")
    parser.add_argument("--rows", nargs="*", default=[], help="methods bench rows with SA plans")
    parser.add_argument("--json", type=Path, help="also write what it prints as a record here")
    args = parser.parse_args()
    with record.capture(args.json, title="The eight ways to deal, alone and in sets"):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    root = Path(args.data)
    label = data_label(root)
    plans = {
        (r["domain"], r["task"]): r["plan"]
        for path in args.rows
        for r in record.rows_of(Path(path))
        if r["method"] == "sa" and r.get("plan") and str(r.get("data", "data")) == label
    }
    results = []
    for domain in args.domains:
        for task in task_ids(args.tasks, list_tasks(domain, root)):
            plan = plans.get((domain, task))
            if plan is None:
                run = run_single_agent(MethodRequest(load_task(domain, task, root),
                                                     planner=PlannerSettings("lama-first", 60)))  # fmt: skip
                plan = run.plans["agent0"]
            lengths, cleaned, seconds = deal_task(plan, domain, task, root)
            results.append({"domain": domain, "task": task, "sa": len(plan) or 1,
                            "cleaned": cleaned, "lengths": lengths, "seconds": seconds})  # fmt: skip
            print(f"  {domain} p{task:02d}: {seconds:.2f} s", file=sys.stderr, flush=True)
    print(f"# {' '.join(sys.argv)}\n")
    print(f"{len(results)} tasks of {label}; macro exec/SA (plan-deal's rule: the shortest of "
          "the ways' deals to 2..N agents and the cleaned SA plan):\n")  # fmt: skip
    print("| ways | N = 2 | N = 3 | N = 4 |\n|---|---|---|---|")
    print(line("the whole grid (8)", results, GRID))
    print(line("plan-deal's: " + ", ".join(map(name, ways())), results, ways()))
    for way in GRID:
        print(line(name(way) + " alone", results, (way,)))
    for size in (2, 3):
        ranked = sorted(
            itertools.combinations(GRID, size),
            key=lambda chosen: sum(macro(results, n, chosen) for n in AGENTS),
        )
        for chosen in ranked[:3]:
            print(line(f"best of size {size}: " + ", ".join(map(name, chosen)), results, chosen))
    seconds = [float(r["seconds"]) for r in results]  # type: ignore[arg-type]
    print(f"\nDealing the grid (8 ways x N = 2, 3, 4) per task: median {statistics.median(seconds):.2f} s, "
          f"max {max(seconds):.2f} s")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
