"""The LLM+P benchmark files (the paper's own task files) as a held-out data root: laid out
for the methods bench (:func:`prepare`), each schedule dealt again and checked by the
independent validator (:func:`validate`), and the cross-check of our domains against theirs
(:func:`cross_check`, :func:`cross_table`). ``bench/bench_heldout.py`` is the command line.
"""

from __future__ import annotations

import re
import shutil
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

import yaml

REPO = Path(__file__).resolve().parent.parent

DOMAINS = ("barman", "blocksworld", "grippers", "termes", "tyreworld", "storage", "floortile")
PROBLEM = re.compile(r"p\d\d\.pddl")
DOMAIN_NAME = re.compile(r"\(\s*:domain\s+([^\s()]+)\s*\)", re.IGNORECASE)


NO_DOMAIN_FILE = ("blocksworld",)
"""LLM+P's folders without a domain file: the layout gives them ours (their problems name
it), and the cross-check reads their problems with ours alone."""


def problem_domain(path: Path) -> str:
    """The domain name a problem file asks for."""
    found = DOMAIN_NAME.search(path.read_text())
    if found is None:
        raise ValueError(f"{path}: no (:domain ...)")
    return found.group(1)


def domain_name(path: Path) -> str:
    """The name a domain file gives its domain."""
    found = re.search(r"\(\s*domain\s+([^\s()]+)\s*\)", path.read_text(), re.IGNORECASE)
    if found is None:
        raise ValueError(f"{path}: no (domain ...)")
    return found.group(1)


def prepare(llmp: Path, out: Path, domains: tuple[str, ...] = DOMAINS) -> dict[str, int]:
    """Lay out ``domains`` of the LLM+P checkout ``llmp`` as a data root at ``out``; return
    how many problems each domain has."""
    source = llmp / "domains" if (llmp / "domains").is_dir() else llmp
    counts: dict[str, int] = {}
    for domain in domains:
        folder = source / domain
        problems = sorted(p for p in folder.glob("p*.pddl") if PROBLEM.fullmatch(p.name))
        if not problems:
            raise FileNotFoundError(f"{folder}: no p01.pddl ... p20.pddl")
        target = out / domain
        target.mkdir(parents=True, exist_ok=True)
        for problem in problems:
            shutil.copyfile(problem, target / problem.name)
        if (folder / "domain.pddl").is_file():
            shutil.copyfile(folder / "domain.pddl", target / "domain.pddl")
        elif domain in NO_DOMAIN_FILE:
            ours = REPO / "data" / domain / "domain.pddl"
            wanted, name = problem_domain(problems[0]), domain_name(ours)
            if wanted.lower() != name.lower():
                raise ValueError(f"{problems[0]}: names domain {wanted}, {ours} is {name}")
            shutil.copyfile(ours, target / "domain.pddl")
        else:
            raise FileNotFoundError(f"{folder}: no domain.pddl")
        counts[domain] = len(problems)
    return counts


AGENTS_FILE = REPO / "bench" / "heldout_agents.yaml"
CONSTANTS_IN_PROBLEMS = {"tyreworld": ("wrench", "jack", "pump")}
"""Objects a domain file names that only its problems declare (read as constants by us and
Fast Downward's translator after twostep's repair; the independent checkers read copies)."""


def heldout_predicates(domain: str) -> list[str]:
    """The agent predicates of a held-out domain: bench/heldout_agents.yaml, else conf's."""
    given = yaml.safe_load(AGENTS_FILE.read_text()) or {}
    if domain in given:
        return [str(p) for p in given[domain]]
    from evaluation.methods import agent_predicates

    return agent_predicates(domain)


def validate(root: Path, rows: list[dict[str, Any]], agents: tuple[int, ...]) -> Counter[str]:
    """Deal every stored SA plan of ``root``'s tasks to each of ``agents`` with plan-deal and
    check the schedule with the independent validator; print each one that fails."""
    from checkers import IndependentValidator
    from checkers.constants import move_constants
    from twostep.methods import MethodRequest
    from twostep.methods.plan_deal import run_plan_deal
    from twostep.planner import PlannerSettings
    from twostep.planner.results import PlanResult, Status
    from twostep.tasks.benchmark import load_task

    counts: Counter[str] = Counter()
    for row in rows:
        if row["method"] != "sa" or not row["valid"] or not row.get("plan"):
            continue
        domain, number = row["domain"], row["task"]
        files = (root / domain / "domain.pddl", root / domain / f"p{number:02d}.pddl")
        if domain in CONSTANTS_IN_PROBLEMS:
            files = move_constants(*files, CONSTANTS_IN_PROBLEMS[domain], Path(tempfile.mkdtemp()))
        check = IndependentValidator(*files)
        task, preds = load_task(domain, number, root), heldout_predicates(domain)
        sa = PlanResult(Status.SOLVED, tuple(row["plan"]), 0.0, 0.0)
        for n in agents:
            run = run_plan_deal(MethodRequest(task, n, PlannerSettings(), preds, sa_plan=sa))
            steps = [[[agent, action] for agent, action in step] for step in run.schedule]
            verdict = check.check_schedule(run.agent_order, run.plans, steps, preds)
            counts["valid" if verdict.valid else "not valid"] += 1
            counts[f"checked by: {verdict.checkers}"] += 1
            if not verdict.valid:
                print(f"{domain} p{number:02d} N={n}: {verdict.reason}", flush=True)
    return counts


