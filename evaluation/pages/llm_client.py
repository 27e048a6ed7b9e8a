"""The results page of the rows ``bench/bench_llm_client.py`` writes (``make results``:
:mod:`tools.results`), and the goal the bench prints its runs against.
"""

from __future__ import annotations

import statistics
from typing import Any

from tools import record

GOAL_MS = 5.0  # a cache hit's median


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of a ``--json`` record (tools.results)."""
    from matplotlib.figure import Figure

    (data,) = records
    rows, goal = data["rows"], data.get("goal_ms", GOAL_MS)
    hit = statistics.median(rows[0]["ms"])
    mocked = statistics.median(rows[-1]["ms"])
    lines = [
        "## Summary",
        "",
        f"`LLMClient.complete` on a prompt of {data.get('prompt_chars')} characters (the "
        f"subgoal generator's size), {data.get('calls')} calls each; the first call of the "
        f"process (litellm's import, a mocked answer, the cache write) took "
        f"{data.get('first_call_ms', 0):.0f} ms.",
        "",
    ]
    table = []
    for row in rows:
        times = sorted(row["ms"])
        p95 = times[min(len(times) - 1, int(0.95 * len(times)))]
        table.append([row["call"], f"{statistics.median(times):.3f}", f"{p95:.3f}"])
    lines += record.table(["call", "median ms", "p95 ms"], table)
    lines += ["", f"A cache hit's median: {hit:.3f} ms, goal under {goal:g} ms: "
              + ("met" if hit < goal else "missed")
              + f"; {mocked / hit:.0f}x faster than a mocked litellm call.", ""]  # fmt: skip
    drawn = Figure(figsize=(6.4, 2.4), layout="constrained")
    axes = drawn.subplots()
    axes.boxplot([r["ms"] for r in rows], vert=False, showfliers=False)
    axes.set_yticks(range(1, len(rows) + 1), [r["call"] for r in rows], fontsize=8)
    axes.invert_yaxis()
    axes.set_xscale("log")
    axes.axvline(goal, color="grey", linestyle="--", linewidth=1)
    axes.set_xlabel("milliseconds per call (log scale; dashed: the goal)")
    alt = "Milliseconds per LLM client call: cache hits, scripted answers, mocked litellm calls"
    lines += ["## Figure", "", figure(drawn, "calls", alt), "",
              "Each call's time, per kind of call (box: quartiles; whiskers: the rest, "
              "outliers left out).", ""]  # fmt: skip
    return lines
