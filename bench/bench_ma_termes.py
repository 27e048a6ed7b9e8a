"""MA on the termes tasks whose 4-agent compilation times out at 60 s, with a longer limit.

.venv/bin/python bench/bench_ma_termes.py [--time-limit 600] [--tasks 2 6 10]
"""

from __future__ import annotations

import argparse

from twostep.methods import MethodRequest, run_multi_agent
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import load_task


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--time-limit", type=float, default=600.0)
    parser.add_argument("--tasks", type=int, nargs="*", default=[2, 6, 10])
    args = parser.parse_args()
    for k in args.tasks:
        settings = PlannerSettings("lama-first", args.time_limit)
        r = run_multi_agent(MethodRequest(load_task("termes", k), 4, settings, ["at", "has-block"]))
        print(
            f"termes p{k:02d} MA N=4 lama-first {args.time_limit:g} s: status={r.status} "
            f"exec_length={r.exec_length} planning_time={r.planning_time_s:.1f}s",
            flush=True,
        )


if __name__ == "__main__":
    main()
