"""The results page of the rows ``bench/bench_replay.py`` writes (``make results``:
:mod:`tools.results`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tools import record

REPO = Path(__file__).resolve().parent.parent.parent
TABLE_ONE = REPO / "docs" / "report" / "replay" / "replay_table1.csv"
FIG_THREE = "../report/replay/replay_fig3.png"  # from docs/results/


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page (tools.results): what the replay bench printed, then the replay
    report's Table I (``docs/report/replay/replay_table1.csv``, written by ``twostep-report``
    from the same sweep) as a table, and its Fig. 3."""
    import csv

    lines = record.printed_page(records, figure)
    with TABLE_ONE.open(newline="") as handle:
        table = list(csv.DictReader(handle))
    lines += [
        "## Table I from the replayed answers",
        "",
        "The report of the replay sweep (`twostep-report`, the reproduce-the-paper how-to): "
        "per domain and N, the official TwoStep's lengths from its logs, the same answers "
        "run through twostep, and plan-deal; exec length and SA length are means over the "
        "row's tasks (`tasks`), length / SA the one over the other. "
        "Rows: [`docs/report/replay/replay_table1.csv`](../report/replay/replay_table1.csv).",
        "",
    ]
    lines += record.table(
        ["domain", "N", "row", "tasks", "exec length", "SA length", "length / SA"],
        (
            [r["domain"], r["agents"], r["row"], r["tasks"], f"{float(r['exec_length']):.2f}",
             f"{float(r['sa_length']):.2f}", f"{float(r['length_over_sa']):.3f}"]
            for r in table
        ),
    )  # fmt: skip
    lines += ["", f"![Fig. 3 of the replay: exec length / SA length against N]({FIG_THREE})", ""]
    return lines
