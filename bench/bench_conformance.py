"""Conformance bench: does twostep read, plan and validate real PDDL as Fast Downward does?

For every problem of a corpus:

* **Fast Downward** (lama-first, ``--time-limit`` seconds of search) on the ORIGINAL files:
  solved?, wall time; its plan is also given to the independent validator (a validator that
  rejected Fast Downward's own plan would be reported as a failure of the validator).
* **twostep, SA**: ``twostep method=sa data.root=... domain.name=<folder> task=<n>
  mlflow.enabled=false output.root=<fresh tmp>`` through the command line, as a user runs
  it (a fresh ``output.root`` per run: nothing reused, the parsed-task cache cold). Loaded?
  (the run got past reading the task), load time (``orchestration.task_load_s`` of
  result.json), solved?, and is the plan valid on the ORIGINAL files by the independent
  validator (``checkers``: unified-planning where its reader accepts the files,
  Fast Downward's translator plus a simulator written apart from twostep everywhere)? Also
  checked: ``sa_length`` is the plan's action count, ``sa_cost`` its cost.
* with ``--agents FILE`` (YAML: ``domain: [agent predicates]``), for the domains it lists:
  **MA** (``method=ma agents=2``) and **plan-deal** (``method=plan-deal agents=2``). A
  schedule is valid when each agent's actions in it are
  its plan, in order, and (check_run's job, done independently) its time steps replay on the
  original task's grounding with each agent owning a copy of the agent-specific facts
  (every order of a step's actions must run and reach the same state), and
  unified-planning accepts the sequentialised schedule in an N-agent formulation it builds
  itself from the original files (each agent-specific fluent and each action copied per
  agent). We do not validate against twostep's own MA compilation: a bug there would
  then pass unnoticed. The N-agent formulation is the one the paper and twostep's scorer
  define (agents share environment facts, each keeps its own agent facts, agent-specific
  goal literals must hold for every agent).

Prints a table (domain, problem, loaded, load s, solved, FD solved, plan valid, MA valid,
plan-deal valid), every failure with its one-line reason, and a summary line. Rows go to
``--out`` as they finish; a re-run with the same ``--out`` skips the rows it holds (resume).

Corpus layouts: the LLM+P layout (``<domain>/domain.pddl`` + ``pNN.pddl``), or any tree of
folders with a ``domain.pddl`` beside problem files (any ``*.pddl`` that is a
``(define (problem``; such problems are given to twostep through a staging folder of links).

    .venv/bin/python bench/bench_conformance.py --corpus ../shared/ipc-sample \\
        --agents ../shared/ipc-sample/agents.yaml --out docs/bench/conformance.json
    .venv/bin/python bench/bench_conformance.py --corpus DIR --only blocks,gripper --workers 2
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import os
import sys
from pathlib import Path
from typing import Any

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.conformance import AGENTS, check_problem, find_problems, mark, report


def load_average() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def write_json(path: Path, data: dict[str, Any]) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=1) + "\n")
    tmp.replace(path)


def progress_line(done: int, total: int, row: dict[str, Any]) -> str:
    sa = row["sa"]
    state = "not loaded" if not sa["loaded"] else ("solved" if sa["solved"] else "not solved")
    if sa.get("valid") is not None:
        state += ", valid" if sa["valid"] else ", INVALID"
    extra = "".join(
        f" | {label} {mark(row[key]['valid'])}"
        for label, key in (("MA", "ma"), ("deal", "deal"))
        if row.get(key)
    )
    fd_state = "solved" if row["fd"]["solved"] else row["fd"]["status"]
    return f"[{done}/{total}] {row['key']}: SA {state} | FD {fd_state}{extra} | {row['seconds']} s"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--corpus",
        type=Path,
        required=True,
        help="LLM+P layout or any tree of domain.pddl + problems",
    )
    parser.add_argument(
        "--agents", type=Path, help="YAML: domain -> agent predicates (MA and plan-deal, N = 2)"
    )
    parser.add_argument(
        "--time-limit", type=float, default=30, help="search seconds, FD and twostep (default 30)"
    )
    parser.add_argument(
        "--run-timeout", type=float, default=600, help="wall-clock limit of one twostep run"
    )
    parser.add_argument(
        "--out", type=Path, help="JSON file of rows; rows already there are not run again"
    )
    parser.add_argument("--only", help="comma-separated domain folders")
    parser.add_argument("--workers", type=int, default=1, help="problems at once (default 1)")
    args = parser.parse_args(argv)

    corpus = args.corpus.resolve()
    problems = find_problems(corpus)
    if args.only:
        wanted = {d.strip() for d in args.only.split(",") if d.strip()}
        problems = [p for p in problems if p.domain_name in wanted]
    if not problems:
        print(f"no problems found under {corpus}", file=sys.stderr)
        return 2
    agents: dict[str, list[str]] = {}
    if args.agents:
        agents = {
            str(k): [str(p) for p in v]
            for k, v in (yaml.safe_load(args.agents.read_text()) or {}).items()
        }
    meta = {"corpus": str(corpus), "time_limit_s": args.time_limit, "agents_file": str(args.agents or ""),
            "planner": "lama-first", "agents": AGENTS}  # fmt: skip
    rows: list[dict[str, Any]] = []
    loads: list[str] = []  # the machine's load average at each start and end (timings depend on it)
    if args.out and args.out.is_file():
        stored = json.loads(args.out.read_text())
        if stored.get("meta") != meta:
            print(
                f"{args.out} holds rows of another setting ({stored.get('meta')}); use another --out",
                file=sys.stderr,
            )
            return 2
        rows = stored.get("rows", [])
        loads = stored.get("load_average", [])
    done_keys = {row["key"] for row in rows}
    todo = [p for p in problems if p.key not in done_keys]
    print(
        f"{len(problems)} problems, {len(problems) - len(todo)} already in {args.out}, {len(todo)} to run",
        flush=True,
    )

    if todo:
        loads.append(f"start {load_average()}")

    def finished(row: dict[str, Any]) -> None:
        rows.append(row)
        print(progress_line(len(rows), len(problems), row), flush=True)
        if args.out:
            write_json(args.out, {"meta": meta, "load_average": loads, "rows": rows})

    if args.workers <= 1:
        for files in todo:
            finished(check_problem(files, agents.get(files.domain_name), args))
    else:
        with concurrent.futures.ProcessPoolExecutor(args.workers) as pool:
            futures = [pool.submit(check_problem, f, agents.get(f.domain_name), args) for f in todo]
            for future in concurrent.futures.as_completed(futures):
                finished(future.result())
    if todo:
        loads.append(f"end {load_average()}")
    if args.out and todo:
        write_json(args.out, {"meta": meta, "load_average": loads, "rows": rows})
    keys = [p.key for p in problems]
    chosen = sorted((r for r in rows if r["key"] in keys), key=lambda r: keys.index(r["key"]))
    print()
    print(report(chosen))
    print("load average (1, 5, 15 min): " + "; ".join(loads))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
