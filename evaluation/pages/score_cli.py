"""The results page of the rows ``bench/bench_score_cli.py`` writes (``make results``:
:mod:`tools.results`), and the goal the bench prints its runs against.
"""

from __future__ import annotations

import statistics
from typing import Any

from tools import record

GOAL_S = 1.5  # the command's wall time when it reads and grounds the PDDL (no cache)


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of a ``--json`` record (tools.results): medians per command, the
    goal for the uncached read, and a figure of every run."""
    from matplotlib.figure import Figure

    (data,) = records
    rows, goal = data["rows"], data.get("goal_s", GOAL_S)
    lines = [
        "## Summary",
        "",
        f"`twostep-score` on {data.get('agents')} plans of {data.get('steps')} steps (each agent "
        "drives its own cart along a private track, so the search takes milliseconds and the "
        f"time is the process's); medians of {data.get('repeats')} fresh processes, timed from "
        "outside (CPU: user + system of the process).",
        "",
    ]
    table = []
    for row in rows:
        wall, cpu = statistics.median(row["wall_s"]), statistics.median(row["cpu_s"])
        verdict = ""
        if "--no-cache" in row["command"] and row["command"].startswith("twostep-score"):
            verdict = f"<= {goal:g}: " + ("met" if wall <= goal else "missed")
        table.append([row["command"], f"{wall:.2f}", f"{cpu:.2f}", verdict])
    lines += record.table(["command", "wall s", "CPU s", "goal (wall s)"], table)
    drawn = Figure(figsize=(6.4, 2.6), layout="constrained")
    axes = drawn.subplots()
    for y, row in enumerate(rows):
        axes.scatter(row["wall_s"], [y] * len(row["wall_s"]), marker="o", color="#0072B2",
                     label="wall" if y == 0 else None)  # fmt: skip
        axes.scatter(row["cpu_s"], [y - 0.15] * len(row["cpu_s"]), marker="s", color="#D55E00",
                     label="CPU" if y == 0 else None)  # fmt: skip
    axes.axvline(goal, color="grey", linestyle="--", linewidth=1, label=f"goal {goal:g} s")
    axes.set_yticks(range(len(rows)), [r["command"] for r in rows], fontsize=8)
    axes.invert_yaxis()
    axes.set_xscale("log")
    axes.set_xlabel("seconds per run (log scale)")
    axes.legend(fontsize=8, loc="lower right")
    alt = "Wall and CPU seconds of every run of each twostep-score command"
    lines += ["", "## Figure", "", figure(drawn, "runs", alt), "",
              "Every run: wall time (circles) and CPU time (squares).", ""]  # fmt: skip
    return lines
