"""plan-deal on real IPC domains the project never tuned for (beyond the sample's agents.yaml).

For each domain of the IPC sample (read in place, ``--sample``, default ../shared/ipc-sample)
and the agent predicates chosen below from its domain file (the facts that say what the
acting object's own state is, none shared with other objects), the SA plan (lama-first,
``--time-limit`` s) is dealt to N = 2 and 3 agents by plan-deal. Every schedule, a fallback
to the SA plan included, is re-validated twice: by ``check_run`` (our simulator) and by
unified-planning's validator on the N-agent compilation of the task, with the schedule's
parallel steps laid out one after the other (as in tests/test_plan_split.py).

Prints one row per domain, agent predicates and N: SA length, plan-deal length, the
fallback reason if any, both verdicts, the dealing CPU seconds (every phase after the SA
plan, scoring included). A crash (an exception out of plan-deal) or a deal that takes more
than ``--deal-limit`` s is a row too. Domains whose SA plan takes longer than the limit are
skipped.

    .venv/bin/python bench/bench_deal_ipc.py > docs/bench/deal_ipc.txt
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
import traceback
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import FrameType

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from twostep.benchmark import BenchmarkTask, load_task
from twostep.methods import MethodRequest, RunResult, check_run, run_single_agent
from twostep.methods.plan_deal import run_plan_deal
from twostep.multiagent import compile_multi_agent_problem
from twostep.planner import PlannerSettings
from twostep.strips import parse_action
from twostep.validation import validate_plan

REPO = Path(__file__).resolve().parent.parent
SAMPLE = REPO.parent / "shared" / "ipc-sample"

# Agent predicates per domain, read from each domain file: the acting object's own state.
# Where several objects of the agent's kind exist (rovers, satellites, elevators, hoists),
# each agent has its own copy of all of them, as floortile's agents have both robots.
# A predicate shared by the agents' objects and others (depot's, driverlog's, zenotravel's,
# transport's, nomystery's and sokoban's ``at``, which also places crates, packages,
# persons or stones) gives each agent its own copy of where the cargo is: the compilation
# reads it so, and the second row of such a domain probes that reading. airport's second
# row makes the goal (is-parked) an agent fact, which every agent must then reach.
ROVER = ["at", "have_soil_analysis", "have_rock_analysis", "have_image", "calibrated"]
ROVER += ["empty", "full"]  # its store
CASES: dict[str, list[list[str]]] = {
    "depot": [["available", "lifting"], ["at", "available", "lifting"]],
    "driverlog": [["driving"], ["at", "driving"]],
    "rovers": [["at"], ROVER],
    "satellite": [["pointing", "power_avail", "power_on", "calibrated"]],
    "zenotravel": [["fuel-level", "in"], ["at", "fuel-level", "in"]],
    "tpp": [["at", "loaded"]],
    "transport-sat08-strips": [["in", "capacity"], ["at", "in", "capacity"]],
    "nomystery-sat11-strips": [["in", "fuel"], ["at", "in", "fuel"]],
    "elevators-sat08-strips": [["lift-at", "boarded", "passengers"]],
    "miconic-simpleadl": [["lift-at", "boarded"]],
    "storage": [["at", "available", "lifting"]],
    "airport-adl": [
        ["at-segment", "facing", "airborne", "is-moving", "is-pushing"],
        ["at-segment", "facing", "airborne", "is-moving", "is-pushing", "is-parked"],
    ],
    "sokoban-sat08-strips": [["at"]],
    "citycar-sat14-adl": [["at_car_jun", "at_car_road", "starting"]],
    "childsnack-sat14-strips": [["at"]],
    "floortile-sat11-strips": [["robot-at", "robot-has", "free-color"]],
}


class Timeout(Exception):
    pass


@contextmanager
def time_limit(seconds: int) -> Iterator[None]:
    def expire(signum: int, frame: FrameType | None) -> None:
        raise Timeout(f"over {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def up_verdict(task: BenchmarkTask, run: RunResult, preds: Sequence[str]) -> str:
    """unified-planning's verdict on the schedule in the N-agent compilation."""
    try:
        compiled, names = compile_multi_agent_problem(task.problem, len(run.agent_order), preds)
        index = {agent: i for i, agent in enumerate(run.agent_order)}
        sequential = []
        for step in run.schedule:
            for agent, action in step:
                name, args = parse_action(action)
                sequential.append("(" + " ".join((name, names[index[agent]], *args)) + ")")
        verdict = validate_plan(compiled, sequential)
    except Exception as error:  # a reader that cannot read the task: no verdict
        return f"n/a ({type(error).__name__}: {str(error).splitlines()[0][:60]})"
    return "ok" if verdict.valid else f"INVALID ({verdict.message[:80]})"


def our_verdict(task: BenchmarkTask, run: RunResult, preds: Sequence[str]) -> str:
    try:
        check_run(task.problem, run, preds)
    except Exception as error:
        return f"INVALID ({type(error).__name__}: {str(error)[:80]})"
    return "ok"


def deal_seconds(run: RunResult) -> float:
    return float(sum(run.extra.get("deal_seconds", {}).values()))


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sample", type=Path, default=SAMPLE)
    parser.add_argument("--domains", nargs="*", default=list(CASES))
    parser.add_argument("--agents", type=int, nargs="*", default=[2, 3])
    parser.add_argument("--time-limit", type=float, default=30.0, help="SA planner seconds")
    parser.add_argument("--deal-limit", type=int, default=60, help="seconds per plan-deal run")
    args = parser.parse_args(argv)
    planner = PlannerSettings("lama-first", args.time_limit)
    shown = " ".join(a for a in (argv if argv is not None else sys.argv[1:]))
    print(f".venv/bin/python bench/bench_deal_ipc.py {shown}".rstrip())
    print(f"sample: {args.sample.name}, p01 of each domain; SA lama-first {args.time_limit:g} s")
    header = ("domain", "agent predicates", "N", "SA", "deal", "fallback", "check_run",
              "unified-planning", "deal CPU s")  # fmt: skip
    print(" | ".join(header))
    began = time.perf_counter()
    for domain in args.domains:
        try:
            task = load_task(domain, 1, args.sample)
            sa = run_single_agent(MethodRequest(task, planner=planner))
        except Exception as error:
            print(f"{domain} | - | - | SA error: {type(error).__name__}: {error}"[:200])
            continue
        if sa.exec_length is None:
            print(f"{domain} | - | - | no SA plan ({sa.message[:80]})")
            continue
        sa_plan = sa.planner_calls[0].result
        for preds in CASES[domain]:
            for agents in args.agents:
                label = ",".join(preds)
                request = MethodRequest(task, agents, planner, preds, sa_plan=sa_plan)
                start = time.process_time()
                try:
                    with time_limit(args.deal_limit):
                        run = run_plan_deal(request)
                except Exception as error:
                    spent = time.process_time() - start
                    where = traceback.extract_tb(error.__traceback__)[-1]
                    print(f"{domain} | {label} | {agents} | {sa.exec_length} | CRASH | "
                          f"{type(error).__name__}: {str(error)[:100]} "
                          f"({Path(where.filename).name}:{where.lineno}) | - | - | "
                          f"{spent:.2f}")  # fmt: skip
                    continue
                print(" | ".join(str(x) for x in (
                    domain, label, agents, sa.exec_length, run.exec_length,
                    run.fallback or "-", our_verdict(task, run, preds),
                    up_verdict(task, run, preds), f"{deal_seconds(run):.2f}",
                )), flush=True)  # fmt: skip
    print(f"total {time.perf_counter() - began:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
