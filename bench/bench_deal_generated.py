"""plan-deal on generated problems of the IPC sample's domains (not only the sample's p01).

The problems come from :mod:`twostep.generators.ipc_sample` (generators of our own for
seven domains of the IPC sample, and the sizes run here). The domain files are read from the
sample (``--sample``, default ../shared/ipc-sample): at run time each is copied into a
scratch folder and the generated problems are written beside it, so nothing of the sample
lands in the repository.

For each problem (sizes below, ``--seeds`` seeds each): the SA plan (lama-first,
``--time-limit`` s, the repo's planner; a problem it does not solve is skipped and
counted), then plan-deal for N = 2, 3, 4 (``--agents``) with the agent predicates of
:data:`AGENT_PREDICATES` (agents.yaml's, and the issue's for storage and floortile). Every
schedule, a fallback to the SA plan included, is re-validated by ``check_run`` and by the
independent validator on the generated files (``checkers``).

One row per problem: SA length, plan-deal length per N, the fallback reasons, both
verdicts, the dealing CPU seconds per N (plan-deal's own ``deal_seconds``: every phase after
the SA plan) and, in brackets, the CPU seconds of the whole ``run_plan_deal`` call measured
here (grounding the task and cleaning the plan included); then a summary per
domain: runs, dealt shorter than SA, fallbacks by reason, crashes, invalid schedules,
monotonicity violations (N longer than N-1, N = 1 being the SA plan) and the largest
dealing time.

    .venv/bin/python bench/bench_deal_generated.py --seeds 5 --json docs/bench/deal_generated.json
    .venv/bin/python bench/bench_deal_generated.py --domains storage --seeds 1 --sizes 1
    .venv/bin/python bench/bench_deal_generated.py --domains storage --only d1:c8:h3 \\
        --seed-list 1 --agents 2 --keep /tmp/generated

The last reproduces one row: ``--only`` takes the size label of the table, ``--seed-list``
the seed; ``--keep`` also writes the generated problem files into a folder.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from checkers import IndependentValidator
from evaluation.deal_checks import (
    deal_seconds,
    deal_within,
    fallback_text,
    independent_verdict,
    our_verdict,
)
from tools import record
from twostep.generators.ipc_sample import AGENT_PREDICATES, SIZES, Generated
from twostep.methods import MethodRequest, run_single_agent
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import BenchmarkTask, load_task

REPO = Path(__file__).resolve().parent.parent
SAMPLE = REPO.parent / "shared" / "ipc-sample"


@dataclass
class Row:
    domain: str
    size: str
    seed: int
    sa: int | None = None
    lengths: dict[int, int | None] = field(default_factory=dict)  # None: crash
    fallbacks: dict[int, str] = field(default_factory=dict)
    ours: dict[int, str] = field(default_factory=dict)
    independent: dict[int, str] = field(default_factory=dict)
    cpu: dict[int, float] = field(default_factory=dict)  # plan-deal's own deal_seconds
    process_cpu: dict[int, float] = field(default_factory=dict)  # the whole call, measured here
    skipped: str = ""


def run_problem(
    task: BenchmarkTask,
    row: Row,
    preds: list[str],
    planner: PlannerSettings,
    agent_counts: Sequence[int],
    deal_limit: int,
) -> Row:
    sa = run_single_agent(MethodRequest(task, planner=planner))
    if sa.exec_length is None:
        row.skipped = f"no SA plan ({sa.message[:70]})"
        return row
    row.sa = sa.exec_length
    sa_plan = sa.planner_calls[0].result
    validator = IndependentValidator(task.domain_path, task.problem_path)
    for agents in agent_counts:
        request = MethodRequest(task, agents, planner, preds, sa_plan=sa_plan)
        start = time.process_time()
        run = deal_within(request, deal_limit, 90)
        if isinstance(run, str):
            row.lengths[agents] = None
            row.fallbacks[agents] = f"CRASH {run}"
            row.cpu[agents] = time.process_time() - start
            continue
        row.lengths[agents] = run.exec_length
        row.fallbacks[agents] = fallback_text(run, none="", width=90)
        row.ours[agents] = our_verdict(task, run, preds)
        row.independent[agents] = independent_verdict(validator, run, preds)
        row.cpu[agents] = deal_seconds(run)
        row.process_cpu[agents] = time.process_time() - start
    return row


def violations(row: Row, agent_counts: Sequence[int]) -> list[str]:
    """N longer than N-1 (N-1 = 1: the SA plan)."""
    found = []
    previous, label = row.sa, 1
    for agents in sorted(agent_counts):
        length = row.lengths.get(agents)
        if length is not None and previous is not None and length > previous:
            found.append(f"N={agents} {length} > N={label} {previous}")
        if length is not None:
            previous, label = length, agents
    return found


def format_row(row: Row, agent_counts: Sequence[int]) -> str:
    if row.skipped:
        return f"{row.domain} | {row.size} | {row.seed} | SKIPPED: {row.skipped}"
    lengths = "/".join(
        "CRASH" if row.lengths.get(n) is None else str(row.lengths[n]) for n in agent_counts
    )
    falls = "; ".join(f"N={n}: {row.fallbacks[n]}" for n in agent_counts if row.fallbacks.get(n))
    ours = _verdicts(row.ours, agent_counts)
    independent = _verdicts(row.independent, agent_counts)
    cpu = "/".join(f"{row.cpu.get(n, 0):.2f}" for n in agent_counts)
    cpu += " (call " + "/".join(f"{row.process_cpu.get(n, 0):.2f}" for n in agent_counts) + ")"
    cells = (row.domain, row.size, row.seed, row.sa, lengths, falls or "-", ours, independent, cpu)
    return " | ".join(str(c) for c in cells)


def _verdicts(verdicts: dict[int, str], agent_counts: Sequence[int]) -> str:
    """``ok`` when every N's verdict is ok (the checkers that read the files once), else each."""
    values = [verdicts.get(n, "-") for n in agent_counts]
    if all(v.startswith("ok") for v in values) and len(set(values)) == 1:
        return values[0]
    return "; ".join(f"N={n}: {v}" for n, v in zip(agent_counts, values, strict=True))


