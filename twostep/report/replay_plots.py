"""Fig. 3 of a replay, and the files of a replay report (:func:`write_replay`).

One panel per domain: execution length against N for the three rows of Table I
(:mod:`twostep.report.replay`), each on the tasks all three cover at that N, with the
spread over runs as error bars where there are several; the single-agent lengths at N = 1
(the official code's and twostep's, which differ: anytime LAMA against twostep's planner).
A last panel averages each row's length / SA over the domains (the macro row).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from twostep.report.plots import _new_figure, paper_style, save_figure
from twostep.report.replay import (
    LABELS,
    SOURCES,
    ReplayTables,
    compact_markdown,
    coverage_markdown,
    table_markdown,
)
from twostep.report.style import COLUMN_WIDTH_IN, OKABE_ITO, TEXT_WIDTH_IN
from twostep.util.files import write_text_atomic

COLOURS = {
    "official": (OKABE_ITO["sky blue"], "s", "--"),
    "twostep": (OKABE_ITO["reddish purple"], "v", "-"),
    "plan-deal": (OKABE_ITO["orange"], "P", "-"),
}
CHECK_GLOB = "translation_check*.json"


def replay_figure(tables: ReplayTables) -> Figure:
    """Fig. 3 of the replay (see the module docstring)."""
    table = tables.table
    domains = sorted(table["domain"].unique())
    panels = len(domains) + 1
    columns = min(panels, 3)
    rows = math.ceil(panels / columns)
    with paper_style():
        figure = _new_figure(TEXT_WIDTH_IN, max(COLUMN_WIDTH_IN * 0.62 * rows, 2.2))
        axes = figure.subplots(rows, columns, squeeze=False).ravel()
        for ax, domain in zip(axes, domains, strict=False):
            cells = table[table["domain"] == domain]
            for source in SOURCES:
                colour, marker, line = COLOURS[source]
                part = cells[(cells["source"] == source) & cells["tasks"].gt(0)]
                part = part.sort_values("agents")
                if part.empty:
                    continue
                spread = part["std"].fillna(0.0)
                ax.errorbar(
                    part["agents"], part["exec_length"], yerr=spread, color=colour,
                    marker=marker, linestyle=line, capsize=2, label=LABELS[source],
                )  # fmt: skip
                first = part.iloc[0]
                ax.plot([1], [first["sa_length"]], marker=marker, color=colour, linestyle="none")
            ax.set_title(domain)
            ax.set_xlabel("agents N (N = 1: its SA plan)")
            ax.set_ylabel("execution length")
            ax.grid(True, alpha=0.4)
            ax.set_xticks(range(1, int(table["agents"].max()) + 1))
        macro_ax = axes[len(domains)]
        for source in SOURCES:
            colour, marker, line = COLOURS[source]
            part = tables.macro[tables.macro["source"] == source].sort_values("agents")
            if part.empty:
                continue
            macro_ax.plot(
                [1, *part["agents"]], [1.0, *part["length_over_sa"]], color=colour,
                marker=marker, linestyle=line, label=LABELS[source],
            )  # fmt: skip
        macro_ax.set_title("all domains: length / own SA")
        macro_ax.set_xticks(range(1, int(table["agents"].max()) + 1))
        macro_ax.set_xlabel("agents N")
        macro_ax.grid(True, alpha=0.4)
        for extra in axes[panels:]:
            extra.set_visible(False)
        handles, labels = macro_ax.get_legend_handles_labels()
        figure.legend(handles, labels, loc="outside lower center", ncols=3)
    return figure


def write_replay(
    tables: ReplayTables, bundle_dir: Path, out_dir: Path, settings: dict[str, Any]
) -> list[Path]:
    """``replay.md`` (Table I, the macro row, the translation checks the bundle's folder
    holds: ``translation_check*.json``), ``replay_table1.csv`` and the figure
    ``replay_fig3`` (PNG, PDF, SVG)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    csv = out_dir / "replay_table1.csv"
    tables.table.to_csv(csv, index=False)
    paths.append(csv)
    if not tables.empty:
        paths += save_figure(replay_figure(tables), out_dir / "replay_fig3")
    lines = [
        "# Table I and Fig. 3 from replayed model answers",
        "",
        f"Answers of {tables.model} from the bundle `{bundle_dir}`; twostep's planner: "
        f"{settings.get('planner', '?')}; twostep's execution length: {settings.get('score', '?')}. "
        "The official rows are the official code's own numbers from its logs (anytime LAMA "
        "with its 100 s search limit per call; its execution length by the paper's "
        "Algorithm 1).",
        "",
        "Each cell averages the tasks all three rows cover at that N (`tasks`; `own tasks`: "
        "what the row has alone). `runs`: logs (official) or seeds (TwoStep) averaged; with "
        "more than one the cell shows mean ± standard deviation over runs, with one none.",
        "",
        "Execution length (tasks) per domain, row and N:",
        "",
        compact_markdown(tables),
        "The cells in full:",
        "",
        table_markdown(tables),
    ]
    checks = sorted(bundle_dir.glob(CHECK_GLOB))
    if checks:
        lines += ["## Translation of the replayed subgoals (rules)", ""]
    for check in checks:  # twostep-data check-answers (one file per planner setting)
        data = json.loads(check.read_text(encoding="utf-8"))
        lines += [f"`{check.name}`:", "", coverage_markdown(data)]
    if not tables.empty:
        lines += ["![Fig. 3 from replayed answers](replay_fig3.png)", ""]
    page = out_dir / "replay.md"
    write_text_atomic(page, "\n".join(lines))
    paths.append(page)
    return paths
