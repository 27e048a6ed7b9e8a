"""Fig. 3-style plots of a :class:`~twostep.report.build.Report` (matplotlib, Agg).

Per domain: execution length and planning time against N, one line per series (SA is
N = 1 only: a marker with a dashed reference line across), mean over seeds with a shaded
band of +- 1 std over seeds. Overview: all domains side by side plus the cross-domain
panel of min-max normalised averages, as in the paper. Figures are built on
:class:`matplotlib.figure.Figure` with an Agg canvas: no pyplot, no global state.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from twostep.report.build import METRIC_LABELS, REPORT_METRICS, Report

_TWOSTEP_COLORS = (
    "tab:blue",
    "tab:green",
    "tab:purple",
    "tab:orange",
    "tab:brown",
    "tab:cyan",
    "tab:olive",
    "tab:pink",
)
_TWOSTEP_MARKERS = ("o", "D", "v", "P", "X", "h", "<", ">")
#: Planning times spanning more than this ratio are drawn on a log axis.
LOG_RATIO = 50.0
DPI = 130


@dataclass(frozen=True)
class SeriesStyle:
    color: str
    marker: str
    method: str


def series_styles(report: Report) -> dict[str, SeriesStyle]:
    """One fixed colour and marker per series, the same in every figure of a report."""
    methods = dict(
        zip(report.runs["series"], report.runs["method"], strict=True)
    )  # series -> method
    styles: dict[str, SeriesStyle] = {}
    twostep_index = 0
    ma_shades = ("tab:red", "darkred", "salmon", "firebrick")
    sa_shades = ("0.2", "0.45", "0.6", "0.35")
    ma_index = sa_index = 0
    for name in report.series:
        method = str(methods.get(name, ""))
        if method == "sa":
            styles[name] = SeriesStyle(sa_shades[sa_index % len(sa_shades)], "s", method)
            sa_index += 1
        elif method == "ma":
            styles[name] = SeriesStyle(ma_shades[ma_index % len(ma_shades)], "^", method)
            ma_index += 1
        else:
            styles[name] = SeriesStyle(
                _TWOSTEP_COLORS[twostep_index % len(_TWOSTEP_COLORS)],
                _TWOSTEP_MARKERS[twostep_index % len(_TWOSTEP_MARKERS)],
                method,
            )
            twostep_index += 1
    return styles


def _new_figure(width: float, height: float) -> Figure:
    figure = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _use_log(values: Sequence[float]) -> bool:
    positive = [v for v in values if v > 0 and not math.isnan(v)]
    return len(positive) >= 2 and max(positive) / min(positive) > LOG_RATIO


def _failed_label(n_failed: int, n_timeout: int) -> str:
    parts = []
    if n_failed:
        parts.append(f"{n_failed} failed")
    if n_timeout:
        parts.append(f"{n_timeout} timed out")
    return ", ".join(parts)


def _draw_series(
    ax: Axes,
    rows: pd.DataFrame,
    mean_col: str,
    std_col: str,
    style: SeriesStyle,
    label: str,
    annotate_failures: bool,
    domain_tasks: int = 0,
    max_agents: int = 0,
) -> None:
    rows = rows.sort_values("agents")
    x = [int(n) for n in rows["agents"]]
    mean = [float(v) for v in rows[mean_col]]
    std = [float(v) for v in rows[std_col]]
    has = [not math.isnan(m) for m in mean]
    xs = [n for n, ok in zip(x, has, strict=True) if ok]
    ms = [m for m, ok in zip(mean, has, strict=True) if ok]
    ss = [0.0 if math.isnan(s) else s for s, ok in zip(std, has, strict=True) if ok]
    if style.method == "sa" and xs:
        ax.axhline(ms[0], color=style.color, linestyle="--", linewidth=1.1, alpha=0.7)
    if xs:
        if len(xs) == 1 or style.method == "sa":
            ax.plot(
                xs,
                ms,
                color=style.color,
                marker=style.marker,
                markersize=8 if style.method == "sa" else 7,
                ls="none",
                label=label,
                zorder=4 if style.method == "sa" else 3,  # SA stays visible under N = 1 points
            )
            if any(ss):
                ax.errorbar(xs, ms, yerr=ss, color=style.color, capsize=4, linestyle="none")
        else:
            ax.plot(
                xs, ms, color=style.color, marker=style.marker, markersize=6, lw=1.8, label=label
            )
            if any(ss):
                low = [m - s for m, s in zip(ms, ss, strict=True)]
                high = [m + s for m, s in zip(ms, ss, strict=True)]
                ax.fill_between(xs, low, high, color=style.color, alpha=0.18, linewidth=0)
    if not annotate_failures:
        return
    for row in rows.itertuples(index=False):
        value = float(getattr(row, mean_col))
        if domain_tasks and 0 < int(row.n_tasks) < domain_tasks and not math.isnan(value):
            ax.annotate(
                f"{int(row.n_tasks)} tasks",
                xy=(int(row.agents), value),
                xytext=(0, 7),
                textcoords="offset points",
                ha="center",
                fontsize=7,
                color=style.color,
            )
        text = _failed_label(int(row.n_failed), int(row.n_timeout))
        if not text:
            continue
        if math.isnan(value):
            ax.annotate(
                f"{label} N={int(row.agents)}: all {text}",
                xy=(int(row.agents), 0.03),
                xycoords=("data", "axes fraction"),
                ha="right" if int(row.agents) == max_agents else "center",
                fontsize=7,
                color=style.color,
            )
        else:
            ax.annotate(
                text,
                xy=(int(row.agents), value),
                xytext=(0, -12),
                textcoords="offset points",
                ha="center",
                fontsize=7,
                color=style.color,
            )


def _finish_axis(ax: Axes, agent_counts: Sequence[int], ylabel: str, log: bool) -> None:
    ax.set_xticks(list(agent_counts))
    ax.set_xlim(min(agent_counts) - 0.35, max(agent_counts) + 0.35)
    ax.set_xlabel("Number of agents N")
    if log:
        ax.set_yscale("log")
        ylabel = ylabel.replace(")", ", log scale)")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3, which="major")
    if log:
        ax.grid(True, alpha=0.08, which="minor")


def _draw_domain_axis(
    ax: Axes, report: Report, domain: str, metric: str, styles: dict[str, SeriesStyle]
) -> None:
    cells = report.summary[report.summary["domain"] == domain]
    domain_tasks = int(report.runs[report.runs["domain"] == domain]["task"].nunique())
    for name in report.series:
        rows = cells[cells["series"] == name]
        if rows.empty:
            continue
        _draw_series(
            ax,
            rows,
            f"{metric}_mean",
            f"{metric}_std",
            styles[name],
            legend_label(report, name),
            annotate_failures=True,
            domain_tasks=domain_tasks,
            max_agents=max(report.agent_counts),
        )
    log = metric == "planning_time_s" and _use_log(list(cells[f"{metric}_mean"]))
    _finish_axis(ax, report.agent_counts, METRIC_LABELS[metric], log)


def _draw_normalised_axis(
    ax: Axes, report: Report, metric: str, styles: dict[str, SeriesStyle]
) -> None:
    cross = report.cross_domain[report.cross_domain["metric"] == metric]
    for name in report.series:
        rows = cross[cross["series"] == name]
        if rows.empty:
            continue
        _draw_series(
            ax,
            rows,
            "normalised_mean",
            "normalised_std",
            styles[name],
            legend_label(report, name),
            annotate_failures=False,
        )
    label = METRIC_LABELS[metric].split(" (")[0]
    _finish_axis(ax, report.agent_counts, f"{label} (normalised, 0-1)", log=False)
    ax.set_ylim(-0.05, 1.05)


def legend_label(report: Report, series: str) -> str:
    """The series label, marked when it covers fewer tasks than its domains somewhere."""
    summary = report.summary
    cells = summary[summary["series"] == series]
    domain_tasks = report.runs.groupby("domain")["task"].nunique()
    fewer = any(
        int(row.n_tasks) < int(domain_tasks.get(row.domain, 0))
        for row in cells.itertuples(index=False)
    )
    return f"{series} (subset of tasks)" if fewer else series


def _legend(figure: Figure, axes: Sequence[Axes], report: Report) -> None:
    found: dict[str, Any] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            found.setdefault(label, handle)
    if not found:
        return
    order = [legend_label(report, name) for name in report.series]
    labels = [label for label in order if label in found]
    labels += [label for label in found if label not in labels]
    handles = [found[label] for label in labels]
    if "sa" in set(report.runs["method"]):
        handles.append(Line2D([], [], color="0.4", linestyle="--"))
        labels.append("SA (N = 1) as reference line")
    figure.legend(
        handles,
        labels,
        loc="outside lower center",
        ncol=len(labels) if len(labels) <= 5 else math.ceil(len(labels) / 2),
        frameon=False,
        fontsize=9,
    )


def _domain_title(report: Report, domain: str) -> str:
    tasks = report.runs[report.runs["domain"] == domain]["task"].nunique()
    return f"{domain} ({tasks} task{'s' if tasks != 1 else ''})"


BAND_NOTE = "mean over seeds; band / error bar = ±1 std over seeds (none with 1 seed)"


def _prefix(label: str) -> str:
    return f"[{label}] " if label else ""


def _suptitle(figure: Figure, text: str, fontsize: float = 11) -> None:
    """A figure title wrapped to the figure's width (long experiment names included)."""
    width_chars = int(figure.get_figwidth() * 72 / (fontsize * 0.55))
    lines = [textwrap.fill(line, width_chars) for line in text.splitlines()]
    figure.suptitle("\n".join(lines), fontsize=fontsize)


