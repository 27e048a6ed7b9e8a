"""The results page of the rows ``bench/bench_deal_generated.py`` writes (``make results``:
:mod:`tools.results`).
"""

from __future__ import annotations

from typing import Any

from tools import record


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of plan-deal beyond the benchmark (tools.results): a figure of this
    bench's rows (plan-deal's length against the SA plan's, per N), then what each of the
    records printed (this bench's, bench_deal_ipc's, bench_deal_budget's, bench_dealing's)."""
    from matplotlib.figure import Figure

    rows = records[0]["rows"]
    column = next((c for c in rows[0] if c.startswith("plan-deal N=")), "") if rows else ""
    agents = column.removeprefix("plan-deal N=").split("/") if column else []
    fig = Figure(figsize=(6.4, 4.2))
    axes = fig.subplots()
    top = 1
    for k, n in enumerate(agents):
        points = [(int(r["SA"]), int(r[column].split("/")[k])) for r in rows
                  if r.get("SA", "").isdigit() and r.get(column, "").count("/") == len(agents) - 1]  # fmt: skip
        if points:
            top = max(top, *(sa for sa, _ in points))
            xs, ys = zip(*points, strict=True)
            axes.scatter(xs, ys, s=12, alpha=0.6, label=f"N = {n}")
    axes.plot([0, top], [0, top], color="grey", linewidth=0.8, label="as long as SA")
    axes.set_xlabel("SA plan length")
    axes.set_ylabel("plan-deal exec length")
    axes.set_title("plan-deal on generated problems (seven IPC domains)")
    axes.legend()
    fig.tight_layout()
    alt = "plan-deal's exec length against the SA plan's length on the generated problems"
    return [figure(fig, "generated", alt), "", *record.printed_page(records, figure)]
