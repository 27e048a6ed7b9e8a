"""Fig. 3 of a :class:`~twostep.report.model.Report` as figures ready for a paper.

``fig3_<domain>`` (one column wide): execution length and planning time against N for
every series; with two or more domains also ``fig3_normalised`` (one column): the
cross-domain panel of min-max normalised averages, and ``fig3_overview`` (two columns
wide): every domain and the normalised panel, as the paper's Fig. 3. Each is written as PNG, PDF and SVG
(:mod:`twostep.report.style` owns sizes, fonts, colours and markers).

What the marks mean:

* Points are the *compared* means (:mod:`twostep.report.compared`): the average over the
  tasks every series of the domain solved, of one distinct run for a deterministic series
  (n = 1, no band), else the mean over seeds with a band (lines) or error bar (bars) of
  ±1 sample std over seeds; the legend gives each series' n
  (:mod:`twostep.report.seeds`). Kitchen domains draw their embodied length.
* A hollow marker or hollow bar: the series lost runs in that cell (failed, timed out,
  unfinished or without a length); the legend counts them per series, per task and seed,
  e.g. ``MA (n = 1; 3 timeouts)``. An ``x`` on the axis: the cell solved no task.
* Normalised panels say so on their y axis (``Length, normalised 0-1``); a point that
  averages fewer domains than the others is half-filled, ``k/n`` beside it (on a bar).
* The series of a panel are set a little apart at each N (:data:`DODGE`), so that no
  marker hides another.
* Lines when some series has results at two or more N; otherwise (one N per series, such
  as Table II's runs) grouped bars per N. SA, run at N = 1 only, is a single marker with a
  dashed reference line across.
* Linear y axes start at 0; planning times spanning more than :data:`LOG_RATIO` are drawn on
  a log axis.

Figures are :class:`matplotlib.figure.Figure` objects with an Agg canvas (no pyplot), built
and saved under :data:`~twostep.report.style.PAPER_RC`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import matplotlib as mpl
import pandas as pd
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.textpath import TextToPath

from twostep.report.model import METRIC_LABELS, REPORT_METRICS, Report
from twostep.report.style import (
    COLUMN_WIDTH_IN,
    FIGURE_FORMATS,
    MIN_FONT_PT,
    PAPER_RC,
    PNG_DPI,
    TEXT_WIDTH_IN,
    TITLE_FONT_PT,
    LineStyle,
    SeriesStyle,
    series_styles,
)

#: Planning times spanning more than this ratio are drawn on a log axis.
LOG_RATIO = 50.0
TIME = REPORT_METRICS[1]
X_LABEL = "Number of agents N"
PANEL_HEIGHT_IN = 2.0  # a row of panels with its title and axis labels
HOLLOW = "white"


@dataclass(frozen=True)
class Cell:
    """One point (or bar) of a series: its N, mean, std and what it lost; ``fewer``: a
    normalised point over fewer domains than the figure's (``"4/5"``), else ``""``."""

    agents: int
    mean: float
    std: float
    lost: bool = False
    fewer: str = ""

    @property
    def solved_none(self) -> bool:
        return math.isnan(self.mean)


@contextmanager
def paper_style() -> Iterator[None]:
    """Build and save figures under the report's print settings."""
    with mpl.rc_context(cast("Any", PAPER_RC)):
        yield


def report_styles(report: Report) -> dict[str, SeriesStyle]:
    """The style of every series of ``report`` (:func:`~twostep.report.style.series_styles`)."""
    counted = report.runs[report.runs["counted"]]
    rows = counted[["series", "method", "decomposer", "variant"]].drop_duplicates()
    return series_styles(
        (str(r.series), str(r.method), str(r.decomposer), str(r.variant))
        for r in rows.itertuples(index=False)
    )


def draws_bars(report: Report) -> bool:
    """True when no series has results at two or more N: bars instead of isolated dots."""
    rows = report.compared[report.compared["method"] != "sa"]
    with_mean = rows[rows[f"{TIME}_mean"].notna()]
    per_series = with_mean.groupby(["domain", "series"])["agents"].nunique()
    return not bool((per_series >= 2).any())


