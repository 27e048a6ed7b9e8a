"""Which portfolio members are worth their planning time: read from the portfolio's rows.

The portfolio (``twostep/methods/portfolio.py``) records every candidate of every run:
each TwoStep member with N, N-1, ..., 2 agents, plan-deal, and each TwoStep candidate's
plans dealt again (``candidates`` in the rows of ``bench/bench_methods.py``). This script
replays, without planning anything, what a smaller portfolio would have chosen: plan-deal
plus the members of a subset, each with N agents only (its TwoStep run and the re-deal of
its plans). For every member alone and every pair it prints the macro exec/SA per N (mean
over domains of the per-task mean, as the methods bench) and the planning time the subset
adds to plan-deal's (its candidates' ``planning_time_s``: median per domain, the largest of
those medians shown). A member whose candidate was not planned because an earlier one had
the same subgoals (``same_as``) takes that candidate's length and adds no time.

    .venv/bin/python bench/bench_portfolio_members.py docs/bench/methods_portfolio.json

Last, the pairs by their mean macro over the N: ``portfolio-lite`` takes the first
(``docs/bench/methods_lite.txt``), and ``bench/bench_methods.py --methods portfolio-lite``
then runs it for real.
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.portfolio_members import evaluate, members
from tools import record


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("rows", type=Path, help="rows of bench_methods.py with portfolio runs")
    parser.add_argument("--top", type=int, default=5, help="subsets shown per N (default 5)")
    args = parser.parse_args(argv)
    rows = [r for r in record.rows_of(args.rows) if r.get("method") == "portfolio"]
    names = members(rows)
    subsets = [(), *((m,) for m in names), *itertools.combinations(names, 2), tuple(names)]
    print(f"# {len(rows)} portfolio runs; members: {', '.join(names)}")
    counts = sorted({r["agents"] for r in rows})
    evaluated = {(n, s): evaluate(rows, n, s) for n in counts for s in subsets}
    for agents in counts:
        ranked = sorted(subsets, key=lambda s: (evaluated[agents, s]["macro"],
                                                evaluated[agents, s]["added_s"]))  # fmt: skip
        print(f"\nN = {agents}: plan-deal + subset, macro exec/SA, largest per-domain median of "
              "the added planning time (s)")  # fmt: skip
        ends = [s for s in ranked if len(s) in (0, len(names))]  # plan-deal alone, and all
        for subset in dict.fromkeys([*ranked[: args.top], *ends]):
            result = evaluated[agents, subset]
            label = " + ".join(subset) if subset else "(plan-deal alone)"
            if len(subset) == len(names):
                label = "(all members, N agents only)"
            domains = " ".join(f"{d} {v:.3f}" for d, v in sorted(result["domains"].items()))
            print(f"  {result['macro']:.3f}  +{result['added_s']:.2f} s  {label}  [{domains}]")
    pairs = [s for s in subsets if len(s) == 2]
    overall = sorted((statistics.mean(evaluated[n, s]["macro"] for n in counts), s) for s in pairs)
    print(f"\npairs by their mean macro exec/SA over N = {', '.join(map(str, counts))}:")
    for macro, subset in overall[: args.top]:
        print(f"  {macro:.4f}  {' + '.join(subset)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