def plot_domain(report: Report, domain: str, path: Path, label: str = "") -> Path:
    """Execution length and planning time against N for one domain."""
    styles = series_styles(report)
    figure = _new_figure(11, 4.6)
    axes = figure.subplots(1, 2)
    for ax, metric in zip(axes, REPORT_METRICS, strict=True):
        _draw_domain_axis(ax, report, domain, metric, styles)
        ax.set_title(METRIC_LABELS[metric].split(" (")[0], fontsize=11)
    _suptitle(figure, f"{_prefix(label)}{_domain_title(report, domain)}\n{BAND_NOTE}")
    _legend(figure, axes, report)
    figure.savefig(path)
    return path


def plot_normalised(report: Report, path: Path, label: str = "") -> Path:
    """The cross-domain panel: min-max normalised per-domain averages, averaged."""
    styles = series_styles(report)
    figure = _new_figure(11, 4.6)
    axes = figure.subplots(1, 2)
    for ax, metric in zip(axes, REPORT_METRICS, strict=True):
        _draw_normalised_axis(ax, report, metric, styles)
        ax.set_title(METRIC_LABELS[metric].split(" (")[0], fontsize=11)
    _suptitle(
        figure,
        f"{_prefix(label)}All domains: per-domain averages min-max normalised to 0-1, "
        f"then averaged across domains\n{BAND_NOTE}",
    )
    _legend(figure, axes, report)
    figure.savefig(path)
    return path