# ------------------------------------------------------------------ data of a panel


def _domain_cells(report: Report, domain: str, series: str, metric: str) -> list[Cell]:
    rows = report.compared[
        (report.compared["domain"] == domain) & (report.compared["series"] == series)
    ].sort_values("agents")
    return [
        Cell(
            int(row["agents"]),
            float(row[f"{metric}_mean"]),
            0.0 if pd.isna(row[f"{metric}_std"]) else float(row[f"{metric}_std"]),
            int(row["n_lost"]) > 0,
        )
        for row in rows.to_dict("records")
    ]


def _normalised_cells(report: Report, series: str, metric: str) -> list[Cell]:
    cross = report.cross_domain
    rows = cross[(cross["series"] == series) & (cross["metric"] == metric)].sort_values("agents")
    most = int(cross["n_domains"].max()) if len(cross) else 0
    return [
        Cell(
            int(row["agents"]),
            float(row["normalised_mean"]),
            0.0 if pd.isna(row["normalised_std"]) else float(row["normalised_std"]),
            fewer=f"{int(row['n_domains'])}/{most}" if int(row["n_domains"]) < most else "",
        )
        for row in rows.to_dict("records")
    ]


def _plural(count: int, word: str, plural: str = "") -> str:
    return f"{count} {word if count == 1 else plural or word + 's'}"


def lost_counts(report: Report, series: str, domains: Sequence[str]) -> str:
    """What ``series`` lost in ``domains``: ``1 timeout``, ``2 failed, 1 unfinished``..."""
    rows = report.compared[
        (report.compared["series"] == series) & report.compared["domain"].isin(domains)
    ]
    failed, timeout = int(rows["n_failed"].sum()), int(rows["n_timeout"].sum())
    running = int(rows["n_running"].sum())
    unmeasured = int(rows["n_lost"].sum()) - failed - timeout - running
    parts = []
    if failed:
        parts.append(f"{failed} failed")
    if timeout:
        parts.append(_plural(timeout, "timeout"))
    if running:
        parts.append(f"{running} unfinished")
    if unmeasured > 0:
        parts.append(f"{unmeasured} without length")
    return ", ".join(parts)


def series_n(report: Report, series: str, domains: Sequence[str]) -> str:
    """``n = 1`` for a deterministic series (one distinct run per point), else the seeds
    its points average, ``n = 3`` (``n = 2-3`` when they differ)."""
    rows = report.compared[
        (report.compared["series"] == series) & report.compared["domain"].isin(domains)
    ]
    if "seeded" in rows and not bool(rows["seeded"].any()):
        return "n = 1"
    counts = sorted({int(n) for n in rows[f"{TIME}_n_seeds"] if int(n) > 0})
    if not counts:
        return "n = 0"
    return f"n = {counts[0]}" if len(counts) == 1 else f"n = {counts[0]}-{counts[-1]}"


def legend_label(report: Report, series: str, domains: Sequence[str] | None = None) -> str:
    """The series' legend label: its name, n (runs per point: :func:`series_n`),
    ``subset of tasks`` when it ran fewer tasks than its domains, and the runs it lost
    (per task and seed), e.g. ``MA (n = 1; 3 timeouts)``."""
    chosen = list(report.domains if domains is None else domains)
    rows = report.compared[
        (report.compared["series"] == series) & report.compared["domain"].isin(chosen)
    ]
    domain_tasks = dict(zip(report.coverage["domain"], report.coverage["n_tasks"], strict=True))
    notes = [series_n(report, series, chosen)]
    if any(int(r.n_tasks) < int(domain_tasks.get(r.domain, 0)) for r in rows.itertuples()):
        notes.append("subset of tasks")
    lost = lost_counts(report, series, chosen)
    if lost:
        notes.append(lost)
    return f"{series} ({'; '.join(notes)})" if notes else series


# ------------------------------------------------------------------ drawing


#: How far apart (in N) the markers of the series of one panel are set, so that none
#: hides another at the same N.
DODGE = 0.2


