"""Load time on real PDDL, as the results page shows it: the corpus's medians and maxima
(:func:`summary`) and the load-time part of the conformance page (:func:`section`), from
the rows of ``bench/bench_load.py --out``.
"""

from __future__ import annotations

import statistics
from typing import Any

from tools import record


def fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def summary(rows: list[dict[str, Any]]) -> list[str]:
    """The corpus's medians and maxima and the AlfWorld-shaped problem's line (the last row)."""
    lines = []
    alf = rows[-1]
    corpus_rows = rows[:-1]
    both = [r for r in corpus_rows if r["twostep_load_s"] is not None and r["fd_translate_wall_s"]]
    fds = [r["fd_translate_wall_s"] for r in corpus_rows if r["fd_translate_wall_s"] is not None]
    if corpus_rows:
        lines.append(f"twostep loads {len(both)}/{len(corpus_rows)} problems")
    if both:
        loads = [r["twostep_load_s"] for r in both]
        worst = max(both, key=lambda r: r["twostep_load_s"])
        lines.append(
            f"on those {len(both)}: twostep load (process) median {statistics.median(loads):.2f} s, "
            f"max {max(loads):.2f} s ({worst['key']}), above 5 s: {sum(x > 5 for x in loads)}; "
            f"Fast Downward translate (process) median "
            f"{statistics.median(r['fd_translate_wall_s'] for r in both):.2f} s; "
            f"ratio median {statistics.median(r['ratio'] for r in both):.1f}x"
        )
    if fds:
        lines.append(
            f"Fast Downward translate (process), all {len(fds)}: median {statistics.median(fds):.2f} s, "
            f"max {max(fds):.2f} s"
        )
    lines.append(
        f"AlfWorld ({alf['key']}): twostep cold {fmt(alf['twostep_load_s'])} s, warm "
        f"{fmt(alf['twostep_warm_s'])} s; Fast Downward translate {fmt(alf['fd_translate_wall_s'])} s"
    )
    return lines


def section(data: dict[str, Any], figure: Any) -> list[str]:
    """The load-time part of the conformance results page, from an ``--out`` file."""
    from matplotlib.figure import Figure

    rows = data["rows"]
    baseline = data.get("baseline_s")
    lines = [
        "## Load time",
        "",
        f"Process wall times, start to end, medians of {data.get('repeats')} runs: twostep's "
        "load-only command (`twostep-score DOMAIN PROBLEM EMPTY_PLAN --no-cache`: read and "
        "ground the task), warm (the parsed-task cache), and Fast Downward's translator on "
        "the same files (process; own: its \"Done!\" time). The process start-up alone "
        f"(`twostep-score --help`): {baseline:.2f} s. The last row is the 65-object "
        "AlfWorld-shaped problem (`tests/fixtures/constructs/exists_goal/p02.pddl`).",
        "",
        *(f"- {line}" for line in summary(rows)),
        "",
        *record.table(
            ["problem", "twostep s", "twostep warm s", "FD translate s", "FD own s", "ratio", "error"],
            [[r["key"], fmt(r["twostep_load_s"]), fmt(r["twostep_warm_s"]),
              fmt(r["fd_translate_wall_s"]), fmt(r["fd_translate_own_s"]),
              "" if r["ratio"] is None else f"{r['ratio']:.1f}", r["error"]] for r in rows],
        ),
        "",
    ]  # fmt: skip
    fig = Figure(figsize=(9.0, 3.4), layout="constrained")
    axes = fig.subplots()
    shown = [r for r in rows if r["twostep_load_s"] is not None and r["fd_translate_wall_s"]]
    xs = range(len(shown))
    axes.bar([x - 0.2 for x in xs], [r["twostep_load_s"] for r in shown], 0.4, label="twostep")
    axes.bar([x + 0.2 for x in xs], [r["fd_translate_wall_s"] for r in shown], 0.4,
             label="Fast Downward translator")  # fmt: skip
    axes.set_xticks(list(xs), [r["key"].split("/")[0] for r in shown], rotation=90, fontsize=7)
    axes.set_ylabel("process wall s")
    axes.set_title("Reading and grounding each problem")
    axes.legend(fontsize=8)
    axes.grid(alpha=0.3, axis="y")
    lines += [
        figure(fig, "load", "Load time per problem, twostep and Fast Downward's translator"),
        "",
    ]
    return lines