CROSS_DOMAINS = ("barman", "blocksworld", "grippers", "termes", "tyreworld")
CROSS_TIME_LIMIT_S = 60.0


def without_domain_constants(domain: Path, problem: Path, out_dir: Path) -> Path:
    """A copy of ``problem`` without the objects ``domain`` declares as constants, written
    with the independent checkers' own s-expression code (not twostep's repair)."""
    from checkers.constants import read_sexp, write_sexp

    def part(expr: Any, keyword: str) -> list[Any]:
        found = [p for p in expr if isinstance(p, list) and p and str(p[0]).lower() == keyword]
        return found[0] if found else [keyword]

    domain_expr, problem_expr = read_sexp(domain.read_text()), read_sexp(problem.read_text())
    constants = {str(n).lower() for n in part(domain_expr, ":constants")[1:] if n != "-"}
    objects, kept = part(problem_expr, ":objects"), [":objects"]
    pending: list[Any] = []
    items = objects[1:]
    index = 0
    while index < len(items):
        if items[index] == "-" and index + 1 < len(items):
            staying = [n for n in pending if str(n).lower() not in constants]
            kept += [*staying, "-", items[index + 1]] if staying else []
            pending, index = [], index + 2
            continue
        pending.append(items[index])
        index += 1
    kept += [n for n in pending if str(n).lower() not in constants]
    objects[:] = kept
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / problem.name).write_text(write_sexp(problem_expr) + "\n")
    return out_dir / problem.name


def _simulated(task: Any, plan: list[str]) -> str:
    """'' if twostep's simulator runs ``plan`` to ``task``'s goal, else why not."""
    from twostep.plans.simulate import Grounder, PlanError, simulate

    try:
        state = simulate(task.init, Grounder(task).ground_plan(plan))
    except PlanError as error:
        return str(error)
    return "" if task.goal.holds(state) else "the goal does not hold at the end"


def cross_check(root: Path, domains: tuple[str, ...], say: Any) -> dict[str, Counter[str]]:
    """Every task of ``root``'s ``domains`` read with our domain and with theirs, planned
    on both, each plan checked on the other task; per domain, the counts (see ``main``)."""
    from checkers import IndependentValidator
    from checkers.constants import move_constants
    from twostep.pddl import PDDLError, load_problem
    from twostep.planner import PlannerSettings, plan

    settings = PlannerSettings("lama-first", CROSS_TIME_LIMIT_S)
    scratch = Path(tempfile.mkdtemp(prefix="cross-"))
    summary: dict[str, Counter[str]] = {}
    for domain in domains:
        if domain in NO_DOMAIN_FILE:
            summary[domain] = ours_only(root, domain, settings, say)
            continue
        counts: Counter[str] = Counter()
        ours_domain = REPO / "data" / domain / "domain.pddl"
        theirs_domain = root / domain / "domain.pddl"
        for problem in sorted(
            p for p in (root / domain).glob("p*.pddl") if PROBLEM.fullmatch(p.name)
        ):
            counts["tasks"] += 1
            label = f"{domain} {problem.stem}"
            tasks: dict[str, Any] = {}
            for side, domain_file in (("ours", ours_domain), ("theirs", theirs_domain)):
                try:
                    tasks[side] = load_problem(domain_file, problem)
                except PDDLError as error:
                    say(f"{label}: not loaded with {side} domain: {error}")
            if len(tasks) < 2:
                continue
            counts["loaded"] += 1
            plans: dict[str, list[str]] = {}
            for side, task in tasks.items():
                result = plan(task, settings)
                if result.solved and result.plan is not None:
                    plans[side] = list(result.plan)
                else:
                    say(f"{label}: no plan on {side} domain: {result.status} {result.message}")
            if len(plans) < 2:
                continue
            counts["plans"] += 1
            counts["length ours"] += len(plans["ours"])
            counts["length theirs"] += len(plans["theirs"])
            # the files of each task as the independent checkers read them
            here = scratch / domain / problem.stem
            files = {
                "ours": (ours_domain, without_domain_constants(ours_domain, problem, here)),
                "theirs": (theirs_domain, problem),
            }
            if domain in CONSTANTS_IN_PROBLEMS:
                files["theirs"] = move_constants(
                    theirs_domain, problem, CONSTANTS_IN_PROBLEMS[domain], here / "theirs"
                )
            verdicts = []
            for made_on, checked_on in (("ours", "theirs"), ("theirs", "ours")):
                steps = plans[made_on]
                simulator = _simulated(tasks[checked_on], steps)
                verdict = IndependentValidator(*files[checked_on]).check_plan(steps)
                ok = not simulator and verdict.valid
                counts[f"valid {made_on} on {checked_on}"] += ok
                counts[f"checked by: {verdict.checkers}"] += 1
                verdicts.append(ok)
                if not ok:
                    say(
                        f"{label}: the plan on {made_on} domain is not valid on {checked_on}: "
                        f"simulator: {simulator or 'valid'}; independent: "
                        f"{verdict.reason or 'valid'}"
                    )
            counts["valid both ways"] += all(verdicts)
            say(
                f"{label}: lengths {len(plans['ours'])} (ours) {len(plans['theirs'])} (theirs), "
                f"valid both ways: {'yes' if all(verdicts) else 'NO'}"
            )
        summary[domain] = counts
    return summary