def dodges(names: Sequence[str]) -> dict[str, float]:
    """Each series' x offset in a panel: centred around N, :data:`DODGE` apart."""
    return {name: (i - (len(names) - 1) / 2) * DODGE for i, name in enumerate(names)}


def _draw_lines(ax: Axes, cells: Sequence[Cell], style: SeriesStyle, dodge: float = 0.0) -> None:
    have = [c for c in cells if not c.solved_none]
    sa = style.method == "sa"
    if have:
        xs = [c.agents + dodge for c in have]
        means = [c.mean for c in have]
        stds = [c.std for c in have]
        if sa:
            ax.axhline(means[0], color=style.color, linestyle="--", linewidth=0.9, alpha=0.7)
        if len(have) > 1 and not sa:
            ax.plot(xs, means, color=style.color, linestyle=style.linestyle, zorder=2)
            if any(stds):
                low = [m - s for m, s in zip(means, stds, strict=True)]
                high = [m + s for m, s in zip(means, stds, strict=True)]
                ax.fill_between(xs, low, high, color=style.color, alpha=0.18, linewidth=0)
        elif any(stds):
            ax.errorbar(xs, means, yerr=stds, color=style.color, capsize=2, linestyle="none")
        for cell in have:
            ax.plot(
                [cell.agents + dodge],
                [cell.mean],
                linestyle="none",
                marker=style.marker,
                color=style.color,
                markerfacecolor=HOLLOW if cell.lost else style.color,
                markerfacecoloralt=HOLLOW,
                fillstyle="left" if cell.fewer else "full",
                markeredgewidth=1.0,
                zorder=4 if sa else 3,
            )
            if cell.fewer:  # a mean over fewer domains: half-filled, with k/n beside it
                ax.annotate(
                    cell.fewer,
                    (cell.agents + dodge, cell.mean),
                    xytext=(0, 4),
                    textcoords="offset points",
                    ha="center",
                    va="bottom",
                    fontsize=MIN_FONT_PT,
                    color=style.color,
                )
    _draw_solved_none(ax, [c.agents + dodge for c in cells if c.solved_none], style)


def _draw_solved_none(ax: Axes, agents: Sequence[float], style: SeriesStyle) -> None:
    """An x on the axis (data x, axes y) where a cell solved no task."""
    for x in agents:
        ax.plot(
            [x],
            [0.0],
            transform=ax.get_xaxis_transform(),
            linestyle="none",
            marker="x",
            markersize=6,
            markeredgewidth=1.4,
            color=style.color,
            clip_on=False,
            zorder=5,
        )


def _draw_bars(ax: Axes, cells_of: dict[str, list[Cell]], styles: dict[str, SeriesStyle]) -> None:
    """Grouped bars: one group per N, one bar per series that ran at that N."""
    agent_counts = sorted({c.agents for cells in cells_of.values() for c in cells})
    groups = {
        agents: [
            (name, cell) for name, cells in cells_of.items() for cell in cells
            if cell.agents == agents
        ]
        for agents in agent_counts
    }  # fmt: skip
    width = 0.8 / max((len(group) for group in groups.values()), default=1)  # one bar width
    for agents, present in groups.items():
        for index, (name, cell) in enumerate(present):
            style = styles[name]
            x = agents + (index - (len(present) - 1) / 2) * width
            if cell.solved_none:
                _draw_solved_none(ax, [x], style)
                continue
            ax.bar(
                x,
                cell.mean,
                width * 0.92,
                color=HOLLOW if cell.lost else style.color,
                edgecolor=style.color,
                hatch=style.hatch or None,
                linewidth=1.0,
                zorder=2,
            )
            if cell.std:
                ax.errorbar(
                    x, cell.mean, yerr=cell.std, color="black", capsize=2, linewidth=0.8,
                    linestyle="none", zorder=3,
                )  # fmt: skip
            if cell.fewer:  # a normalised mean over fewer domains: k/n above its bar
                ax.annotate(
                    cell.fewer, (x, cell.mean), xytext=(0, 2), textcoords="offset points",
                    ha="center", fontsize=MIN_FONT_PT, color=style.color,
                )  # fmt: skip


