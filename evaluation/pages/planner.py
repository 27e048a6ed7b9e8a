"""The results page of the rows ``bench/bench_planner.py`` writes (``make results``:
:mod:`tools.results`).
"""

from __future__ import annotations

import statistics
from typing import Any

from tools import record

GOAL_RATIO = 1.10  # wrapper wall time / direct driver wall time, median over the tasks


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of a ``--json`` record (tools.results): the summary, the slowest
    tasks, per-domain medians, a figure of planner time by domain, every task's row."""
    from matplotlib.figure import Figure

    (data,) = records
    rows, settings = data["rows"], data.get("settings", {})
    solved = [r for r in rows if r["length"]]  # tasks whose goal holds never reach the driver
    med = statistics.median
    ratio = med(r["ratio"] for r in solved)
    slowest = sorted(rows, key=lambda r: r["planner_s"], reverse=True)[:5]
    lines = [
        "## Summary",
        "",
        f"`{settings.get('alias')}`, {settings.get('time_limit_s'):g} s search limit, "
        f"{settings.get('repeats')} timing run(s) per task (median). Every plan is checked "
        "by unified-planning's validator.",
        "",
        *record.table(
            [
                "tasks",
                "solved and valid",
                "median read s",
                "max read s",
                "median planner s",
                "median wall s",
                "wrapper / direct, median",
                "goal",
            ],
            [
                [
                    len(rows),
                    sum(r["valid"] for r in rows),
                    f"{med(r['parse_s'] for r in rows):.2f}",
                    f"{max(r['parse_s'] for r in rows):.2f}",
                    f"{med(r['planner_s'] for r in rows):.2f}",
                    f"{med(r['plan_s'] for r in rows):.2f}",
                    f"{ratio:.3f}",
                    f"<= {GOAL_RATIO:.2f}",
                ]
            ],
        ),
        "",
        "Read: our reader and Fast Downward's translator. Planner: the planner's own time, as "
        "the driver reports it. Wall: `twostep.planner.plan` (writes the task, runs the "
        "driver, reads the plan). Direct: the Fast Downward driver called on the task's own "
        "files, as a user would by hand; the ratio is wall / direct.",
        "",
        "## The slowest tasks",
        "",
        *record.table(
            ["task", "length", "planner s", "wall s", "direct driver wall s", "read s"],
            [
                [
                    r["name"],
                    r["length"],
                    f"{r['planner_s']:.2f}",
                    f"{r['plan_s']:.2f}",
                    f"{r['direct_s']:.2f}",
                    f"{r['parse_s']:.2f}",
                ]
                for r in slowest
            ],
        ),
        "",
        "## Per domain",
        "",
    ]
    domains = sorted({r["domain"] for r in rows})
    table = []
    for d in domains:
        of = [r for r in rows if r["domain"] == d]
        table.append([d, len(of), f"{med(r['parse_s'] for r in of):.2f}",
                      f"{med(r['planner_s'] for r in of):.2f}", f"{max(r['planner_s'] for r in of):.2f}",
                      f"{med(r['plan_s'] for r in of):.2f}", f"{max(r['plan_s'] for r in of):.2f}",
                      f"{med(r['length'] or 0 for r in of):.0f}"])  # fmt: skip
    lines += record.table(
        ["domain", "tasks", "median read s", "median planner s", "max planner s",
         "median wall s", "max wall s", "median length"], table,
    )  # fmt: skip
    fig = Figure(figsize=(8.0, 3.6), layout="constrained")
    axes = fig.subplots()
    for i, d in enumerate(domains):
        times = [r["planner_s"] for r in rows if r["domain"] == d]
        offsets = [i + 0.25 * ((k % 5) - 2) / 2 for k in range(len(times))]
        axes.scatter(offsets, times, s=14, alpha=0.7, color=f"C{i}")
    axes.set_xticks(range(len(domains)), domains)
    axes.set_yscale("log")
    axes.set_ylabel("planner time s (log scale)")
    axes.set_title("Planner time of every task, by domain")
    axes.grid(alpha=0.3, which="both", axis="y")
    lines += [
        "",
        "## Figure",
        "",
        figure(fig, "planner-time", "Planner time per task by domain"),
        "",
    ]
    lines += ["## Every task", "", '<details markdown="1"><summary>all rows</summary>', ""]
    lines += record.table(
        ["task", "read s", "wall s", "planner s", "direct s", "ratio", "length", "status"],
        [[r["name"], f"{r['parse_s']:.3f}", f"{r['plan_s']:.3f}", f"{r['planner_s']:.3f}",
          f"{r['direct_s']:.3f}", f"{r['ratio']:.3f}", r["length"], r["status"]] for r in rows],
    )  # fmt: skip
    lines += ["", "</details>", ""]
    return lines
