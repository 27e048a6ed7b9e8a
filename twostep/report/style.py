"""How every report draws: one colour and marker per series, print sizes and fonts.

The one owner of a figure's look. Colours come from the Okabe-Ito palette (safe for the
common colour-vision deficiencies; the main pair, MA against TwoStep, is vermillion against
blue, never red against green) and are keyed by the series' *family* — its method and
decomposer, e.g. ``MA`` or ``TwoStep (goal-split)`` — so a series has the same colour and
marker in every report, whatever other series a report holds. Families not listed here get
a colour from Paul Tol's muted palette chosen by a stable hash of their name. Variants of
one family (two planner time limits, two models) share its colour and marker and differ by
line style (lines) or hatch (bars), in sorted order of their variant values.

Sizes are print sizes: a single-column figure is 3.5 in wide, the overview spans two
columns (7.16 in, an IEEE page's text width), and no text is smaller than 8 pt at those
widths. PDFs embed TrueType fonts (no Type 3, which publishers' checkers refuse); SVGs keep
text as text.
"""

from __future__ import annotations

import zlib
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

from twostep.report.series import series_label

COLUMN_WIDTH_IN = 3.5
TEXT_WIDTH_IN = 7.16
MIN_FONT_PT = 8.0
TITLE_FONT_PT = 9.0
PNG_DPI = 300
FIGURE_FORMATS: tuple[str, ...] = ("png", "pdf", "svg")

#: matplotlib settings every report figure is built and saved with.
PAPER_RC: dict[str, object] = {
    "font.size": MIN_FONT_PT,
    "axes.titlesize": TITLE_FONT_PT,
    "axes.labelsize": MIN_FONT_PT,
    "xtick.labelsize": MIN_FONT_PT,
    "ytick.labelsize": MIN_FONT_PT,
    "legend.fontsize": MIN_FONT_PT,
    "figure.titlesize": TITLE_FONT_PT,
    "axes.linewidth": 0.6,
    "grid.linewidth": 0.4,
    "lines.linewidth": 1.2,
    "lines.markersize": 4.5,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "hatch.linewidth": 0.6,
    "pdf.fonttype": 42,
    "ps.fonttype": 42,
    "svg.fonttype": "none",
    "svg.hashsalt": "twostep-report",  # stable ids: the same figure is the same file
    "savefig.dpi": PNG_DPI,
}

OKABE_ITO: dict[str, str] = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky blue": "#56B4E9",
    "bluish green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish purple": "#CC79A7",
}
GREY = "#999999"  # the grey of the Okabe-Ito set as commonly printed (yellow is too light)

#: Colour and marker per family (method and decomposer).
FAMILY_STYLES: dict[str, tuple[str, str]] = {
    "SA": (OKABE_ITO["black"], "s"),
    "MA": (OKABE_ITO["vermillion"], "^"),
    "TwoStep (goal-split)": (OKABE_ITO["blue"], "o"),
    "TwoStep (expert)": (OKABE_ITO["bluish green"], "D"),
    "TwoStep (llm)": (OKABE_ITO["reddish purple"], "v"),
    "TwoStep (plan-deal)": (OKABE_ITO["orange"], "P"),
    "TwoStep (plan-split)": (OKABE_ITO["sky blue"], "X"),
    "TwoStep (portfolio)": (GREY, "h"),
}
#: Paul Tol's muted palette, for families without a fixed style.
FALLBACK_COLORS: tuple[str, ...] = (
    "#332288",
    "#117733",
    "#44AA99",
    "#88CCEE",
    "#DDCC77",
    "#CC6677",
    "#AA4499",
    "#882255",
)
FALLBACK_MARKERS: tuple[str, ...] = ("o", "s", "^", "D", "v", "P", "X", "h")
LineStyle = Literal["-", "--", ":", "-.", "none"]
LINE_STYLES: tuple[LineStyle, ...] = ("-", "--", ":", "-.")
BAR_HATCHES: tuple[str, ...] = ("", "..", "xx", "--")


@dataclass(frozen=True)
class SeriesStyle:
    """How one series is drawn; ``variant_rank`` orders the variants of its family."""

    color: str
    marker: str
    method: str
    variant_rank: int = 0

    @property
    def linestyle(self) -> LineStyle:
        return LINE_STYLES[self.variant_rank % len(LINE_STYLES)]

    @property
    def hatch(self) -> str:
        return BAR_HATCHES[self.variant_rank % len(BAR_HATCHES)]


def family_style(family: str) -> tuple[str, str]:
    """Colour and marker of a family: fixed for the known ones, else by a stable hash."""
    if family in FAMILY_STYLES:
        return FAMILY_STYLES[family]
    index = zlib.crc32(family.encode("utf-8"))
    return (
        FALLBACK_COLORS[index % len(FALLBACK_COLORS)],
        FALLBACK_MARKERS[index % len(FALLBACK_MARKERS)],
    )


def series_styles(series: Iterable[tuple[str, str, str, str]]) -> dict[str, SeriesStyle]:
    """Style per series label from (series, method, decomposer, variant) rows."""
    rows = sorted(set(series), key=lambda r: (r[1], r[2], r[3]))
    ranks: dict[str, int] = {}
    styles: dict[str, SeriesStyle] = {}
    for label, method, decomposer, _variant in rows:
        family = series_label(method, decomposer)
        color, marker = family_style(family)
        rank = ranks.get(family, 0)
        ranks[family] = rank + 1
        styles[label] = SeriesStyle(color, marker, method, rank)
    return styles
