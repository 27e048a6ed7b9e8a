"""Conformance on real PDDL: the problems of a corpus (:func:`find_problems`), each run
through the ``twostep`` command as a user runs it (:func:`run_twostep`) and checked against
Fast Downward and the independent validator (:func:`check_problem`); the table, summary and
results page of the rows (:func:`report`, :func:`page`). ``bench/bench_conformance.py`` is
the command line (what it measures and prints: its docstring).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from checkers import IndependentValidator, Verdict
from checkers import fast_downward as fd
from evaluation.load_time import section

REPO = Path(__file__).resolve().parent.parent

AGENTS = 2
PROBLEM_FILE = re.compile(r"^p(\d+)\.pddl$")
ENVIRONMENT = {  # as the Makefile sets them: offline, no telemetry
    "LITELLM_LOCAL_MODEL_COST_MAP": "True",
    "MLFLOW_DISABLE_TELEMETRY": "true",
    "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
    "DO_NOT_TRACK": "1",
}
COLUMNS = ("domain", "problem", "loaded", "load s", "solved", "FD solved", "plan valid",
           "MA valid", "plan-deal valid")  # fmt: skip


@dataclass(frozen=True)
class ProblemFiles:
    domain_name: str  # the folder, relative to the corpus
    domain: Path
    problem: Path
    task: int | None  # the LLM+P task number when the file is pNN.pddl

    @property
    def key(self) -> str:
        return f"{self.domain_name}/{self.problem.name}"


def is_problem_file(path: Path) -> bool:
    try:
        head = path.read_text(errors="replace")[:4000]
    except OSError:
        return False
    head = re.sub(r";[^\n]*", " ", head)
    return re.match(r"\s*\(\s*define\s*\(\s*problem\b", head, re.I) is not None


def find_problems(corpus: Path) -> list[ProblemFiles]:
    """Every problem of ``corpus``: pNN.pddl beside a domain.pddl (LLM+P layout), else any
    problem file beside a domain.pddl."""
    found = []
    for domain in sorted(corpus.rglob("domain.pddl")):
        folder = domain.parent
        name = folder.relative_to(corpus).as_posix() if folder != corpus else folder.name
        numbered = {
            p: int(m.group(1)) for p in folder.iterdir() if (m := PROBLEM_FILE.match(p.name))
        }
        if numbered:
            for path, task in sorted(numbered.items(), key=lambda item: item[1]):
                found.append(ProblemFiles(name, domain, path, task))
            continue
        for path in sorted(folder.glob("*.pddl")):
            if path.name != "domain.pddl" and is_problem_file(path):
                found.append(ProblemFiles(name, domain, path, None))
    return found


def twostep_command() -> str:
    beside = Path(sys.executable).parent / "twostep"
    return str(beside) if beside.is_file() else (shutil.which("twostep") or "twostep")


@dataclass(frozen=True)
class TwostepRun:
    exit_code: int | None  # None: killed at the wall-clock limit
    result: dict[str, Any] | None
    error: str  # the last line of stderr (a failure's reason)
    wall_s: float


def run_twostep(
    files: ProblemFiles, overrides: Sequence[str], time_limit_s: float, timeout_s: float
) -> TwostepRun:
    """One ``twostep`` run on ``files``, on a fresh output root, through the command line."""
    with tempfile.TemporaryDirectory(prefix="conformance-") as tmp:
        out = Path(tmp)
        if files.task is not None:
            data_root, name, task = files.domain.parent.parent, files.domain.parent.name, files.task
        else:  # stage the original files as <root>/<name>/{domain,p01}.pddl (links)
            name, task = "task", 1
            data_root = out / "data"
            (data_root / name).mkdir(parents=True)
            (data_root / name / "domain.pddl").symlink_to(files.domain.resolve())
            (data_root / name / "p01.pddl").symlink_to(files.problem.resolve())
        command = [
            twostep_command(),
            f"data.root={data_root}",
            "domain=tyreworld",  # any domain config: its name and agent predicates are set here
            f"domain.name={name}",
            f"task={task}",
            "planner=lama-first",
            f"planner.time_limit_s={time_limit_s:g}",
            "mlflow.enabled=false",
            "orchestration.prefect=false",
            f"output.root={out / 'outputs'}",
            f"hydra.run.dir={out / 'run'}",
            *overrides,
        ]
        start = time.perf_counter()
        try:
            done = subprocess.run(
                command,
                capture_output=True,
                text=True,
                timeout=timeout_s,
                env={**os.environ, **ENVIRONMENT},
                cwd=out,
                check=False,
            )
        except subprocess.TimeoutExpired:
            return TwostepRun(
                None, None, f"killed after {timeout_s:g} s", time.perf_counter() - start
            )
        wall = time.perf_counter() - start
        result_file = out / "run" / "result.json"
        result = json.loads(result_file.read_text()) if result_file.is_file() else None
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        return TwostepRun(done.returncode, result, lines[-1][:300] if lines else "", wall)


def loaded(run: TwostepRun) -> bool:
    """The run got past reading the task (a planner ran, or it failed later than loading)."""
    result = run.result or {}
    return bool(result.get("planner_calls")) or result.get("status") not in (None, "failed")


def load_seconds(run: TwostepRun) -> float | None:
    value = ((run.result or {}).get("orchestration") or {}).get("task_load_s")
    return round(float(value), 3) if loaded(run) and value is not None else None


def reason_of(run: TwostepRun) -> str:
    result = run.result or {}
    text = result.get("message") or result.get("error") or run.error or f"exit {run.exit_code}"
    return " ".join(str(text).split())[:300]


def check_single_agent(
    files: ProblemFiles, validator: IndependentValidator, args: Any
) -> dict[str, Any]:
    run = run_twostep(files, ["method=sa"], args.time_limit, args.run_timeout)
    result = run.result or {}
    row: dict[str, Any] = {
        "exit_code": run.exit_code,
        "wall_s": round(run.wall_s, 2),
        "loaded": loaded(run),
        "load_s": load_seconds(run),
        "status": result.get("status"),
        "solved": bool(result.get("success")),
        "sa_length": result.get("sa_length"),
        "sa_cost": result.get("sa_cost"),
        "valid": None,
        "failures": [],
    }
    if not row["loaded"]:
        row["failures"].append(f"SA: not loaded: {reason_of(run)}")
        return row
    if not row["solved"]:
        row["failures"].append(f"SA: not solved ({row['status']}): {reason_of(run)}")
        return row
    order = result.get("agent_order") or ["agent0"]
    plan = list((result.get("plans") or {}).get(order[0], []))
    row["length"] = len(plan)
    verdict = validator.check_plan(plan)
    row.update(
        valid=verdict.valid, reason=verdict.reason, cost=verdict.cost, checkers=verdict.checkers
    )
    if not verdict.valid:
        row["failures"].append(f"SA: plan invalid on the original files: {verdict.reason}")
    if row["sa_length"] != len(plan):
        row["failures"].append(
            f"SA: sa_length {row['sa_length']} but the plan has {len(plan)} actions"
        )
    if verdict.valid and row["sa_cost"] != verdict.cost:
        row["failures"].append(
            f"SA: sa_cost {row['sa_cost']} but the plan costs {verdict.cost} on the original task"
        )
    return row


def check_schedule_run(
    label: str,
    files: ProblemFiles,
    overrides: list[str],
    agent_predicates: list[str],
    validator: IndependentValidator,
    args: Any,
) -> dict[str, Any]:
    preds = f"domain.agent_predicates=[{','.join(agent_predicates)}]"
    run = run_twostep(
        files, [*overrides, f"agents={AGENTS}", preds], args.time_limit, args.run_timeout
    )
    result = run.result or {}
    row: dict[str, Any] = {
        "exit_code": run.exit_code,
        "wall_s": round(run.wall_s, 2),
        "status": result.get("status"),
        "success": bool(result.get("success")),
        "exec_length": result.get("exec_length"),
        "fallback": result.get("fallback"),
        "valid": None,
        "failures": [],
    }
    if not row["success"]:
        row["failures"].append(f"{label}: no schedule ({row['status']}): {reason_of(run)}")
        return row
    schedule = result.get("schedule") or []
    verdict: Verdict = validator.check_schedule(
        result.get("agent_order") or [], result.get("plans") or {}, schedule, agent_predicates
    )
    row.update(
        valid=verdict.valid, reason=verdict.reason, checkers=verdict.checkers, steps=len(schedule)
    )
    if not verdict.valid:
        row["failures"].append(f"{label}: schedule invalid: {verdict.reason}")
    if row["exec_length"] != len(schedule):
        row["failures"].append(
            f"{label}: exec_length {row['exec_length']} but the schedule has {len(schedule)} steps"
        )
    return row


def check_problem(
    files: ProblemFiles, agent_predicates: list[str] | None, args: Any
) -> dict[str, Any]:
    """Everything the bench measures on one problem, as a JSON-ready row."""
    start = time.perf_counter()
    validator = IndependentValidator(files.domain, files.problem)
    row: dict[str, Any] = {
        "key": files.key,
        "domain": files.domain_name,
        "problem": files.problem.name,
    }
    planner = fd.plan(files.domain, files.problem, time_limit_s=args.time_limit)
    row["fd"] = {"status": planner.status, "solved": planner.plan is not None,
                 "wall_s": round(planner.wall_s, 2), "cost": planner.cost,
                 "length": len(planner.plan) if planner.plan is not None else None}  # fmt: skip
    failures: list[str] = []
    if planner.plan is None:
        failures.append(f"FD: not solved ({planner.status}): {planner.message}")
    else:
        own = validator.check_plan(planner.plan)
        row["fd"]["plan_valid"] = own.valid
        if not own.valid:
            failures.append(f"validator: rejects Fast Downward's own plan: {own.reason}")
    row["sa"] = check_single_agent(files, validator, args)
    failures += row["sa"].pop("failures")
    for label, key, overrides in (
        ("MA", "ma", ["method=ma", "compare_sa=false"]),
        ("plan-deal", "deal", ["method=plan-deal"]),
    ):
        if agent_predicates is None or not row["sa"]["loaded"]:
            row[key] = None
            continue
        row[key] = check_schedule_run(label, files, overrides, agent_predicates, validator, args)
        failures += row[key].pop("failures")
    row["checkers"] = validator._checkers()
    row["failures"] = failures
    row["seconds"] = round(time.perf_counter() - start, 1)
    return row


def mark(value: bool | None) -> str:
    return "-" if value is None else ("yes" if value else "no")


def schedule_mark(run: dict[str, Any] | None) -> str:
    if not run:
        return "-"
    return mark(run["valid"]) if run["success"] else f"no ({run['status']})"


def table_rows(rows: list[dict[str, Any]]) -> list[tuple[str, ...]]:
    out: list[tuple[str, ...]] = []
    for row in rows:
        sa = row["sa"]
        load = sa.get("load_s")
        out.append((
            row["domain"], row["problem"], mark(sa["loaded"]),
            "-" if load is None else f"{load:.2f}",
            mark(sa["solved"]) if sa["loaded"] else "-", mark(row["fd"]["solved"]),
            mark(sa.get("valid")),
            schedule_mark(row.get("ma")), schedule_mark(row.get("deal")),
        ))  # fmt: skip
    return out


def summary(rows: list[dict[str, Any]]) -> list[str]:
    total = len(rows)
    fd_solved = [r for r in rows if r["fd"]["solved"]]
    good = [r for r in rows if r["sa"]["solved"] and r["sa"].get("valid")]
    good_of_fd = [r for r in fd_solved if r["sa"]["solved"] and r["sa"].get("valid")]
    ma = [r["ma"] for r in rows if r.get("ma")]
    deal = [r["deal"] for r in rows if r.get("deal")]
    return [
        f"problems {total}; twostep loaded {sum(r['sa']['loaded'] for r in rows)}/{total}; "
        f"Fast Downward solves {len(fd_solved)}/{total}",
        f"SA solved+valid {len(good_of_fd)}/{len(fd_solved)} of the problems FD solves "
        f"({len(good)}/{total} of all)",
        f"MA valid {sum(bool(m['valid']) for m in ma)}/{len(ma)}, "
        f"plan-deal valid {sum(bool(d['valid']) for d in deal)}/{len(deal)} (N = {AGENTS})",
    ]


def report(rows: list[dict[str, Any]]) -> str:
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(cells) + " |" for cells in table_rows(rows)]
    failures = [(row["key"], f) for row in rows for f in row["failures"]]
    if failures:
        lines += ["", "Failures:"]
        lines += [f"- {key}: {text}" for key, text in failures]
    lines += ["", *summary(rows)]
    return "\n".join(lines)


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page (tools.results): this bench's rows (``--out``), then the load-time
    bench's (``bench/bench_load.py --out``)."""
    conformance, load = records
    meta = conformance.get("meta", {})
    lines = [
        "## Conformance",
        "",
        f"Corpus `{meta.get('corpus')}` (one problem per domain; not in this repository), "
        f"`{meta.get('planner')}` with {meta.get('time_limit_s')} s of search for Fast Downward "
        f"and twostep; MA and plan-deal with N = {meta.get('agents')} for the domains of "
        f"`{meta.get('agents_file')}`. Load average at the start and end of each sitting: "
        + "; ".join(conformance.get("load_average", []))
        + ".",
        "",
        "Load s: `orchestration.task_load_s` of the run's result.json (read and ground the "
        "task, in process). Plan valid: the SA plan checked on the original files by the "
        "independent validator (`checkers`); MA valid and plan-deal valid: the "
        "schedule re-validated the same way.",
        "",
        *report(conformance["rows"]).splitlines(),
        "",
    ]
    return lines + section(load, figure)