def summary(domain: str, rows: list[Row], agent_counts: Sequence[int]) -> list[str]:
    done = [r for r in rows if not r.skipped]
    runs = [(r, n) for r in done for n in agent_counts]
    shorter = sum(  # dealt: no fallback (the cleaned SA plan may be shorter than SA too)
        1
        for r, n in runs
        if not r.fallbacks.get(n) and (k := r.lengths.get(n)) is not None and k < (r.sa or 0)
    )
    reasons = Counter(r.fallbacks[n].split(" [")[0] for r, n in runs if r.fallbacks.get(n))
    crashes = sum(1 for r, n in runs if r.lengths.get(n) is None)
    invalid = sum(
        1
        for r, n in runs
        if "INVALID" in r.ours.get(n, "") or "INVALID" in r.independent.get(n, "")
    )
    monotone = sum(len(violations(r, agent_counts)) for r in done)
    slowest = max((r.cpu.get(n, 0.0) for r, n in runs), default=0.0)
    whole = max((r.process_cpu.get(n, 0.0) for r, n in runs), default=0.0)
    lines = [
        f"{domain}: {len(rows)} problems, {len(rows) - len(done)} skipped (no SA plan); "
        f"{len(runs)} runs, {shorter} dealt shorter than SA, {crashes} crashed, "
        f"{invalid} invalid, {monotone} monotonicity violations, max deal CPU {slowest:.2f} s "
        f"(the whole plan-deal call: {whole:.2f} s)"
    ]
    for reason, count in reasons.most_common():
        if not reason.startswith("CRASH"):
            lines.append(f"  fallback x{count}: {reason}")
    return lines


def problems(
    domain: str, seeds: Sequence[int], only: Sequence[str] | None, max_sizes: int | None
) -> Iterator[tuple[str, int, Generated]]:
    sizes = SIZES[domain][:max_sizes] if max_sizes else SIZES[domain]
    for label, make in sizes:
        if only and label not in only:
            continue
        for seed in seeds:
            yield label, seed, make(seed)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sample", type=Path, default=SAMPLE)
    parser.add_argument("--domains", nargs="*", default=list(SIZES), choices=list(SIZES))
    parser.add_argument("--seeds", type=int, default=2, help="seeds per size: 1..SEEDS")
    parser.add_argument("--seed-list", type=int, nargs="*", help="these seeds instead")
    parser.add_argument("--sizes", type=int, help="only the first SIZES sizes of each domain")
    parser.add_argument("--only", nargs="*", help="only these size labels (as in the table)")
    parser.add_argument("--agents", type=int, nargs="*", default=[2, 3, 4])
    parser.add_argument("--time-limit", type=float, default=30.0, help="SA planner seconds")
    parser.add_argument("--deal-limit", type=int, default=60, help="seconds per plan-deal run")
    parser.add_argument("--keep", type=Path, help="also write the generated files here")
    parser.add_argument("--json", type=Path, help="also write what it prints as a record here")
    args = parser.parse_args(argv)
    with record.capture(args.json, title="plan-deal on generated problems of seven IPC domains"):
        return _run(args, argv)


def _run(args: argparse.Namespace, argv: Sequence[str] | None) -> int:
    seeds = args.seed_list or list(range(1, args.seeds + 1))
    planner = PlannerSettings("lama-first", args.time_limit)
    shown = " ".join(argv if argv is not None else sys.argv[1:])
    print(f".venv/bin/python bench/bench_deal_generated.py {shown}".rstrip())
    print(f"sample domains of {args.sample.name}, problems of our own generators; "
          f"SA lama-first {args.time_limit:g} s; plan-deal N = "
          f"{'/'.join(map(str, args.agents))}")  # fmt: skip
    header = ("domain", "size", "seed", "SA", "plan-deal N=" + "/".join(map(str, args.agents)),
              "fallback", "check_run", "independent validator", "deal CPU s (whole call)")  # fmt: skip
    print(" | ".join(header), flush=True)
    began = time.perf_counter()
    summaries: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp)
        for domain in args.domains:
            folder = scratch / domain
            folder.mkdir()
            shutil.copy(args.sample / domain / "domain.pddl", folder / "domain.pddl")
            rows = []
            for number, (label, seed, generated) in enumerate(
                problems(domain, seeds, args.only, args.sizes), 1
            ):
                path = folder / f"p{number:02d}.pddl"
                path.write_text(generated.text)
                if args.keep:
                    (args.keep / domain).mkdir(parents=True, exist_ok=True)
                    kept = f"{label.replace(':', '_')}-s{seed}.pddl"
                    shutil.copy(path, args.keep / domain / kept)
                row = Row(domain, label, seed)
                try:
                    task = load_task(domain, number, scratch)
                    run_problem(task, row, AGENT_PREDICATES[domain], planner, args.agents,
                                args.deal_limit)  # fmt: skip
                except Exception as error:  # the SA run or the reading: the row says so
                    row.skipped = f"error {type(error).__name__}: {str(error)[:90]}"
                rows.append(row)
                print(format_row(row, args.agents), flush=True)
                for found in violations(row, args.agents):
                    print(f"  monotonicity: {found}")
            summaries += summary(domain, rows, args.agents)
    print("summary per domain:")
    print("\n".join(summaries))
    print(f"total {time.perf_counter() - began:.0f} s wall")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
