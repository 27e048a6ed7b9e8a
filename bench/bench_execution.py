"""Benchmark: parallel execution length for N = 4 agents with 60-step plans, and its scaling.

    .venv/bin/python bench/bench_execution.py [--repeats 5] [--budget 30]
    .venv/bin/python bench/bench_execution.py --scaling [--max-nodes 2000] [--time-limit 10]
    .venv/bin/python bench/bench_execution.py --json docs/bench/execution.json
    .venv/bin/python bench/bench_execution.py --scaling --json docs/bench/execution_scaling.json

``--json FILE`` also writes the table's rows as a bench record (:mod:`tools.record`);
:func:`evaluation.pages.execution.page` turns the two records into the results page (``make results``).

``--scaling`` prints only the scaling table: exact mode for N = 2..16 agents and 30, 60
and 100 steps per agent, on the ``shared`` case (every track crosses one hub, pairs of
tracks cross further on) and on ``staggered`` (two shared cells at positions that differ
by cart), with the classes of interchangeable agents the search exploits (their sizes),
wall and CPU time, nodes, length, proven lower bound, exact yes/no and the gap. ``--max-nodes`` and
``--time-limit`` are the search budget (``none``: no limit).

Measures :func:`twostep.makespan.parallel_length` (bit-set states, A* with the pair-
projection bound and dominance pruning) against a straightforward implementation: A*
with the longest-remaining-plan bound over every compatible set of agents, in which each
joint step is checked with unified-planning's ``SequentialSimulator`` (applicability and
successor per action on a UP state; two actions are compatible when each stays
applicable after the other and both orders reach the same state). The column ``plain``
runs that same straightforward search on our bit-set states (same nodes as the UP
baseline), so ``UP / plain`` is the gain of the representation alone and
``plain / twostep`` the gain of the bound and the pruning.

The plans come from a generated toy domain: each agent drives its own cart along a private
track of 60 cells. ``independent``: tracks never meet. ``shared``: all four tracks cross
one hub cell, and two pairs of tracks also share a crossing cell further on, so carts must
queue at the shared cells and the search has to choose who goes first. Agents plan with
the agent-specific predicate ``ready``; the UP baseline uses the equivalent multi-agent
encoding (``ready`` and ``move`` get an agent parameter) so one UP state holds every copy.

The baseline is slow: it runs on 8, 15, 30 and 60 steps per agent in turn and stops
before the size that would exceed ``--budget`` seconds (or at the one that did); the
comparison row uses the largest size it finished, with ours timed on the same plans.
"""

from __future__ import annotations

import argparse
import heapq
import itertools
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.tracks import (
    AGENT_PREDICATES,
    AGENTS,
    CASES,
    PLAN_LENGTH,
    TRACKS,
    TRACKS_MA,
    Case,
    Instance,
    build,
    shared_case,
    staggered_case,
)
from tools import record
from twostep.makespan import ParallelExecution, parallel_length
from twostep.makespan.compiled import compile_task
from twostep.makespan.model import DEFAULT_MAX_NODES, DEFAULT_TIME_LIMIT_S
from twostep.makespan.parallel import _parallel_length
from twostep.makespan.symmetry import Symmetry
from twostep.pddl import Problem, parse_problem
from twostep.plans.simulate import GroundAction, Grounder


class BudgetExceeded(Exception):
    pass


