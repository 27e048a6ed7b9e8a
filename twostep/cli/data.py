"""``twostep-data``: build, check and scale the benchmark tasks in ``data/``.

``generate`` rewrites the committed set (p01..p20 and the example of each domain, and
the embodied kitchen domain ``alfworld``: p01..p04, its floor plan) from the seeded
generators; ``check`` verifies that a data folder is exactly what
``generate`` would write; ``scale`` writes larger tasks for scaling benchmarks into a
folder of the same layout; ``example-plan`` re-plans an in-context example (whose plan
is a static file of the package). Hand-written files (``expert.yaml``) are never touched.

``import-answers`` reads logs of real model answers (the official TwoStep code's run
logs: ``--format twostep-official``) into a replay bundle (:mod:`twostep.replay`), whose
answers the LLM client replays (``LLMSettings.mode="bundle"``; running a job or the
paper's grid on it: docs/how-to/reproduce-paper.md); ``check-answers``
checks the rules translator on a bundle against the helper costs its logs record
(:mod:`twostep.replay.check`) and writes ``translation_check.json`` beside it.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from twostep.cli import console_main
from twostep.generators import (
    DOMAINS,
    GENERATORS,
    alfworld,
    benchmark_files,
    example_task,
    scale_files,
    static_file,
)
from twostep.pddl import parse_problem
from twostep.tasks.benchmark import DEFAULT_DATA_ROOT
from twostep.util.files import file_problem, read_input_bytes, write_text_atomic

EXAMPLE_ALIAS = "seq-opt-lmcut"  # shortest plans make the clearest in-context examples
# The benchmark domains, then the embodied kitchen (its own generator: tasks + floor plan).
DATA_DOMAINS = (*DOMAINS, alfworld.DOMAIN)


def domain_files(domain: str, seed: int) -> dict[str, str]:
    """Every generated file of ``data/<domain>`` (the paper's kitchen tasks are fixed)."""
    if domain == alfworld.DOMAIN:
        return alfworld.data_files()
    return benchmark_files(domain, seed)


def write_files(folder: Path, files: dict[str, str]) -> int:
    """Write ``files`` into ``folder``; return how many changed."""
    folder.mkdir(parents=True, exist_ok=True)
    changed = 0
    for name, text in files.items():
        path = folder / name
        # a FIFO or a device there is replaced, never opened (opening a FIFO blocks)
        same = (
            file_problem(path) is None
            and path.is_file()
            and read_input_bytes(path) == text.encode()
        )
        if not same:
            write_text_atomic(path, text)
            changed += 1
    return changed


def compare_files(folder: Path, files: dict[str, str]) -> list[str]:
    """One line per file of ``files`` that is missing from ``folder`` or differs."""
    problems = []
    for name, text in files.items():
        path = folder / name
        bad = file_problem(path)  # a FIFO, a device, a directory, a loop: never opened
        if bad is not None:
            problems.append(bad)
            continue
        if not path.is_file():
            problems.append(f"{path}: missing")
            continue
        try:
            found = read_input_bytes(path).decode("utf-8")  # byte for byte: a BOM differs
        except UnicodeDecodeError as error:
            problems.append(f"{path}: not a text file (byte {error.start} is not UTF-8)")
            continue
        if found == text:
            continue
        want, have = text.splitlines(), found.splitlines()
        line = next(
            (i for i, (a, b) in enumerate(zip(want, have, strict=False)) if a != b),
            min(len(want), len(have)),
        )
        expected = want[line] if line < len(want) else "<end of file>"
        actual = have[line] if line < len(have) else "<end of file>"
        problems.append(f"{path}:{line + 1}: expected {_clip(expected)!r}, found {_clip(actual)!r}")
    return problems


def _clip(text: str, limit: int = 100) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _generate(args: argparse.Namespace) -> int:
    for domain in args.domain or DATA_DOMAINS:
        files = domain_files(domain, args.seed)
        changed = write_files(Path(args.out) / domain, files)
        print(f"{domain}: {len(files)} files, {changed} written")
    return 0


def _check(args: argparse.Namespace) -> int:
    problems: list[str] = []
    for domain in args.domain or DATA_DOMAINS:
        problems += compare_files(Path(args.data) / domain, domain_files(domain, args.seed))
    if problems:
        print(f"{len(problems)} file(s) do not match the generators:", file=sys.stderr)
        for line in problems:
            print(f"  {line}", file=sys.stderr)
        print("run 'twostep-data generate' to rebuild them", file=sys.stderr)
        return 1
    print(f"{args.data}: every generated file matches")
    return 0


def _scale(args: argparse.Namespace) -> int:
    if args.size < 2 or args.count < 1:
        print("error: --size must be at least 2 and --count at least 1", file=sys.stderr)
        return 2
    if args.domain == alfworld.DOMAIN:
        files = alfworld.scale_files(args.size, args.count, args.seed)
        unit = alfworld.SCALE_UNIT
    else:
        files = scale_files(args.domain, args.size, args.count, args.seed)
        unit = GENERATORS[args.domain].scale_unit
    write_files(Path(args.out), files)
    print(f"{args.out}: {args.count} {args.domain} task(s) with {args.size} {unit}")
    return 0


def _example_plan(args: argparse.Namespace) -> int:
    from twostep.planner import PlannerSettings, plan

    problem = parse_problem(static_file(args.domain, ".pddl"), example_task(args.domain).to_pddl())
    result = plan(problem, PlannerSettings(alias=args.alias, search_time_limit_s=args.time_limit))
    if result.plan is None:
        print(f"error: {args.domain} example not solved: {result.message}", file=sys.stderr)
        return 1
    print("\n".join(result.plan))
    return 0


def _import_answers(args: argparse.Namespace) -> int:
    from twostep.replay.importer import AnswerImportError, import_logs

    try:
        report = import_logs(
            [Path(p) for p in args.logs],
            args.model,
            Path(args.out),
            log_format=args.format,
            tasks=Path(args.tasks) if args.tasks else None,
            append=args.append,
            allow_truncated=args.allow_truncated,
        )
    except AnswerImportError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    for line in report.lines():
        print(line)
    bundle = report.bundle
    subgoals = sum(len(e.answers) for e in bundle.entries)
    print(
        f"{Path(args.out) / 'bundle.json'}: {len(bundle.runs)} run(s), {len(bundle.entries)} "
        f"task answer(s), {subgoals} subgoal(s)"
        + ("" if bundle.tasks else " (no --tasks: the task files are not checked on replay)")
    )
    return 0


CHECK_FILE = "translation_check.json"


def _agent_predicates(domains: Sequence[str], given: str | None) -> dict[str, list[str]]:
    """Each domain's agent predicates: the YAML file given (domain -> list), else the
    installed ``conf/domain/<domain>.yaml`` (the Hydra config's own)."""
    from importlib import resources

    from twostep.util.files import read_yaml_file

    table: dict[str, list[str]] = {}
    if given:
        data = read_yaml_file(Path(given)) or {}
        table = {str(k): [str(p) for p in v or []] for k, v in dict(data).items()}
    for domain in domains:
        if domain in table:
            continue
        conf = resources.files("flows.conf").joinpath("domain", f"{domain}.yaml")
        if not conf.is_file():
            raise ValueError(
                f"no agent predicates for domain '{domain}': give them with --agent-predicates"
            )
        table[domain] = [str(p) for p in read_yaml_file(Path(str(conf)))["agent_predicates"]]
    return table


def _check_answers(args: argparse.Namespace) -> int:
    from twostep.planner import PlannerSettings
    from twostep.replay import BundleError, load_bundle
    from twostep.replay.check import check_entry, settings_text, summarise
    from twostep.tasks.benchmark import BenchmarkError, load_task
    from twostep.util.files import write_json_atomic

    try:
        bundle = load_bundle(args.bundle)
    except BundleError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    entries = [
        e
        for e in bundle.entries
        if (not args.domain or e.domain in args.domain)
        and (not args.agents or e.agents in args.agents)
    ]
    try:
        predicates = _agent_predicates(sorted({e.domain for e in entries}), args.agent_predicates)
    except (ValueError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    settings = PlannerSettings(alias=args.alias, search_time_limit_s=args.time_limit)
    root = Path(args.data_root)
    checks = []
    for number, entry in enumerate(entries, start=1):
        try:
            task = load_task(entry.domain, entry.task, root)
        except BenchmarkError as error:
            print(f"error: {error}", file=sys.stderr)
            return 1
        if bundle.task_digest(entry.domain, entry.task):
            try:
                bundle.check_task_file(entry.domain, entry.task, task.problem_path)
            except LookupError as error:
                print(f"error: {error}", file=sys.stderr)
                return 1
        found = check_entry(entry, task, predicates[entry.domain], settings)
        checks += found
        states = " ".join(c.status for c in found)
        print(
            f"[{number}/{len(entries)}] {entry.domain} p{entry.task:02d} N={entry.agents} "
            f"({entry.run}): {states}",
            flush=True,
        )
    from importlib import metadata

    version = metadata.version("up-fast-downward")
    summary = summarise(checks)
    out = Path(args.out) if args.out else Path(args.bundle) / CHECK_FILE
    write_json_atomic(
        out,
        {
            "bundle": str(args.bundle),
            "data_root": str(root),
            "planner": {
                "alias": settings.alias,
                "search_time_limit_s": settings.search_time_limit_s,
                "up-fast-downward": version,
                "text": settings_text(settings, f"up-fast-downward {version}"),
            },
            "summary": summary,
            "subgoals": [c.to_dict() for c in checks],
        },
    )
    print(f"planner: {settings_text(settings, f'up-fast-downward {version}')}")
    print(
        f"{'domain':<12} {'subgoals':>8} {'translated':>14} {'logged cost':>16} "
        f"{'goes on':>8} {'after it':>9} {'at limit':>9} {'other':>6} {'comparable':>16}"
    )
    for row in summary:
        translated = f"{row['translated']} ({row['translated_pct']}%)"
        match = (
            f"{row['match']}/{row['compared']} ({row['match_pct']}%)" if row["compared"] else "-"
        )
        comparable = (
            f"{row['match']}/{row['compared'] - row['differs_known']} "
            f"({row['match_pct_comparable']}%)"
        )
        print(
            f"{row['domain']:<12} {row['subgoals']:>8} {translated:>14} {match:>16} "
            f"{row['differs_continued']:>8} {row['differs_after_continued']:>9} "
            f"{row['differs_official_limit']:>9} {row['differs_other']:>6} {comparable:>16}"
        )
    print(
        "another cost than logged, for a known cause of the official code's: goes on: the "
        "answer goes on to another helper's subgoal (the official code translated both); "
        "after it: a later helper of such a task (the official one started after both goals); "
        "at limit: the official call ran to its time limit without a plan"
    )
    for row in summary:
        if row["with_logged_translation"]:
            print(
                f"{row['domain']}: the model's own translation is in the log for "
                f"{row['with_logged_translation']} subgoal(s); the rules give the same goal "
                f"for {row['same_as_logged']}"
            )
    print(f"written: {out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="twostep-data", description="Build, check and scale the benchmark tasks (data/)."
    )
    commands = parser.add_subparsers(dest="command", required=True)
    generate = commands.add_parser("generate", help="rebuild the benchmark tasks")
    generate.add_argument("--out", default="data", help="data folder (default: data)")
    check = commands.add_parser("check", help="verify a data folder rebuilds identically")
    check.add_argument(
        "--data",
        default=str(DEFAULT_DATA_ROOT),
        help="data folder (default: the package's, data/ of a checkout)",
    )
    for sub in (generate, check):
        sub.add_argument(
            "--domain",
            action="append",
            choices=DATA_DOMAINS,
            help="only this domain (repeatable; default: all)",
        )
        sub.add_argument("--seed", type=int, default=0, help="base seed (default: 0)")
    units = ", ".join(f"{name}: {g.scale_unit}" for name, g in GENERATORS.items())
    units += f", {alfworld.DOMAIN}: {alfworld.SCALE_UNIT}"
    scale = commands.add_parser("scale", help="write larger tasks for scaling benchmarks")
    scale.add_argument("--domain", required=True, choices=DATA_DOMAINS)
    scale.add_argument("--size", type=int, required=True, help=f"size ({units})")
    scale.add_argument("--out", required=True, help="folder to write (LLM+P layout)")
    scale.add_argument("--count", type=int, default=1, help="number of tasks (default: 1)")
    scale.add_argument("--seed", type=int, default=0, help="base seed (default: 0)")
    example = commands.add_parser(
        "example-plan",
        help="plan p_example with Fast Downward and print the plan (the stored "
        "domains/<domain>.example.sol files were made with the optimal seq-opt-lmcut)",
    )
    example.add_argument("--domain", required=True, choices=DOMAINS)
    example.add_argument("--alias", default=EXAMPLE_ALIAS, help=f"default: {EXAMPLE_ALIAS}")
    example.add_argument("--time-limit", type=float, default=300.0, help="seconds (default 300)")
    example.set_defaults(run=_example_plan)
    answers = commands.add_parser(
        "import-answers",
        help="read logs of real model answers into a replay bundle, which twostep's jobs "
        "can replay (docs/how-to/reproduce-paper.md)",
    )
    answers.add_argument("logs", nargs="+", metavar="LOG", help="log files, in run order")
    answers.add_argument(
        "--format",
        default="twostep-official",
        choices=["twostep-official"],
        help="the logs' format (the official TwoStep code's run logs)",
    )
    answers.add_argument("--out", required=True, help="the bundle's folder")
    answers.add_argument("--model", required=True, help="the model that gave the answers")
    answers.add_argument(
        "--tasks",
        help="the folder of the task files the answers refer to (<domain>/pNN.pddl): "
        "their digests are kept and a replay on other files is refused",
    )
    answers.add_argument("--append", action="store_true", help="add to the bundle in --out")
    answers.add_argument(
        "--allow-truncated",
        action="store_true",
        help="import a log that ends inside a block without that block (else an error)",
    )
    answers.set_defaults(run=_import_answers)
    check_answers = commands.add_parser(
        "check-answers",
        help="check the rules translator on a bundle against the helper costs its logs record",
    )
    check_answers.add_argument("bundle", help="the bundle's folder")
    check_answers.add_argument(
        "--data-root", required=True, help="the folder of the tasks the answers refer to"
    )
    check_answers.add_argument(
        "--alias", default="lama", help="planner alias (default: lama, anytime, as logged)"
    )
    check_answers.add_argument(
        "--time-limit",
        type=float,
        default=100.0,
        help="search time limit per helper plan, s (default: 100, the official runs')",
    )
    check_answers.add_argument("--domain", action="append", help="only this domain (repeatable)")
    check_answers.add_argument(
        "--agents", action="append", type=int, help="only this N (repeatable)"
    )
    check_answers.add_argument(
        "--agent-predicates", help="YAML: domain -> agent predicates (default: conf/domain/)"
    )
    check_answers.add_argument("--out", help=f"the result file (default: <bundle>/{CHECK_FILE})")
    check_answers.set_defaults(run=_check_answers)
    generate.set_defaults(run=_generate)
    check.set_defaults(run=_check)
    scale.set_defaults(run=_scale)
    return parser


@console_main
def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    code: int = args.run(args)
    return code


if __name__ == "__main__":
    sys.exit(main())