def normalised_label(metric: str) -> str:
    """``Length, normalised 0-1``: what a normalised panel's values are (no unit)."""
    name = METRIC_LABELS[metric].split(" (")[0].replace("Execution length", "Length")
    return f"{name}, normalised 0-1"


def _use_log(values: Sequence[float]) -> bool:
    positive = [v for v in values if v > 0 and not math.isnan(v)]
    return len(positive) >= 2 and max(positive) / min(positive) > LOG_RATIO


def _finish_axis(
    ax: Axes, agent_counts: Sequence[int], ylabel: str, log: bool, top: float | None = None
) -> None:
    ax.set_xticks(list(agent_counts))
    ax.set_xlim(min(agent_counts) - 0.5, max(agent_counts) + 0.5)
    if log:
        ax.set_yscale("log")
        ylabel = ylabel.replace(")", ", log)") if ylabel else ylabel
    else:
        high = float(ax.dataLim.y1) if ax.dataLim.y1 > 0 else 1.0
        ax.set_ylim(0.0, top if top is not None else high * 1.1)  # room for the top marker
    if ylabel:
        ax.set_ylabel(ylabel, fontsize=MIN_FONT_PT)
    ax.tick_params(labelsize=MIN_FONT_PT)
    ax.grid(True, axis="y", alpha=0.3, which="major")


def _metric_axis(
    ax: Axes,
    report: Report,
    metric: str,
    styles: dict[str, SeriesStyle],
    bars: bool,
    domain: str | None = None,
    ylabel: bool = True,
) -> None:
    """One panel: ``metric`` against N for every series, in ``domain`` or (``None``) the
    cross-domain normalised averages."""
    cells_of = {
        name: cells
        for name in report.series
        if (
            cells := _domain_cells(report, domain, name, metric)
            if domain is not None
            else _normalised_cells(report, name, metric)
        )
    }
    if bars:
        _draw_bars(ax, cells_of, styles)
    else:
        offsets = dodges(list(cells_of))
        for name, cells in cells_of.items():
            _draw_lines(ax, cells, styles[name], offsets[name])
    if domain is None:
        _finish_axis(ax, report.agent_counts, normalised_label(metric), log=False, top=1.05)
        if not ylabel:  # beside another column's row label: say what this one is, right
            ax.yaxis.set_label_position("right")
        return
    log = metric == TIME and _use_log([c.mean for cells in cells_of.values() for c in cells])
    _finish_axis(ax, report.agent_counts, METRIC_LABELS[metric] if ylabel else "", log)


def _legend_entries(
    report: Report,
    series: Sequence[str],
    styles: dict[str, SeriesStyle],
    domains: Sequence[str],
    bars: bool,
    normalised: bool = False,
) -> tuple[list[Artist], list[str]]:
    handles: list[Artist] = []
    labels: list[str] = []
    rows = report.compared[report.compared["domain"].isin(domains)]
    with_mean = rows[rows[f"{TIME}_mean"].notna()]
    per_series = with_mean.groupby(["domain", "series"])["agents"].nunique()
    lines = {str(name) for (_, name), count in per_series.items() if count >= 2}
    for name in series:
        style = styles[name]
        if bars:
            handles.append(
                Patch(facecolor=style.color, edgecolor=style.color, hatch=style.hatch or None)
            )
        else:
            line: LineStyle = style.linestyle if name in lines else "none"
            handles.append(Line2D([], [], color=style.color, marker=style.marker, linestyle=line))
        labels.append(legend_label(report, name, domains))
    if not bars and "sa" in set(rows["method"]):
        handles.append(Line2D([], [], color="0.3", linestyle="--", linewidth=0.9))
        labels.append("SA (N = 1) as reference")
    if int(rows["n_lost"].sum()):
        if bars:
            handles.append(Patch(facecolor=HOLLOW, edgecolor="0.3"))
        else:
            handles.append(
                Line2D([], [], color="0.3", marker="o", markerfacecolor=HOLLOW, linestyle="none")
            )
        labels.append("hollow: runs lost")
    solved_none = rows[rows[f"{TIME}_mean"].isna() & (rows["n_runs"] > 0)]
    if len(solved_none):
        handles.append(Line2D([], [], color="0.3", marker="x", linestyle="none"))
        labels.append("x: no task solved")
    if not bars and normalised and len(report.cross_domain):
        most = int(report.cross_domain["n_domains"].max())
        if int(report.cross_domain["n_domains"].min()) < most:
            handles.append(
                Line2D([], [], color="0.3", marker="o", fillstyle="left", linestyle="none",
                       markerfacecoloralt=HOLLOW)
            )  # fmt: skip
            labels.append(f"half-filled, k/{most}: normalised over fewer domains")
    return handles, labels