def up_parallel_length(instance: Instance, mode: str, budget: float) -> tuple[int, int]:
    """Straightforward A*, every check done by UP's SequentialSimulator.

    Returns (length, nodes expanded); raises BudgetExceeded after ``budget`` seconds.
    """
    from unified_planning.io import PDDLReader
    from unified_planning.plans import ActionInstance
    from unified_planning.shortcuts import SequentialSimulator

    problem = PDDLReader().parse_problem_string(TRACKS_MA, instance.multi_agent_problem)
    simulator = SequentialSimulator(problem)
    move = problem.action("move")
    plans = [
        [
            ActionInstance(
                move,
                [problem.object(f"a{agent}")]
                + [problem.object(o) for o in text.strip("()").split()[1:]],
            )
            for text in plan
        ]
        for agent, plan in enumerate(instance.plans)
    ]
    lengths = [len(plan) for plan in plans]
    deadline = time.perf_counter() + budget

    def compatible(state: Any, first: Any, second: Any) -> bool:
        after_first = simulator.apply(state, first)
        after_second = simulator.apply(state, second)
        if after_first is None or after_second is None:
            return False
        both = simulator.apply(after_first, second)
        other_order = simulator.apply(after_second, first)
        return both is not None and other_order is not None and both == other_order

    def successor_sets(indices: tuple[int, ...], state: Any) -> list[tuple[int, ...]]:
        active = [i for i in range(AGENTS) if indices[i] < lengths[i]]
        movable = [i for i in active if simulator.is_applicable(state, plans[i][indices[i]])]
        sets: list[tuple[int, ...]]
        if mode == "paper":
            sets = [(i,) for i in movable]
            if (
                len(active) > 1
                and len(movable) == len(active)
                and all(
                    compatible(state, plans[a][indices[a]], plans[b][indices[b]])
                    for a, b in itertools.combinations(active, 2)
                )
            ):
                sets.append(tuple(active))
            return sets
        ok = {
            (a, b): compatible(state, plans[a][indices[a]], plans[b][indices[b]])
            for a, b in itertools.combinations(movable, 2)
        }
        sets = [()]
        for agent in movable:
            sets += [(*s, agent) for s in sets if all(ok[(o, agent)] for o in s)]
        return [s for s in sets if s]

    start = (tuple(0 for _ in lengths), simulator.get_initial_state())
    closed: set[Any] = set()
    best = {start: 0}
    counter = itertools.count()
    frontier = [(max(lengths), 0, sum(lengths), next(counter), start)]
    expanded = 0
    while frontier:
        if time.perf_counter() > deadline:
            raise BudgetExceeded
        _, minus_g, left, _, node = heapq.heappop(frontier)
        if node in closed:
            continue
        closed.add(node)
        expanded += 1
        g = -minus_g
        indices, state = node
        if left == 0:
            if simulator.is_goal(state):
                return g, expanded
            continue
        for chosen in successor_sets(indices, state):
            child_state = state
            advanced = list(indices)
            for agent in chosen:
                child_state = simulator.apply(child_state, plans[agent][indices[agent]])
                advanced[agent] += 1
            child = (tuple(advanced), child_state)
            if child in closed or best.get(child, g + 2) <= g + 1:
                continue
            best[child] = g + 1
            h = max(n - i for n, i in zip(lengths, advanced, strict=True))
            entry = (g + 1 + h, -g - 1, left - len(chosen), next(counter), child)
            heapq.heappush(frontier, entry)
    raise RuntimeError("the baseline found no schedule")


UP_SIZES = (8, 15, 30, PLAN_LENGTH)
"""Plan lengths tried for the UP baseline, smallest first; the largest that fits is kept."""


