"""``twostep-score``: the parallel execution length of per-agent plan files.

    twostep-score DOMAIN PROBLEM PLAN [PLAN ...] [--agent-predicates P,Q] [--mode exact|paper]
                  [--max-nodes N|none] [--time-limit S|none]

Plan files are in Fast Downward's format (one ``(action args)`` per line, ``;`` comments),
one per agent, given in hand-off order; agents are named ``agent0``, ``agent1``, ... in the
order of the PLAN arguments. Prints one JSON object on stdout::

    {"exec_length": 5, "schedule": [[["agent0", "(pickup b1)"], ...], ...], "valid": true,
     "exact": true, "lower_bound": 5, "gap": 0}

``exact`` is false when the search stopped at its budget (``--max-nodes`` nodes or
``--time-limit`` seconds): the schedule is still valid, ``exec_length`` is then an upper
bound and ``lower_bound`` a proven lower bound on the shortest length, ``gap`` their
difference (stderr says so too).

Exit codes: 0 valid, 1 the plans cannot be executed (stderr says which agent, step and
precondition), 2 bad input (malformed PDDL, unreadable or malformed plan file).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path

from twostep.cli import console_main
from twostep.makespan import DEFAULT_SEARCH_BUDGET, MODES, ScheduleError, parallel_length
from twostep.pddl import PDDLError
from twostep.plans.simulate import Grounder, PlanError, read_plan
from twostep.programs.processes import ResourceLimitError
from twostep.tasks.benchmark import load_pddl_files
from twostep.util.files import NotTextError, read_text_file

EXIT_VALID = 0
EXIT_INVALID_PLANS = 1
EXIT_BAD_INPUT = 2

PROG = "twostep-score"


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Parallel execution length of per-agent plans (the TwoStep paper's "
        "metric): the fewest time steps in which the agents' plans can run together.",
    )
    parser.add_argument("domain", type=Path, help="PDDL domain file")
    parser.add_argument("problem", type=Path, help="PDDL problem file")
    parser.add_argument(
        "plans",
        type=Path,
        nargs="+",
        metavar="PLAN",
        help="one plan file per agent (Fast Downward format), in hand-off order",
    )
    parser.add_argument(
        "--agent-predicates",
        default=None,
        metavar="P,Q",
        help="comma-separated agent-specific predicates: each agent has its own copy "
        "(e.g. arm-empty,holding for blocksworld); 'none': every fact is shared (what "
        "leaving it out means too, with a note on stderr)",
    )
    parser.add_argument(
        "--mode",
        choices=MODES,
        default="exact",
        help="exact: any set of agents per step (optimal); paper: one agent or all "
        "(the paper's Algorithm 1). Default: exact",
    )
    parser.add_argument(
        "--max-nodes",
        type=_limit(int),
        default=DEFAULT_SEARCH_BUDGET.max_nodes,
        metavar="N",
        help="the search's budget in expanded nodes, 'none' for no limit; past it "
        "the best schedule found is printed with exact=false and a proven lower_bound "
        f"(default: {DEFAULT_SEARCH_BUDGET.max_nodes})",
    )
    parser.add_argument(
        "--time-limit",
        type=_limit(float),
        default=DEFAULT_SEARCH_BUDGET.time_limit_s,
        metavar="S",
        help="the search's time budget in seconds, 'none' for no limit "
        f"(default: {DEFAULT_SEARCH_BUDGET.time_limit_s:g})",
    )
    parser.add_argument(
        "--cache-dir",
        type=Path,
        default=default_cache_dir(),
        help="keep parsed tasks here, keyed by file contents and parser code, so that later "
        "calls on the same files skip parsing (default: $TWOSTEP_CACHE_DIR, else "
        "$XDG_CACHE_HOME/twostep/tasks or ~/.cache/twostep/tasks)",
    )
    parser.add_argument("--no-cache", action="store_true", help="always parse the PDDL files")
    return parser


def _limit(kind: type[int] | type[float]) -> Callable[[str], int | float | None]:
    """An argparse type: a number >= 0 of ``kind``, or ``none`` for no limit."""

    def parse(text: str) -> int | float | None:
        if text.strip().lower() == "none":
            return None
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number or 'none', got {text!r}") from None
        if value < 0:
            raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
        return value

    return parse


def default_cache_dir() -> Path:
    """Where parsed tasks are kept between calls (see ``--cache-dir``)."""
    if os.environ.get("TWOSTEP_CACHE_DIR"):
        return Path(os.environ["TWOSTEP_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "twostep" / "tasks"


def _fail(message: str) -> int:
    print(f"{PROG}: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


@console_main
def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        problem = load_pddl_files(
            args.domain, args.problem, cache_dir=None if args.no_cache else args.cache_dir
        )
    except (PDDLError, ResourceLimitError) as error:
        return _fail(str(error))
    if args.agent_predicates is None:
        print(
            f"{PROG}: no --agent-predicates: every fact is shared by all agents (name the "
            "agent-specific predicates, e.g. --agent-predicates arm-empty,holding, or say "
            "--agent-predicates none)",
            file=sys.stderr,
        )
    given = "" if args.agent_predicates in (None, "none") else args.agent_predicates
    agent_predicates = [p.strip().lower() for p in given.split(",") if p.strip()]
    unknown = [p for p in agent_predicates if p not in problem.domain.predicates]
    if unknown:
        known = ", ".join(sorted(problem.domain.predicates))
        return _fail(f"unknown agent predicate(s) {', '.join(unknown)}; the domain has {known}")
    grounder = Grounder(problem)
    plans = []
    for path in args.plans:
        try:
            plans.append(grounder.ground_plan(read_plan(read_text_file(path))))
        except NotTextError as error:
            return _fail(f"{error}: expected a plan")
        except OSError as error:
            return _fail(f"{path}: cannot read plan: {error.strerror or error}")
        except PlanError as error:
            return _fail(f"{path}: {error}")
    try:
        result = parallel_length(
            plans,
            problem.init,
            problem.goal,
            agent_predicates,
            args.mode,
            max_nodes=args.max_nodes,
            time_limit_s=args.time_limit,
        )
    except ScheduleError as error:
        if error.precondition is not None and error.agent is not None:
            message = (
                f"agent{error.agent} ({args.plans[error.agent]}) step {error.step} "
                f"{error.action}: precondition {error.precondition} does not hold"
            )
        else:
            message = str(error)
        print(json.dumps({"exec_length": None, "schedule": [], "valid": False, "error": message}))
        print(f"{PROG}: invalid plans: {message}", file=sys.stderr)
        return EXIT_INVALID_PLANS
    schedule = [[[f"agent{agent}", action] for agent, action in step] for step in result.steps]
    print(
        json.dumps(
            {
                "exec_length": result.length,
                "schedule": schedule,
                "valid": True,
                "exact": result.exact,
                "lower_bound": result.lower_bound,
                "gap": result.gap,
            }
        )
    )
    if not result.exact:
        print(
            f"{PROG}: the search stopped at its budget: length {result.length} is not proven "
            f"shortest; proven lower bound {result.lower_bound} (gap {result.gap})",
            file=sys.stderr,
        )
    return EXIT_VALID


if __name__ == "__main__":
    raise SystemExit(main())