def ours_only(root: Path, domain: str, settings: Any, say: Any) -> Counter[str]:
    """The cross-check of a domain without their domain file: each problem of ``root``'s
    ``domain`` read with our domain, planned, and the plan checked on our domain and the
    problem file as written (twostep's simulator and the independent validator)."""
    from checkers import IndependentValidator
    from twostep.pddl import PDDLError, load_problem
    from twostep.planner import plan

    counts: Counter[str] = Counter(ours_only=1)
    ours_domain = REPO / "data" / domain / "domain.pddl"
    for problem in sorted(p for p in (root / domain).glob("p*.pddl") if PROBLEM.fullmatch(p.name)):
        counts["tasks"] += 1
        label = f"{domain} {problem.stem}"
        try:
            task = load_problem(ours_domain, problem)
        except PDDLError as error:
            say(f"{label}: not loaded with ours domain: {error}")
            continue
        counts["loaded"] += 1
        result = plan(task, settings)
        if not result.solved or result.plan is None:
            say(f"{label}: no plan on ours domain: {result.status} {result.message}")
            continue
        steps = list(result.plan)
        counts["plans"] += 1
        counts["length ours"] += len(steps)
        simulator = _simulated(task, steps)
        verdict = IndependentValidator(ours_domain, problem).check_plan(steps)
        ok = not simulator and verdict.valid
        counts["valid ours"] += ok
        counts[f"checked by: {verdict.checkers}"] += 1
        if not ok:
            say(
                f"{label}: the plan on ours domain is not valid: simulator: "
                f"{simulator or 'valid'}; independent: {verdict.reason or 'valid'}"
            )
        say(
            f"{label}: length {len(steps)} (ours), theirs: no domain file, "
            f"valid: {'yes' if ok else 'NO'}"
        )
    return counts


def cross_table(summary: dict[str, Counter[str]]) -> list[str]:
    """The per-domain summary of :func:`cross_check` as a Markdown table."""
    lines = [
        "| domain | tasks | loaded | plans both ways | valid both ways | mean length ours | "
        "mean length theirs |",
        "|---|---|---|---|---|---|---|",
    ]
    for domain, c in summary.items():
        means = [f"{c[f'length {s}'] / c['plans']:.1f}" if c["plans"] else "-" for s in
                 ("ours", "theirs")]  # fmt: skip
        if c["ours_only"]:
            lines.append(
                f"| {domain} | {c['tasks']} | {c['loaded']} | {c['plans']} (ours; theirs: no "
                f"domain file) | {c['valid ours']} (on ours) | {means[0]} | - |"
            )
            continue
        lines.append(
            f"| {domain} | {c['tasks']} | {c['loaded']} | {c['plans']} | "
            f"{c['valid both ways']} | {means[0]} | {means[1]} |"
        )
    checkers = Counter[str]()
    for c in summary.values():
        checkers.update({k: v for k, v in c.items() if k.startswith("checked by: ")})
    lines += ["", "independent validator, plans checked by:"]
    lines += [f"  {k.removeprefix('checked by: ')}: {v}" for k, v in sorted(checkers.items())]
    return lines
