"""The results page of the rows ``bench/bench_execution.py`` writes (``make results``:
:mod:`tools.results`).
"""

from __future__ import annotations

from typing import Any

from tools import record


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of the two ``--json`` records, the comparison and ``--scaling``
    (tools.results)."""
    from matplotlib.figure import Figure

    comparison, scaled = records
    lines = [
        "## Against a straightforward search",
        "",
        f"N = {comparison.get('agents')} agents; twostep: median of {comparison.get('repeats')} "
        "runs of `twostep.makespan.parallel_length`; plain: the same straightforward search "
        "on our bit-set states; UP: that search with each joint step checked by "
        "unified-planning's `SequentialSimulator` (one run, stopped past "
        f"{comparison.get('budget_s'):g} s: `-`).",
        "",
    ]
    table = []
    for r in comparison["rows"]:
        up = r["up_ms"] is not None
        table.append([r["case"], r["steps_per_agent"], r["mode"], r["exec_length"],
                      f"{r['ours_ms']:.1f} ({r['ours_nodes']})", f"{r['plain_ms']:.1f} ({r['plain_nodes']})",
                      f"{r['up_ms']:.0f} ({r['up_nodes']})" if up else "-",
                      f"{r['up_ms'] / r['ours_ms']:.0f}x" if up else "-",
                      f"{r['up_ms'] / r['plain_ms']:.0f}x" if up else "-", r["note"]])  # fmt: skip
    lines += record.table(
        ["case", "steps/agent", "mode", "exec length", "twostep ms (nodes)", "plain ms (nodes)",
         "UP simulator ms (nodes)", "UP / twostep", "UP / plain", "note"], table,
    )  # fmt: skip
    budget = scaled.get("budget", {})
    lines += [
        "",
        "## Many agents",
        "",
        f"Exact mode, one run each, node budget {budget.get('max_nodes')}, time budget "
        f"{budget.get('time_limit_s')} s. `shared`: every track crosses one hub (the "
        "length is derived by hand: the steps per agent + 2 (N - 1)); `staggered`: two shared "
        "cells at positions that differ by cart. Interchangeable: the classes of agents the "
        "search treats as one (their sizes). A row that is not exact stopped at the budget: "
        "its schedule is valid and the lower bound proven.",
        "",
    ]
    rows = scaled["rows"]
    lines += record.table(
        ["case", "N", "steps/agent", "interchangeable", "wall ms", "CPU ms", "nodes", "length",
         "lower bound", "exact", "gap", "hand-derived"],
        [[r["case"], r["agents"], r["steps_per_agent"], r["interchangeable"], f"{r['wall_ms']:.0f}",
          f"{r['cpu_ms']:.0f}", r["nodes"], r["length"], r["lower_bound"],
          "yes" if r["exact"] else "no", r["gap"],
          "-" if r["hand_derived"] is None else r["hand_derived"]] for r in rows],
    )  # fmt: skip
    exact = sum(r["exact"] for r in rows)
    derived = [r for r in rows if r["hand_derived"] is not None]
    agree = sum(r["length"] == r["hand_derived"] for r in derived)
    lines += ["", f"{exact} of {len(rows)} cases proven optimal; the shared case's length "
              f"agrees with the hand-derived one in {agree} of {len(derived)}."]  # fmt: skip
    fig = Figure(figsize=(9.0, 3.6), layout="constrained")
    by_case = fig.subplots(1, 2, sharey=True)
    for axes, case in zip(by_case, ("shared", "staggered"), strict=True):
        for k, steps in enumerate(sorted({r["steps_per_agent"] for r in rows})):
            of = [r for r in rows if r["case"] == case and r["steps_per_agent"] == steps]
            axes.plot([r["agents"] for r in of], [r["cpu_ms"] for r in of], marker="o",
                      color=f"C{k}", label=f"{steps} steps/agent")  # fmt: skip
            stopped = [r for r in of if not r["exact"]]
            axes.scatter([r["agents"] for r in stopped], [r["cpu_ms"] for r in stopped],
                         marker="x", s=60, color="black", zorder=5)  # fmt: skip
        axes.set_yscale("log")
        axes.set_xlabel("agents N")
        axes.set_title(f"{case} (x: stopped at the budget)")
        axes.grid(alpha=0.3, which="both")
    by_case[0].set_ylabel("CPU ms (log scale)")
    by_case[0].legend(fontsize=8)
    lines += [
        "",
        "## Figure",
        "",
        figure(fig, "scaling", "CPU time of the exact scorer against N"),
        "",
    ]
    return lines