def _legend_columns(labels: Sequence[str], width_in: float) -> int:
    """How many legend columns of ``labels`` fit across ``width_in`` (text measured)."""
    measure = TextToPath()
    font = FontProperties(size=MIN_FONT_PT)
    widest = max(
        (measure.get_text_width_height_descent(label, font, ismath=False)[0] for label in labels),
        default=0.0,
    )
    em = MIN_FONT_PT  # in points: handle 1.8 em and pad 0.8 em per column, 1 em between
    # columns, border pad 0.4 em on each side (matplotlib's legend defaults we draw with)
    columns = len(labels)
    while columns > 1 and columns * (widest + 2.6 * em) + (columns - 1 + 0.8) * em > width_in * 72:
        columns -= 1
    return max(1, columns)


@dataclass(frozen=True)
class Legend:
    """A figure's legend entries and how many columns fit at its print width."""

    handles: list[Artist]
    labels: list[str]
    columns: int

    @property
    def height_in(self) -> float:
        rows = math.ceil(len(self.labels) / self.columns) if self.labels else 0
        return 0.17 * rows + 0.08

    def draw(self, figure: Figure) -> None:
        if self.labels:
            figure.legend(
                self.handles,
                self.labels,
                loc="outside lower center",
                ncol=self.columns,
                frameon=False,
                fontsize=MIN_FONT_PT,
                handlelength=1.8,
                columnspacing=1.0,
            )


def _figure_legend(
    report: Report,
    domains: Sequence[str],
    styles: dict[str, SeriesStyle],
    bars: bool,
    width_in: float,
    normalised: bool = False,
) -> Legend:
    present = set(report.compared[report.compared["domain"].isin(domains)]["series"])
    series = [name for name in report.series if name in present]
    handles, labels = _legend_entries(report, series, styles, domains, bars, normalised)
    return Legend(handles, labels, _legend_columns(labels, width_in))


def _new_figure(width: float, height: float) -> Figure:
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _domain_title(
    report: Report, domain: str, separator: str = " ", solved: str = ", solved by all"
) -> str:
    """``termes (4 tasks)``; ``termes (3 of 4 tasks, solved by all)`` when runs were lost."""
    rows = report.coverage[report.coverage["domain"] == domain]
    if rows.empty:
        return domain
    tasks, compared = int(rows["n_tasks"].iloc[0]), int(rows["n_compared"].iloc[0])
    if compared < tasks:
        return f"{domain}{separator}({compared} of {tasks} tasks{solved})"
    return f"{domain}{separator}({_plural(tasks, 'task')})"


# ------------------------------------------------------------------ figures


def domain_figure(report: Report, domain: str) -> Figure:
    """One column wide: execution length and planning time against N for one domain."""
    with paper_style():
        styles = report_styles(report)
        bars = draws_bars(report)
        legend = _figure_legend(report, [domain], styles, bars, COLUMN_WIDTH_IN)
        figure = _new_figure(COLUMN_WIDTH_IN, PANEL_HEIGHT_IN + legend.height_in)
        axes = figure.subplots(1, 2)
        for ax, metric in zip(axes, (report.length_metric(domain), TIME), strict=True):
            _metric_axis(ax, report, metric, styles, bars, domain)
            ax.set_xlabel(X_LABEL, fontsize=MIN_FONT_PT)
        figure.suptitle(_domain_title(report, domain), fontsize=TITLE_FONT_PT)
        legend.draw(figure)
    return figure


