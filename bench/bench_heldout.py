"""A held-out data root from the LLM+P benchmark files (the paper's own task files), for
``bench/bench_methods.py``.

The TwoStep paper's symbolic tasks are the LLM+P benchmark's (github.com/Cranial-XIX/llm-pddl,
``domains/<domain>/p01.pddl`` ... ``p20.pddl``); this repository ships none of them. Given a
checkout of that repository, this script lays them out as a data root (``<out>/<domain>/``
with ``domain.pddl`` and the problems, copied as they are) so that the methods bench runs on
them exactly as on ``data/``:

    git clone https://github.com/Cranial-XIX/llm-pddl /tmp/llm-pddl
    python bench/bench_heldout.py --llmp /tmp/llm-pddl --out /tmp/llmp
    python bench/bench_methods.py --data /tmp/llmp --agents 2 3 4 --methods plan-deal \\
        --domains barman blocksworld grippers termes tyreworld storage floortile \\
        --agent-predicates bench/heldout_agents.yaml --out outputs/bench/methods_heldout.json

Then every schedule again, checked by the independent validator (``checkers``:
Fast Downward's translation simulated apart, and unified-planning where it reads the files):

    python bench/bench_heldout.py --validate /tmp/llmp \
        --rows outputs/bench/methods_heldout.json --agents 2 3 4

It deals each stored SA plan again with plan-deal (no planner call) and checks the schedule;
LLM+P's tyreworld domain names ``wrench``, ``jack`` and ``pump``, which only its problems
declare, so the checkers read copies with those moved to the domain's constants.

Our domains read LLM+P's problem files as they are; the cross-check shows it, for every
task of barman, blocksworld, grippers, termes and tyreworld:

    python bench/bench_heldout.py --cross /tmp/llmp

loads each problem with our domain (``data/<domain>/domain.pddl``) and with theirs, plans
both with lama-first (60 s), and checks each plan on the other domain's task with twostep's
simulator and with the independent validator (their tyreworld: read with the tools moved
to its constants, as ``--validate`` does; ours: with the problem's second declaration of
our constants left out). LLM+P's blocksworld folder has no domain file: its problems are
read with ours alone, planned, and each plan checked on our domain and the problem file as
written. It prints a line per task and a summary per domain, and writes them to
``docs/bench/faithful_cross.txt`` (``--report``) under the command line; ``--domains``
picks some of the domains.

LLM+P's blocksworld problems are untyped and name the domain ``blocksworld-4ops``, as
``data/blocksworld/domain.pddl`` is and does, so the layout gives that folder our domain
file as it is. Storage and floortile are not among our domains: their agent predicates are
in ``bench/heldout_agents.yaml``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.heldout import (
    CROSS_DOMAINS,
    CROSS_TIME_LIMIT_S,
    DOMAINS,
    REPO,
    cross_check,
    cross_table,
    prepare,
    validate,
)


def run_cross(root: Path, domains: tuple[str, ...], report: Path | None, command: str) -> int:
    """The cross-check, printed and written to ``report`` under ``command``."""
    lines = [f"$ {command}", f"lama-first {CROSS_TIME_LIMIT_S:.0f} s per planner call", ""]

    def say(line: str) -> None:
        print(line, flush=True)
        lines.append(line)

    summary = cross_check(root, domains, say)
    lines.append("")
    for line in cross_table(summary):
        print(line)
        lines.append(line)
    if report is not None:
        report.parent.mkdir(parents=True, exist_ok=True)
        report.write_text("\n".join(lines) + "\n")
    complete = all(
        c["valid ours" if c["ours_only"] else "valid both ways"] == c["tasks"]
        for c in summary.values()
    )
    return 0 if complete else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--llmp", type=Path, help="a checkout of llm-pddl")
    parser.add_argument("--out", type=Path, help="the data root to write")
    parser.add_argument("--domains", nargs="*", default=list(DOMAINS))
    parser.add_argument("--validate", type=Path, help="a data root made by this script")
    parser.add_argument("--rows", type=Path, help="the methods bench's rows of that root")
    parser.add_argument("--agents", nargs="*", type=int, default=[2, 3, 4])
    parser.add_argument("--cross", type=Path, help="a data root of LLM+P's files: cross-check")
    parser.add_argument(
        "--report",
        type=Path,
        default=REPO / "docs" / "bench" / "faithful_cross.txt",
        help="where --cross writes its output (default: docs/bench/faithful_cross.txt)",
    )
    args = parser.parse_args(argv)
    if args.cross:
        domains = tuple(d for d in args.domains if d in CROSS_DOMAINS)
        shown = ["python bench/bench_heldout.py", *(argv if argv is not None else sys.argv[1:])]
        return run_cross(args.cross, domains, args.report, " ".join(shown))
    if args.validate:
        if args.rows is None:
            parser.error("--validate needs --rows")
        from tools import record

        counts = validate(args.validate, record.rows_of(args.rows), tuple(args.agents))
        for what, n in sorted(counts.items()):
            print(f"{what}: {n}")
        return 0 if counts["not valid"] == 0 else 1
    if args.llmp is None or args.out is None:
        parser.error("--llmp and --out (or --validate and --rows)")
    try:
        counts = prepare(args.llmp, args.out, tuple(args.domains))
    except (FileNotFoundError, ValueError) as error:
        print(f"bench_heldout: {error}", file=sys.stderr)
        return 2
    for domain, n in counts.items():
        print(f"{args.out / domain}: {n} problems")
    return 0


if __name__ == "__main__":
    sys.exit(main())
