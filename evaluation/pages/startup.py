"""The results page of the rows ``bench/bench_startup.py`` writes (``make results``:
:mod:`tools.results`), and the goals the bench prints its runs against.
"""

from __future__ import annotations

import statistics
from typing import Any

from tools import record

JOB = ["method=sa", "domain=grippers", "task=9"]
GOALS = {"default": 3.0, "services": 5.0}

SCENARIO_TEXT = {
    "default": "a re-run, its MLflow run already in the store (nothing to log)",
    "logged": "a job new to the warm store (its MLflow run created and logged)",
    "cold": "the first run on a fresh output.root (a new store)",
    "services": "with `twostep-services up` and orchestration.prefect=true (a Prefect flow)",
}


def _medians(row: dict[str, Any]) -> tuple[float, float, float, float]:
    """(wall, planner, wall - planner, CPU) medians of a scenario's command runs."""
    if "runs" in row:
        runs = row["runs"]
        wall = statistics.median(r[0] for r in runs)
        planner = statistics.median(r[1] for r in runs)
        return wall, planner, row["overhead_s"], statistics.median(r[2] for r in runs)
    return row["wall_s"], row["planner_s"], row["overhead_s"], row["cpu_s"]


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of a ``--json`` record (tools.results)."""
    from matplotlib.figure import Figure

    (data,) = records
    every, goals = data["rows"], data.get("goals", GOALS)
    rows = [r for r in every if r["scenario"] != "refusals"]
    refused = [r for r in every if r["scenario"] == "refusals"]
    job = " ".join(data.get("job", JOB))
    lines = [
        "## Summary",
        "",
        f"`twostep {job}`, a warm install; medians of {data.get('repeat')} runs of the "
        "command each (wall time from outside the process; planner: its wall time from "
        "result.json; CPU: user + system of the command and the processes it waits for).",
        "",
    ]
    table = []
    for row in rows:
        wall, planner, overhead, cpu = _medians(row)
        goal = goals.get(row["scenario"], goals["default"])
        table.append([row["scenario"], SCENARIO_TEXT.get(row["scenario"], ""), f"{wall:.2f}",
                      f"{planner:.2f}", f"**{overhead:.2f}**", f"<= {goal:g}",
                      "met" if overhead <= goal else "missed", f"{cpu:.1f}"])  # fmt: skip
    lines += record.table(
        ["scenario", "what it is", "wall s", "planner s", "wall - planner s", "goal s", "goal",
         "CPU s"], table,
    )  # fmt: skip
    detailed = [r for r in rows if "breakdown" in r]
    if detailed:
        lines += ["", "## Where the time goes", "",
                  "The same job in a driver process that times its phases (medians):", ""]  # fmt: skip
        head = ["phase"]
        for r in detailed:
            head += [f"{r['scenario']} wall s"]
        parts = list(detailed[0]["breakdown"])
        lines += record.table(
            head, [[p, *(f"{r['breakdown'].get(p, 0.0):.2f}" for r in detailed)] for p in parts]
        )
        lines += ["", "CPU seconds by phase (what a shared machine's load does not inflate):", ""]
        cpu_parts = list(detailed[0]["cpu_breakdown"])
        lines += record.table(
            ["phase", *(f"{r['scenario']} CPU s" for r in detailed)],
            [[p, *(f"{r['cpu_breakdown'].get(p, 0.0):.2f}" for r in detailed)] for p in cpu_parts],
        )
    for row in refused:
        lines += ["", "## Refusals", "",
                  f"Commands refused before any work (goal: exit 2 in under {REFUSAL_GOAL_S:g} "
                  "s, one line, nothing written); medians.", ""]  # fmt: skip
        lines += record.table(
            ["command", "exit", "stderr lines", "written", "wall s", "CPU s"],
            [[f"`twostep {' '.join(r['command'])}`", ", ".join(map(str, r["codes"])),
              str(r["lines"]), "yes" if r["written"] else "no",
              f"{statistics.median(r['walls']):.2f}", f"{statistics.median(r['cpus']):.2f}"]
             for r in row["rows"]],
        )  # fmt: skip
    fig = Figure(figsize=(7.0, 2.8), layout="constrained")
    axes = fig.subplots()
    names = [r["scenario"] for r in rows]
    overheads = [_medians(r)[2] for r in rows]
    axes.barh(names, overheads, color="C0")
    for i, name in enumerate(names):
        goal = goals.get(name, goals["default"])
        axes.plot([goal, goal], [i - 0.4, i + 0.4], color="black", linewidth=2)
    axes.invert_yaxis()
    axes.set_xlabel("wall - planner s (median); black: the goal")
    axes.set_title("What a single run costs besides planning")
    axes.grid(alpha=0.3, axis="x")
    lines += [
        "",
        "## Figure",
        "",
        figure(fig, "overhead", "Wall minus planner time per scenario"),
        "",
    ]
    return lines


REFUSAL_GOAL_S = 1.0