def median_seconds(run: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


@dataclass
class Row:
    case: str
    steps_per_agent: int
    mode: str
    exec_length: int
    ours_ms: float
    ours_nodes: int
    plain_ms: float
    plain_nodes: int
    up_ms: float | None = None
    up_nodes: int | None = None
    note: str = ""


def measure_ours(case: Case, length: int, mode: str, repeats: int) -> Row:
    """Median times of parallel_length and of the plain search, from grounded plans."""
    instance = build(case, length)
    problem = parse_problem(TRACKS, instance.single_agent_problem)
    grounder = Grounder(problem)
    plans = [grounder.ground_plan(plan) for plan in instance.plans]

    def run() -> ParallelExecution:
        return parallel_length(plans, problem.init, problem.goal, AGENT_PREDICATES, mode)

    def run_plain() -> ParallelExecution:
        # Bench only: the private entry point switches the bound and the pruning off.
        return _parallel_length(
            plans, problem.init, problem.goal, AGENT_PREDICATES, mode, plain=True
        )

    ours, plain = run(), run_plain()
    assert ours.length == plain.length, (ours, plain)
    return Row(
        case.name,
        length,
        mode,
        ours.length,
        1000 * median_seconds(run, repeats),
        ours.nodes_expanded,
        1000 * median_seconds(run_plain, repeats),
        plain.nodes_expanded,
    )


def measure(case: Case, mode: str, repeats: int, budget: float) -> list[Row]:
    """Ours at full size; the UP baseline at the largest size that fits the budget."""
    full = measure_ours(case, PLAN_LENGTH, mode, repeats)
    compared: Row | None = None
    for length in UP_SIZES:
        start = time.perf_counter()
        try:
            up_length, up_nodes = up_parallel_length(build(case, length), mode, budget)
        except BudgetExceeded:
            break
        seconds = time.perf_counter() - start
        compared = full if length == PLAN_LENGTH else measure_ours(case, length, mode, repeats)
        assert up_length == compared.exec_length, (up_length, compared)
        compared.up_ms, compared.up_nodes = 1000 * seconds, up_nodes
        if seconds * 3 > budget:  # sizes double and nodes grow faster: the next won't fit
            break
    if compared is None:
        full.note = f"UP baseline over budget even at {UP_SIZES[0]} steps/agent"
        return [full]
    if compared is full:
        return [full]
    compared.note = f"UP baseline: largest size within {budget:.0f} s"
    return [full, compared]


def up_call_costs() -> str:
    """Per-call cost of the UP simulator on the 60-step instance, to explain the ratio."""
    from unified_planning.io import PDDLReader
    from unified_planning.plans import ActionInstance
    from unified_planning.shortcuts import SequentialSimulator

    instance = build(CASES[0], PLAN_LENGTH)
    problem = PDDLReader().parse_problem_string(TRACKS_MA, instance.multi_agent_problem)
    simulator = SequentialSimulator(problem)
    state = simulator.get_initial_state()
    args = [problem.object(o) for o in instance.plans[0][0].strip("()").split()[1:]]
    action = ActionInstance(problem.action("move"), [problem.object("a0"), *args])
    runs = 200
    applicable = median_seconds(lambda: simulator.is_applicable(state, action), runs)
    apply = median_seconds(lambda: simulator.apply(state, action), runs)
    apply_hash = median_seconds(lambda: hash(simulator.apply(state, action)), runs)
    return (
        f"UP simulator per call on the {PLAN_LENGTH}-step instance: is_applicable "
        f"{1000 * applicable:.2f} ms, apply {1000 * apply:.2f} ms, hashing the new state "
        f"(duplicate detection) {1000 * (apply_hash - apply):.2f} ms"
    )


SCALING_AGENTS = (2, 4, 6, 8, 10, 12, 14, 16)
SCALING_LENGTHS = (30, 60, 100)


def class_sizes(plans: Sequence[Sequence[GroundAction]], problem: Problem) -> str:
    """Sizes of the classes of interchangeable agents, e.g. ``5+5+4`` (``-``: none)."""
    task = compile_task(plans, problem.init, problem.goal, AGENT_PREDICATES)
    sizes = sorted((len(members) for members in Symmetry(task).classes), reverse=True)
    return "+".join(map(str, sizes)) or "-"


def scaling(
    max_nodes: int | None, time_limit_s: float | None, rows: list[dict[str, Any]] | None = None
) -> int:
    """The scaling table: exact mode, N = 2..16 agents, 30/60/100 steps per agent (each
    row also appended to ``rows``)."""
    print(
        f"exact mode, one run each, node budget {max_nodes}, time budget {time_limit_s} s; "
        "grounding not timed; CPU time is this process's (the machine may be shared: "
        f"load average at the start {' '.join(f'{x:.1f}' for x in os.getloadavg())})"
    )
    columns = (
        "case",
        "N",
        "steps/agent",
        "interchangeable",
        "wall ms",
        "CPU ms",
        "nodes",
        "length",
        "lower bound",
        "exact",
        "gap",
        "hand-derived",
    )
    print()
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    worst: dict[int, tuple[float, float]] = {}
    stopped: list[str] = []
    for make in (shared_case, staggered_case):
        for agents in SCALING_AGENTS:
            for length in SCALING_LENGTHS:
                case = make(agents)
                instance = build(case, length, agents)
                problem = parse_problem(TRACKS, instance.single_agent_problem)
                grounder = Grounder(problem)
                plans = [grounder.ground_plan(plan) for plan in instance.plans]
                start, cpu_start = time.perf_counter(), time.process_time()
                # parallel_length re-validates the schedule (check_schedule) before returning.
                result = parallel_length(
                    plans,
                    problem.init,
                    problem.goal,
                    AGENT_PREDICATES,
                    max_nodes=max_nodes,
                    time_limit_s=time_limit_s,
                )
                ms = 1000 * (time.perf_counter() - start)
                cpu_ms = 1000 * (time.process_time() - cpu_start)
                if agents in (8, 16):
                    wall, cpu = worst.get(agents, (0.0, 0.0))
                    worst[agents] = (max(wall, ms), max(cpu, cpu_ms))
                # Shared case by hand: every cart holds the hub two steps (enter, leave),
                # the last one enters 2 (N - 1) steps late, and the crossings add nothing.
                derived = str(length + 2 * (agents - 1)) if case.name == "shared" else "-"
                cells = [
                    case.name,
                    str(agents),
                    str(length),
                    class_sizes(plans, problem),
                    f"{ms:.0f}",
                    f"{cpu_ms:.0f}",
                    str(result.nodes_expanded),
                    str(result.length),
                    str(result.lower_bound),
                    "yes" if result.exact else "no",
                    str(result.gap),
                    derived,
                ]
                print("| " + " | ".join(cells) + " |", flush=True)
                if rows is not None:
                    rows.append({"case": case.name, "agents": agents, "steps_per_agent": length,
                                 "interchangeable": cells[3], "wall_ms": ms, "cpu_ms": cpu_ms,
                                 "nodes": result.nodes_expanded, "length": result.length,
                                 "lower_bound": result.lower_bound, "exact": result.exact,
                                 "gap": result.gap,
                                 "hand_derived": None if derived == "-" else int(derived)})  # fmt: skip
                if not result.exact:
                    stopped.append(
                        f"{case.name} N = {agents}, {length} steps: length {result.length}, "
                        f"proven lower bound {result.lower_bound} (gap {result.gap})"
                    )
    print()
    print(f"load average at the end: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    for agents, (wall, cpu) in sorted(worst.items()):
        verdict = "met" if cpu < 1000 else "NOT met"
        print(
            f"N = {agents}: worst {wall:.0f} ms wall, {cpu:.0f} ms CPU over both cases and "
            f"lengths (goal < 1 s of CPU: {verdict})"
        )
    print(f"stopped at the budget (schedule valid, optimality not proven): {len(stopped)}")
    for line in stopped:
        print(f"  {line}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per measurement")
    parser.add_argument("--budget", type=float, default=30.0, help="seconds per UP baseline run")
    parser.add_argument(
        "--scaling",
        action="store_true",
        help="print only the scaling table (N = 2..16 agents, 30/60/100 steps)",
    )
    parser.add_argument(
        "--max-nodes",
        type=lambda text: None if text == "none" else int(text),
        default=DEFAULT_MAX_NODES,
        help="node budget of the search in the scaling table ('none': no limit)",
    )
    parser.add_argument(
        "--time-limit",
        type=lambda text: None if text == "none" else float(text),
        default=DEFAULT_TIME_LIMIT_S,
        help="time budget of the search in the scaling table, seconds ('none': no limit)",
    )
    parser.add_argument("--json", type=Path, help="also write the rows here (a bench record)")
    args = parser.parse_args(argv)
    command = " ".join(argv if argv is not None else sys.argv[1:])
    run = record.started(None if argv is None else ["bench/bench_execution.py", *argv])
    if args.scaling:
        print(f"$ python bench/bench_execution.py {command}".rstrip())
        print(f"python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs")
        scaled: list[dict[str, Any]] = []
        code = scaling(args.max_nodes, args.time_limit, scaled)
        if args.json:
            budget = {"max_nodes": args.max_nodes, "time_limit_s": args.time_limit}
            record.write(args.json, run, scaled, table="scaling", budget=budget)
        return code
    from unified_planning.shortcuts import get_environment

    get_environment().credits_stream = None
    print(f"$ python bench/bench_execution.py {command}".rstrip())
    print(
        f"python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs; "
        f"N = {AGENTS} agents; median of {args.repeats} runs (UP: one run, "
        f"budget {args.budget:.0f} s)"
    )
    rows = [
        row
        for case in CASES
        for mode in ("exact", "paper")
        for row in measure(case, mode, args.repeats, args.budget)
    ]
    columns = (
        "case",
        "steps/agent",
        "mode",
        "exec length",
        "twostep ms (nodes)",
        "plain ms (nodes)",
        "UP simulator ms (nodes)",
        "UP / twostep",
        "UP / plain",
        "note",
    )
    print()
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for row in rows:
        up = row.up_ms is not None
        cells = [
            row.case,
            str(row.steps_per_agent),
            row.mode,
            str(row.exec_length),
            f"{row.ours_ms:.1f} ({row.ours_nodes})",
            f"{row.plain_ms:.1f} ({row.plain_nodes})",
            f"{row.up_ms:.0f} ({row.up_nodes})" if up else "-",
            f"{row.up_ms / row.ours_ms:.0f}x" if row.up_ms is not None else "-",
            f"{row.up_ms / row.plain_ms:.0f}x" if row.up_ms is not None else "-",
            row.note,
        ]
        print("| " + " | ".join(cells) + " |")
    print()
    print(up_call_costs())
    worst = max(r.ours_ms for r in rows if r.steps_per_agent == PLAN_LENGTH and r.mode == "exact")
    verdict = "met" if worst < 1000 else "NOT met"
    print(
        f"exact mode, N = {AGENTS}, {PLAN_LENGTH}-step plans: worst median {worst:.1f} ms "
        f"(goal < 1000 ms: {verdict})"
    )
    if args.json:
        record.write(args.json, run, [asdict(r) for r in rows], table="comparison",
                     agents=AGENTS, repeats=args.repeats, budget_s=args.budget)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