def normalised_figure(report: Report) -> Figure:
    """One column wide: the per-domain compared averages min-max normalised, averaged."""
    with paper_style():
        styles = report_styles(report)
        bars = draws_bars(report)
        legend = _figure_legend(
            report, report.domains, styles, bars, COLUMN_WIDTH_IN, normalised=True
        )
        figure = _new_figure(COLUMN_WIDTH_IN, PANEL_HEIGHT_IN + legend.height_in)
        axes = figure.subplots(1, 2)
        for ax, metric in zip(axes, REPORT_METRICS, strict=True):
            _metric_axis(ax, report, metric, styles, bars)
            ax.set_xlabel(X_LABEL, fontsize=MIN_FONT_PT)
        figure.suptitle(
            f"All {len(report.domains)} domains, normalised to 0-1", fontsize=TITLE_FONT_PT
        )
        legend.draw(figure)
    return figure


def overview_figure(report: Report) -> Figure:
    """Two columns wide, as the paper's Fig. 3: one column per domain (length on top,
    planning time below) and, with two or more domains, the normalised column."""
    with paper_style():
        styles = report_styles(report)
        bars = draws_bars(report)
        domains = report.domains
        normalised = len(domains) >= 2 and len(report.cross_domain) > 0
        columns = len(domains) + int(normalised)
        legend = _figure_legend(report, domains, styles, bars, TEXT_WIDTH_IN, normalised)
        figure = _new_figure(TEXT_WIDTH_IN, 2 * PANEL_HEIGHT_IN + legend.height_in)
        axes = figure.subplots(2, columns, squeeze=False)
        first_length = report.length_metric(domains[0])
        for column, domain in enumerate(domains):
            length = report.length_metric(domain)
            label_length = column == 0 or length != first_length
            _metric_axis(axes[0][column], report, length, styles, bars, domain, label_length)
            _metric_axis(axes[1][column], report, TIME, styles, bars, domain, column == 0)
            title = _domain_title(report, domain, "\n", solved="")
            axes[0][column].set_title(title, fontsize=TITLE_FONT_PT)
        if normalised:
            for row, metric in enumerate(REPORT_METRICS):
                _metric_axis(axes[row][-1], report, metric, styles, bars, ylabel=False)
            axes[0][-1].set_title("All domains\n(normalised)", fontsize=TITLE_FONT_PT)
        for ax in axes[1]:
            ax.set_xlabel("N", fontsize=MIN_FONT_PT)
        legend.draw(figure)
    return figure


def save_figure(figure: Figure, stem: Path) -> list[Path]:
    """Write ``figure`` as ``stem.png`` (300 dpi), ``stem.pdf`` and ``stem.svg``."""
    paths = []
    with paper_style():
        for suffix in FIGURE_FORMATS:
            path = stem.with_suffix(f".{suffix}")
            figure.savefig(path, dpi=PNG_DPI, metadata=_metadata(suffix))
            paths.append(path)
    return paths


def _metadata(suffix: str) -> dict[str, str | None]:
    """No creation date in PDF/SVG files, so a figure redrawn from the same runs is the
    same file."""
    if suffix == "pdf":
        return {"CreationDate": None}
    if suffix == "svg":
        return {"Date": None}
    return {}


def plot_report(report: Report, out_dir: Path) -> list[Path]:
    """Every figure of a report into ``out_dir`` as PNG, PDF and SVG; returns the paths
    written (PNG first for each figure)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    if not report.has_results:
        return []
    figures = []
    if len(report.domains) >= 2:  # one domain: its own figure says it all
        figures.append(("fig3_overview", overview_figure(report)))
        if len(report.cross_domain):
            figures.append(("fig3_normalised", normalised_figure(report)))
    figures += [(f"fig3_{_slug(d)}", domain_figure(report, d)) for d in report.domains]
    paths: list[Path] = []
    for name, figure in figures:
        paths += save_figure(figure, out_dir / name)
    return paths


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)
