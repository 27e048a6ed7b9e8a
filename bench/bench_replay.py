"""A replay sweep (``experiment=paper_replay``), checked and timed: every schedule of every
job re-validated, and where the sweep's time went.

For each ``result.json`` below the sweep directories given, the job's task is read from the
data root of its config (``.hydra/config.yaml``) and its joint schedule (the SA plan as a
one-agent schedule for SA and for fallbacks) is re-validated twice: by ``check_run`` (our
simulator) and by the independent validator on the original files (``checkers``:
Fast Downward's grounding run by a simulator of its own, and unified-planning's N-agent
formulation where its reader accepts the files). Prints, per domain and method, how many
jobs, how many succeeded, how many schedules each checker accepted, and the job wall times
(``orchestration.job_wall_time_s``: mean and total); then the sweep's own wall time from its
summary. Exit 1 if any schedule is refused.

    .venv/bin/python bench/bench_replay.py outputs/multiruns/<date>/<time> --json docs/bench/replay.json
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import yaml

from checkers import IndependentValidator
from tools import record
from twostep.methods import check_run
from twostep.methods.result import RunResult
from twostep.tasks.benchmark import load_task


def _run(result: dict[str, Any]) -> RunResult:
    run = RunResult(result["domain"], result["task"], result["method"], result["agents"])
    run.agent_order = list(result["agent_order"])
    run.plans = {agent: list(plan) for agent, plan in result["plans"].items()}
    run.schedule = [[(agent, action) for agent, action in step] for step in result["schedule"]]
    return run


def _label(result: dict[str, Any]) -> str:
    if result["method"] == "twostep":
        return f"twostep ({result.get('decomposer')})"
    return str(result["method"])


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sweeps", nargs="+", type=Path, help="sweep directories")
    parser.add_argument("--json", type=Path, help="also write what it prints as a record here")
    args = parser.parse_args(argv)
    with record.capture(args.json, title="The replay sweep"):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    rows: dict[tuple[str, str], dict[str, Any]] = defaultdict(
        lambda: {"jobs": 0, "success": 0, "check_run": 0, "independent": 0, "wall": []}
    )
    refused: list[str] = []
    validators: dict[tuple[Path, Path], IndependentValidator] = {}
    for sweep in args.sweeps:
        for path in sorted(sweep.glob("*/result.json")):
            result = json.loads(path.read_text())
            config = yaml.safe_load((path.parent / ".hydra" / "config.yaml").read_text())
            row = rows[(str(result["domain"]), _label(result))]
            row["jobs"] += 1
            wall = (result.get("orchestration") or {}).get("job_wall_time_s")
            if isinstance(wall, int | float):
                row["wall"].append(float(wall))
            if not result.get("success") or not result.get("schedule"):
                continue
            row["success"] += 1
            task = load_task(result["domain"], int(result["task"]), Path(config["data"]["root"]))
            predicates = list(config["domain"]["agent_predicates"])
            where = f"{path.parent.name}"
            try:
                check_run(task.problem, _run(result), predicates)
                row["check_run"] += 1
            except Exception as error:  # a refused schedule is a row, not a crash
                refused.append(f"{where}: check_run: {error}")
            key = (task.domain_path, task.problem_path)
            if key not in validators:
                validators[key] = IndependentValidator(*key)
            steps = [[tuple(a) for a in step] for step in result["schedule"]]
            verdict = validators[key].check_schedule(
                result["agent_order"], result["plans"], steps, predicates
            )
            if verdict.valid:
                row["independent"] += 1
            else:
                refused.append(f"{where}: independent: {verdict.reason}")
    print(f"{'domain':<12} {'method':<22} {'jobs':>5} {'ok':>5} {'check_run':>10} "
          f"{'independent':>12} {'job wall s (mean)':>18} {'total s':>9}")  # fmt: skip
    for (domain, method), row in sorted(rows.items()):
        wall = row["wall"]
        mean = f"{sum(wall) / len(wall):.1f}" if wall else "-"
        print(
            f"{domain:<12} {method:<22} {row['jobs']:>5} {row['success']:>5} "
            f"{row['check_run']:>10} {row['independent']:>12} {mean:>18} {sum(wall):>9.0f}"
        )
    for sweep in args.sweeps:
        summary = sweep / ".twostep" / "summary.json"
        if summary.is_file():
            data = json.loads(summary.read_text())
            keep = ("jobs_total", "jobs_done", "jobs_failed", "jobs_timeout", "sweep_wall_time_s")
            print(f"{sweep}: {json.dumps({k: data.get(k) for k in keep})}")
    for line in refused:
        print(f"REFUSED {line}")
    print(f"schedules refused: {len(refused)}")
    return 1 if refused else 0


if __name__ == "__main__":
    sys.exit(main())