def plot_overview(report: Report, path: Path, label: str = "") -> Path:
    """Fig. 3 layout: one column per domain plus the normalised column; two rows."""
    styles = series_styles(report)
    domains = report.domains
    columns = len(domains) + 1
    figure = _new_figure(3.3 * columns + 0.5, 7.4)
    axes = figure.subplots(2, columns, squeeze=False)
    for column, domain in enumerate(domains):
        for row, metric in enumerate(REPORT_METRICS):
            _draw_domain_axis(axes[row][column], report, domain, metric, styles)
        axes[0][column].set_title(_domain_title(report, domain), fontsize=11)
    for row, metric in enumerate(REPORT_METRICS):
        _draw_normalised_axis(axes[row][-1], report, metric, styles)
    axes[0][-1].set_title("All domains (normalised)", fontsize=11)
    for ax in axes[0]:
        ax.set_xlabel("")
    _suptitle(figure, f"{_prefix(label)}Execution length and planning time against N\n{BAND_NOTE}")
    _legend(figure, [ax for row_axes in axes for ax in row_axes], report)
    figure.savefig(path)
    return path


def plot_report(report: Report, out_dir: Path, label: str = "") -> list[Path]:
    """Every figure of a report into ``out_dir``; returns the paths written.

    ``label`` (e.g. the experiment name) prefixes every figure title.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    if not report.has_results:
        return []
    paths = [plot_overview(report, out_dir / "fig3_overview.png", label)]
    if len(report.cross_domain):
        paths.append(plot_normalised(report, out_dir / "fig3_normalised.png", label))
    for domain in report.domains:
        paths.append(plot_domain(report, domain, out_dir / f"fig3_{_slug(domain)}.png", label))
    return paths


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)
