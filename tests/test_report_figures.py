"""Report figures (twostep/report/plots.py, style.py, compared.py), read back from matplotlib.

Run tables are made here by hand and every expected number is worked out from them; what a
figure shows is read from the drawn matplotlib objects (lines, bars, legend texts, axis
limits, font sizes) or from the written files, never from the functions that drew them.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from matplotlib.axes import Axes
from matplotlib.container import BarContainer
from matplotlib.figure import Figure
from matplotlib.image import imread
from matplotlib.lines import Line2D
from matplotlib.text import Text

from flows.report_cli import main
from twostep.report import build_report, format_console, load_runs_from_csv, write_report
from twostep.report.plots import domain_figure, normalised_figure, overview_figure
from twostep.report.table2 import read_task_titles
from twostep.tasks.benchmark import DEFAULT_DATA_ROOT

#: Length of each task for SA; MA and TwoStep take fixed fractions of it.
TASK_LENGTH = {1: 10.0, 2: 20.0, 3: 30.0, 4: 80.0}


def run(
    domain: str,
    task: int,
    method: str,
    agents: int,
    length: float | None,
    time: float = 1.0,
    status: str = "success",
    seed: int = 0,
    decomposer: str = "goal-split",
    **extra: Any,
) -> dict[str, Any]:
    return {
        "domain": domain, "task": task, "method": method, "agents": agents, "seed": seed,
        "decomposer": decomposer if method == "twostep" else "", "status": status,
        "exec_length": length, "planning_time_s": time, **extra,
    }  # fmt: skip


def termes_like(ma4_timeouts: tuple[int, ...] = (4,)) -> pd.DataFrame:
    """SA; MA at N = 2, 3, 4 (0.5 of SA's length); TwoStep at N = 2, 3, 4 (0.75). MA at
    N = 4 times out on ``ma4_timeouts`` (task 4 is by far the longest)."""
    rows = []
    for task, length in TASK_LENGTH.items():
        rows.append(run("termes", task, "sa", 1, length, time=1.0))
        for agents in (2, 3, 4):
            if agents == 4 and task in ma4_timeouts:
                rows.append(run("termes", task, "ma", 4, None, time=None, status="timeout"))
            else:
                rows.append(run("termes", task, "ma", agents, 0.5 * length, time=2.0 * agents))
            rows.append(run("termes", task, "twostep", agents, 0.75 * length, time=1.5))
    return pd.DataFrame.from_records(rows)


def legend_of(figure: Figure) -> dict[str, Any]:
    """Legend text -> its handle, for the figure's one legend."""
    (legend,) = figure.legends
    return {
        text.get_text(): handle
        for text, handle in zip(legend.texts, legend.legend_handles, strict=True)
    }


def markers(ax: Axes, color: str) -> list[Line2D]:
    """Single-point marker lines of ``color`` on ``ax`` (one per drawn cell)."""
    return [
        line
        for line in ax.get_lines()
        if line.get_color() == color and line.get_marker() not in ("None", "", None)
        and len(line.get_xdata()) == 1
    ]  # fmt: skip


def texts_of(figure: Figure) -> list[Text]:
    figure.canvas.draw()  # tick labels exist only once drawn
    return [
        t for t in figure.findobj(Text) if t.get_visible() and t.get_text().strip()
    ]  # fmt: skip


# ------------------------------------------------------------------ lost runs


def test_a_timeout_never_improves_a_mean() -> None:
    report = build_report(termes_like())
    coverage = report.coverage.set_index("domain").loc["termes"]
    assert coverage["compared_tasks"] == "1,2,3" and coverage["left_out_tasks"] == "4"
    # the summary keeps every successful run: MA at N = 4 "improves" from 35 to 10 steps
    summary = report.summary.set_index(["series", "agents"])
    assert summary.loc[("MA", 3), "exec_length_mean"] == pytest.approx(0.5 * 140 / 4)
    assert summary.loc[("MA", 4), "exec_length_mean"] == pytest.approx(0.5 * 60 / 3)
    # the figure compares every series on tasks 1-3: MA is flat at 0.5 * 20 = 10 steps
    figure = domain_figure(report, "termes")
    length_axis = figure.axes[0]
    ma_color = legend_of(figure)["MA (n = 1; 1 timeout)"].get_color()
    drawn = {round(m.get_xdata()[0]): m for m in markers(length_axis, ma_color)}
    assert {n: float(m.get_ydata()[0]) for n, m in drawn.items()} == {2: 10.0, 3: 10.0, 4: 10.0}
    assert drawn[4].get_markerfacecolor() == "white"  # hollow: the cell lost a run
    assert drawn[3].get_markerfacecolor() != "white"
    sa_color = legend_of(figure)["SA (n = 1)"].get_color()
    assert [float(m.get_ydata()[0]) for m in markers(length_axis, sa_color)] == [20.0]
    assert "3 of 4 tasks" in figure.get_suptitle()
    assert any("left out: task 4" in note for note in report.notes)
    # the normalised change compares the same tasks: TwoStep 15 vs MA 10 at every N
    changes = report.changes.set_index(["baseline", "metric", "agents"])
    assert changes.loc[("MA", "exec_length", 4), "change_pct_raw"] == pytest.approx(50.0)


def test_a_cell_that_solved_nothing_is_marked_not_dropped() -> None:
    report = build_report(termes_like(ma4_timeouts=(1, 2, 3, 4)))
    coverage = report.coverage.set_index("domain").loc["termes"]
    assert coverage["n_compared"] == 4  # the lost cell does not empty the comparison
    assert "MA N=4 solved none" in coverage["lost_cells"]
    figure = domain_figure(report, "termes")
    legend = legend_of(figure)
    assert "MA (n = 1; 4 timeouts)" in legend and "x: no task solved" in legend
    ma_color = legend["MA (n = 1; 4 timeouts)"].get_color()
    crosses = [m for m in markers(figure.axes[0], ma_color) if m.get_marker() == "x"]
    assert [round(c.get_xdata()[0]) for c in crosses] == [4]


# ------------------------------------------------------------------ one style per series


def two_runs() -> tuple[pd.DataFrame, pd.DataFrame]:
    """Two sweeps with different series: only MA and TwoStep (goal-split) in both."""
    first = [run("A", t, m, n, 10.0 * t) for t in (1, 2) for m, n in (("sa", 1), ("ma", 2))]
    first += [run("A", t, "twostep", n, 8.0 * t) for t in (1, 2) for n in (2, 3)]
    second = [run("B", t, "ma", n, 9.0 * t) for t in (1, 2) for n in (2, 3)]
    second += [
        run("B", t, "twostep", n, 7.0 * t, decomposer=d)
        for t in (1, 2)
        for n in (2, 3)
        for d in ("goal-split", "expert", "llm", "a-new-one")
    ]
    return pd.DataFrame(first), pd.DataFrame(second)


def styles_drawn(figure: Figure) -> dict[str, tuple[str, str]]:
    """Series name (its legend label without n) -> (colour, marker) of its legend handle."""
    return {
        label.split(" (n = ")[0]: (handle.get_color(), handle.get_marker())
        for label, handle in legend_of(figure).items()
        if label.startswith(("SA", "MA", "TwoStep"))
    }


def test_a_series_has_one_colour_and_marker_in_every_report() -> None:
    first, second = two_runs()
    drawn_first = styles_drawn(domain_figure(build_report(first), "A"))
    drawn_second = styles_drawn(domain_figure(build_report(second), "B"))
    shared = set(drawn_first) & set(drawn_second)
    assert shared == {"MA", "TwoStep (goal-split)"}
    for label in shared:
        assert drawn_first[label] == drawn_second[label], label
    # every series of a report is told apart by its colour and by its marker
    for drawn in (drawn_first, drawn_second):
        assert len({color for color, _ in drawn.values()}) == len(drawn)
        assert len({marker for _, marker in drawn.values()}) == len(drawn)
    # a third report holding both sweeps draws them the same way in all its figures
    both = build_report(pd.concat([first, second]))
    for figure in (overview_figure(both), normalised_figure(both), domain_figure(both, "B")):
        drawn = styles_drawn(figure)
        assert drawn["MA"] == drawn_first["MA"]
        assert drawn["TwoStep (expert)"] == drawn_second["TwoStep (expert)"]
    # MA against TwoStep is not red against green: neither colour is a pure red or green
    for label in ("MA", "TwoStep (goal-split)"):
        red, green, blue = (int(drawn_first[label][0][i : i + 2], 16) for i in (1, 3, 5))
        assert not (red > 150 and green < 60 and blue < 60), label
        assert not (green > 150 and red < 60 and blue < 60), label


def test_variants_of_a_series_share_its_colour_and_differ_in_line_style() -> None:
    rows = [
        run("A", t, "twostep", n, 8.0 * t + (1 if limit == "20" else 0))
        | {"param.planner.time_limit_s": limit}
        for t in (1, 2)
        for n in (2, 3)
        for limit in ("10", "20")
    ]
    figure = domain_figure(build_report(pd.DataFrame(rows)), "A")
    handles = {
        k.split(" (n = ")[0]: v for k, v in legend_of(figure).items() if k.startswith("TwoStep")
    }
    assert len(handles) == 2
    ten, twenty = (
        handles[f"TwoStep (goal-split) [planner.time_limit_s={v}]"] for v in ("10", "20")
    )
    assert ten.get_color() == twenty.get_color()
    assert ten.get_linestyle() != twenty.get_linestyle()


# ------------------------------------------------------------------ print sizes and files


def test_figures_are_sized_for_print_with_fonts_of_8_pt_or_more() -> None:
    report = build_report(pd.concat([termes_like(), termes_like().assign(domain="other")]))
    for figure, width in (
        (domain_figure(report, "termes"), 3.5),
        (normalised_figure(report), 3.5),
        (overview_figure(report), 7.16),
    ):
        assert figure.get_figwidth() == pytest.approx(width)
        sizes = [t.get_fontsize() for t in texts_of(figure)]
        assert len(sizes) > 20
        assert min(sizes) >= 8.0
        # nothing drawn outside the figure (a legend or title cut off at print size)
        renderer = figure.canvas.get_renderer()  # type: ignore[attr-defined]
        box = figure.bbox
        for text in texts_of(figure):
            extent = text.get_window_extent(renderer)
            assert extent.x0 >= box.x0 - 1 and extent.x1 <= box.x1 + 1, text.get_text()


def test_lengths_and_linear_times_start_at_zero() -> None:
    figure = domain_figure(build_report(termes_like()), "termes")
    length_axis, time_axis = figure.axes[:2]
    assert length_axis.get_ylim()[0] == 0.0
    assert time_axis.get_ylim()[0] == 0.0
    assert length_axis.get_ylabel() == "Execution length (steps)"


def test_one_n_per_series_draws_bars() -> None:
    rows = [run("A", t, "sa", 1, 10.0 * t, time=4.0) for t in (1, 2)]
    rows += [run("A", t, "ma", 2, 6.0 * t, time=3.0) for t in (1, 2)]
    rows += [run("A", t, "twostep", 2, 5.0 * t, time=1.0) for t in (1, 2)]
    figure = domain_figure(build_report(pd.DataFrame(rows)), "A")
    length_axis = figure.axes[0]
    bars = [c for c in length_axis.containers if isinstance(c, BarContainer)]
    heights = sorted(round(p.get_height(), 6) for c in bars for p in c.patches)
    assert heights == [7.5, 9.0, 15.0]  # TwoStep, MA, SA: means over tasks 1 and 2
    assert not [line for line in length_axis.get_lines() if len(line.get_xdata()) > 1]
    # with two N for a series: lines, no bars
    rows += [run("A", t, "twostep", 3, 4.0 * t) for t in (1, 2)]
    lines_figure = domain_figure(build_report(pd.DataFrame(rows)), "A")
    assert not lines_figure.axes[0].containers
    assert [line for line in lines_figure.axes[0].get_lines() if len(line.get_xdata()) == 2]


def test_every_figure_is_written_as_png_pdf_and_svg(tmp_path: Path) -> None:
    report = build_report(pd.concat([termes_like(), termes_like().assign(domain="other")]))
    written = write_report(report, tmp_path, "t", "s")
    pngs = [p for p in written if p.suffix == ".png"]
    assert {p.stem for p in pngs} == {
        "fig3_overview",
        "fig3_normalised",
        "fig3_termes",
        "fig3_other",
    }
    for png in pngs:
        pdf, svg = png.with_suffix(".pdf"), png.with_suffix(".svg")
        assert pdf in written and svg in written
        data = pdf.read_bytes()
        assert data.startswith(b"%PDF") and b"/FontFile2" in data  # embedded TrueType
        assert b"/Type3" not in data  # publishers' checkers refuse Type 3 fonts
        root = ElementTree.parse(svg).getroot()
        assert root.tag.endswith("svg")
        texts = {"".join(t.itertext()) for t in root.iter() if t.tag.endswith("text")}
        assert "4" in texts  # text stays text (an x tick label), not glyph outlines
    svg_texts = ElementTree.parse(tmp_path / "fig3_termes.svg").getroot().iter()
    assert "Planning time (s)" in {"".join(t.itertext()) for t in svg_texts}
    width_px = imread(tmp_path / "fig3_termes.png").shape[1]
    assert width_px == 3.5 * 300
    markdown = (tmp_path / "report.md").read_text()
    assert "![fig3_termes](fig3_termes.png)" in markdown
    assert "| termes | exec_length | 3 of 4 | 4 |" in markdown
    # the same runs give the same files (no dates or random ids inside)
    again = tmp_path / "again"
    write_report(report, again, "t", "s")
    for name in ("fig3_termes.svg", "fig3_termes.pdf"):
        assert (again / name).read_bytes() == (tmp_path / name).read_bytes()


# ------------------------------------------------------------------ console and kitchen


def test_console_gives_the_normalised_and_the_raw_change() -> None:
    rows = []
    values = {"A": (10.0, 8.0, 6.0), "B": (100.0, 50.0, 75.0)}  # SA, MA(N=2), TwoStep(N=2)
    for domain, (sa, ma, two) in values.items():
        for method, agents, value in (("sa", 1, sa), ("ma", 2, ma), ("twostep", 2, two)):
            rows.append(run(domain, 1, method, agents, value, time=value))
    text = format_console(build_report(pd.DataFrame(rows)))
    # normalised: A: SA 1, MA .5, TS 0; B: SA 1, MA 0, TS .5 -> SA 1, MA .25, TS .25
    # raw: mean of (6 - 10) / 10 and (75 - 100) / 100; of (6 - 8) / 8 and (75 - 50) / 50
    line = "TwoStep (goal-split) vs SA, execution length, N=2: -75.0 % normalised / -32.5 % raw"
    assert line + " | paper -7.7 %" in text
    assert "vs MA, execution length, N=2: +0.0 % normalised / +12.5 % raw" in text


def kitchen_runs() -> pd.DataFrame:
    rows = []
    for task in (1, 2, 3, 4):
        for seed in (0, 1):
            for method, agents, embodied in (("sa", 1, 50), ("ma", 2, 40), ("twostep", 2, 30)):
                rows.append(
                    run("alfworld", task, method, agents, 12.0, seed=seed, time=2.0,
                        embodied_length=embodied + task + seed)
                )  # fmt: skip
    return pd.DataFrame.from_records(rows)


def test_kitchen_figures_draw_the_embodied_length() -> None:
    report = build_report(kitchen_runs())
    figure = domain_figure(report, "alfworld")
    length_axis = figure.axes[0]
    assert length_axis.get_ylabel() == "Embodied length (steps)"
    bars = [p for c in length_axis.containers if isinstance(c, BarContainer) for p in c.patches]
    # per seed: mean over tasks of embodied + task + seed = embodied + 2.5 + seed; then
    # the mean over seeds 0 and 1, and their sample std sqrt(0.5)
    assert sorted(p.get_height() for p in bars) == [pytest.approx(v + 3.0) for v in (30, 40, 50)]
    spans = [
        abs(segment[1][1] - segment[0][1]) / 2
        for collection in length_axis.collections
        for segment in collection.get_segments()  # type: ignore[attr-defined]
    ]
    assert spans == [pytest.approx(math.sqrt(0.5))] * 3


def test_table_two_is_headed_by_the_task_descriptions(tmp_path: Path) -> None:
    kitchen = tmp_path / "data" / "alfworld"
    kitchen.mkdir(parents=True)
    (kitchen / "titles.yaml").write_text(
        "1: Put an apple on the table\n2: Clear the table\n3: Fill the fridge\n4: Clear the sink\n"
    )
    titles = read_task_titles(kitchen)
    assert titles == {1: "Put an apple on the table", 2: "Clear the table",
                      3: "Fill the fridge", 4: "Clear the sink"}  # fmt: skip
    text = format_console(build_report(kitchen_runs(), titles))
    assert (
        "| tasks |  | Put an apple on the table | Clear the table | Fill the fridge | "
        "Clear the sink |  |" in text
    )
    assert read_task_titles(tmp_path) == {}  # no file: no titles
    # the kitchen's own titles.yaml names its tasks by file (p01: ...): read as well
    shipped = read_task_titles(DEFAULT_DATA_ROOT / "alfworld")
    assert sorted(shipped) == [1, 2, 3, 4] and shipped[3].startswith("Put the apple")
    # the command finds them under --data-root and writes them into table2.csv
    runs_csv = tmp_path / "runs.csv"
    kitchen_runs().to_csv(runs_csv, index=False)
    out = tmp_path / "report"
    code = main(
        ["--runs-csv", str(runs_csv), "--data-root", str(tmp_path / "data"), "--out", str(out)]
    )
    assert code == 0
    table = pd.read_csv(out / "table2.csv", keep_default_na=False)
    assert (
        table[(table["series"] == "SA") & (table["task"] == "3")]["title"].item()
        == "Fill the fridge"
    )


def test_a_reports_runs_csv_redraws_the_same_report(tmp_path: Path) -> None:
    report = build_report(termes_like())
    write_report(report, tmp_path, "t", "s")
    again = build_report(load_runs_from_csv(tmp_path / "runs.csv"))
    pd.testing.assert_frame_equal(again.summary, report.summary)
    pd.testing.assert_frame_equal(again.compared, report.compared)
    assert main(["--runs-csv", str(tmp_path / "runs.csv"), "--out", str(tmp_path / "r")]) == 0
    assert main(["--runs-csv", str(tmp_path / "absent.csv")]) == 1


# ------------------------------------------------------------------ seeds, n, issue 37


def three_seed_sweep() -> pd.DataFrame:
    """Two domains, tasks 1-2, seeds 0-2, as a sweep over ``agents=2,3`` logs them: SA
    (launched at N = 2 and 3: each job twice), MA and TwoStep with the LLM at N = 2, 3.
    SA and MA are deterministic: every seed repeats one run (the same numbers); SA times
    out on B's task 2 in every seed. The LLM's lengths differ by seed (+1 per seed)."""
    rows = []
    for domain, base in (("A", 10.0), ("B", 20.0)):
        for task in (1, 2):
            for seed in (0, 1, 2):
                for grid in (2, 3):
                    if (domain, task) == ("B", 2):
                        rows.append(run(domain, task, "sa", 1, None, time=None, seed=seed,
                                        status="timeout", agents_param=grid))  # fmt: skip
                    else:
                        rows.append(run(domain, task, "sa", 1, base * task, time=2.0,
                                        seed=seed, agents_param=grid))  # fmt: skip
                    rows.append(run(domain, task, "ma", grid, 0.8 * base * task, seed=seed))
                    rows.append(run(domain, task, "twostep", grid, 0.5 * base * task + seed,
                                    seed=seed, decomposer="llm"))  # fmt: skip
    return pd.DataFrame.from_records(rows)


def test_seeds_mean_what_they_say_in_tables_and_legends(tmp_path: Path) -> None:
    """Issue 37: a deterministic method is one distinct run (no ±, n = 1), a method whose
    runs differ by seed is a mean ± std over its n seeds, n in every table row and legend
    label; SA's grid duplicates count once per (task, seed): 3 timeouts, not 6."""
    report = build_report(three_seed_sweep())
    summary = report.summary.set_index(["domain", "series", "agents"])
    # SA on A: one distinct run per task, (10 + 20) / 2; no spread, n = 1
    sa = summary.loc[("A", "SA", 1)]
    assert sa["exec_length_mean"] == 15.0 and sa["exec_length_n_seeds"] == 1
    assert math.isnan(sa["exec_length_std"])
    assert sa["n_runs"] == 6  # 2 tasks x 3 seeds: the grid's N=2 and N=3 are one run
    assert summary.loc[("B", "SA", 1), "n_timeout"] == 3
    # the LLM on A at N = 2: per seed (5 + s + 10 + s) / 2 = 7.5 + s over s = 0, 1, 2
    llm = summary.loc[("A", "TwoStep (llm)", 2)]
    assert llm["exec_length_mean"] == 8.5 and llm["exec_length_n_seeds"] == 3
    assert llm["exec_length_std"] == pytest.approx(1.0)  # stdev(7.5, 8.5, 9.5)

    written = write_report(report, tmp_path, "t", "s")
    markdown = (tmp_path / "report.md").read_text()
    results = markdown.split("## Results per domain")[1].split("## Change")[0]
    rows = [line for line in results.splitlines() if line.startswith("| ") and "---" not in line]
    body = [row for row in rows if not row.startswith("| series")]
    assert len(body) == 2 * 5  # per domain: SA, MA at 2 and 3, TwoStep (llm) at 2 and 3
    for row in body:
        n = row.rstrip(" |").rsplit("| ", 1)[1]
        if row.startswith(("| SA ", "| MA ")):
            assert n == "1 distinct run" and " ± " not in row, row
        else:
            assert n == "3 seeds" and " ± " in row, row
    assert {p.name for p in written} >= {"fig3_overview.png", "fig3_normalised.png"}

    legend = legend_of(domain_figure(report, "B"))
    assert "SA (n = 1; 3 timeouts)" in legend  # per task and seed, not per grid duplicate
    assert "MA (n = 1)" in legend and "TwoStep (llm) (n = 3)" in legend
    overview = overview_figure(report)
    labels = set(legend_of(overview))
    assert {"SA (n = 1; 3 timeouts)", "MA (n = 1)", "TwoStep (llm) (n = 3)"} <= labels


def test_normalised_panels_say_what_they_show_and_no_marker_hides_another() -> None:
    """Issue 37: the overview's normalised column sat under row labels with units; a mean
    over fewer domains looked like the others; the expert's diamond hid MA's triangle."""
    rows = [
        *(run(d, t, "sa", 1, 10.0 * t + i, time=1.0 + i) for i, d in enumerate("ABC")
          for t in (1, 2)),
        *(run(d, t, "ma", 2, 8.0 * t + i, time=3.0) for i, d in enumerate("ABC") for t in (1, 2)),
        # the expert's subgoals exist for A and B only, at the same N (and length) as MA
        *(run(d, t, "twostep", 2, 8.0 * t + i, time=3.0, decomposer="expert")
          for i, d in enumerate("AB") for t in (1, 2)),
        *(run(d, t, "twostep", n, 6.0 * t, time=2.0) for d in "ABC" for t in (1, 2)
          for n in (2, 3)),
    ]  # fmt: skip
    report = build_report(pd.DataFrame.from_records(rows))
    overview = overview_figure(report)
    normalised_axes = [ax for ax in overview.axes if ax.get_title().startswith("All domains")]
    (top,) = normalised_axes
    column = [ax for ax in overview.axes if ax.get_position().x0 == top.get_position().x0]
    labels = sorted(ax.get_ylabel() for ax in column)
    assert labels == ["Length, normalised 0-1", "Planning time, normalised 0-1"]
    assert all(ax.yaxis.get_label_position() == "right" for ax in column)
    # the expert's normalised point averages 2 of the 3 domains: half-filled, "2/3" beside it
    expert_color = legend_of(overview)["TwoStep (expert) (n = 1)"].get_color()
    (expert,) = markers(top, expert_color)
    assert expert.get_fillstyle() == "left"
    assert "2/3" in [t.get_text() for t in top.texts]
    assert "half-filled, k/3: normalised over fewer domains" in legend_of(overview)
    # in domain A, MA and the expert have the same mean at N = 2: set apart, both visible
    figure = domain_figure(report, "A")
    legend = legend_of(figure)
    ma = markers(figure.axes[0], legend["MA (n = 1)"].get_color())
    (expert_a,) = markers(figure.axes[0], legend["TwoStep (expert) (n = 1)"].get_color())
    (ma_2,) = [m for m in ma if round(m.get_xdata()[0]) == 2]
    assert ma_2.get_ydata()[0] == expert_a.get_ydata()[0]
    gap = abs(ma_2.get_xdata()[0] - expert_a.get_xdata()[0])
    assert gap >= 0.19  # in N: about a marker's width (4.5 pt) in a one-column panel
