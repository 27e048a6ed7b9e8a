"""Writing a :class:`~twostep.report.build.Report`: CSV files, Markdown, console text.

:func:`write_report` puts everything in one directory::

    report.md          the whole report (figures linked, every table, notes, failed runs)
    summary.csv        per domain, series, N: mean/std over seeds, success rate, counts
    compared.csv       the same cells over the tasks every series solved (the figures' means)
    coverage.csv       per domain: the tasks compared, those left out and why
    changes.csv        TwoStep vs SA / MA per N (normalised, as the paper), paper's figures
    planning_time.csv  TwoStep vs MA planning time per domain and N (:mod:`.planning_time`)
    table1.csv         expert vs decomposers on the annotated tasks (+ the paper's rows)
    per_seed.csv       per domain, series, N, seed: the task averages the stds come from
    per_task.csv       per domain, series, N, task: mean/std over seeds
    normalised.csv     per domain cell: min-max normalised mean
    cross_domain.csv   per series, N: normalised mean across domains
    runs.csv           every run read, failed ones included
    fig3_*.png/.pdf/.svg  the figures (:mod:`twostep.report.plots`)
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from twostep.report.model import METRIC_LABELS, METRIC_NAMES, Report
from twostep.report.paper import ANNOTATED_TASKS, TABLE1_AGENTS, TABLE1_DOMAINS
from twostep.report.planning_time import planning_time_view, view_rows
from twostep.report.plots import plot_report
from twostep.report.runs import PARAM_PREFIX
from twostep.report.seeds import distinct_label
from twostep.report.table2 import (
    PAPER_TIME_LIMIT_S,
    TABLE2_AGENTS,
    TABLE2_DOMAIN,
    table_two_rows,
)
from twostep.util.outcome import ReportStatus

FAILED_ROWS_SHOWN = 200


def _is_nan(value: object) -> bool:
    try:
        return value is None or bool(pd.isna(value))
    except (TypeError, ValueError):
        return False


def _digits(metric: str, value: float) -> int:
    if metric in ("exec_length", "embodied_length"):
        return 1
    return 2 if abs(value) < 100 else 1


def format_mean_std(
    mean: object, std: object, n_seeds: object, metric: str, seeded: object = True
) -> str:
    """``12.3 ± 0.4`` over seeds that differ; ``12.3`` for one value (one seed, or one
    distinct run of a deterministic series: the table's n says which); ``n/a``."""
    if _is_nan(mean):
        return "n/a"
    value = float(str(mean))
    digits = _digits(metric, value)
    single = not _is_nan(n_seeds) and int(float(str(n_seeds))) == 1
    if single or not bool(seeded) or _is_nan(std):
        return f"{value:.{digits}f}"
    return f"{value:.{digits}f} ± {float(str(std)):.{digits}f}"


def n_label(n_seeds: object, seeded: object) -> str:
    """The n of a table row: ``1 distinct run`` (deterministic), ``3 seeds``, ``-``."""
    if _is_nan(n_seeds) or int(float(str(n_seeds))) == 0:
        return "-"
    return distinct_label(n_seeds, seeded)


def format_pct(value: object) -> str:
    if _is_nan(value):
        return "n/a"
    return f"{float(str(value)):+.1f} %"


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A GitHub Markdown table; ``|`` in cells is escaped."""

    def cell(value: object) -> str:
        return str(value).replace("|", "\\|").replace("\n", " ")

    lines = [
        "| " + " | ".join(cell(h) for h in headers) + " |",
        "|" + "|".join("---" for _ in headers) + "|",
    ]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


# ------------------------------------------------------------------ sections

FIGURE_CAPTION = (
    "Each point: the average over the tasks every series of the domain solved (a run lost "
    "to a failure or timeout leaves its task out for every series, so it never improves a "
    "mean), for a deterministic series of its one distinct run (n = 1), else the mean over "
    "its n seeds with a shaded band / error bar of ±1 sample std; the legend gives n. "
    "Hollow markers or bars: the series lost runs there (counted in the legend, per task "
    "and seed); x on the axis: it solved no task. Normalised panels: half-filled markers "
    "(with k/n beside them) average fewer domains than the others. Markers of different "
    "series at one N are set a little apart. SA runs at N = 1 only: its dashed line is a "
    "reference. Kitchen domains are measured by their embodied length. Every figure is "
    "also written as PDF and SVG (fonts of 8 pt and more at 3.5 in, the overview at 7.16 in)."
)


def _coverage_section(report: Report) -> str:
    """Which tasks each domain's figures compare, and what was left out."""
    rows = [
        [
            row["domain"],
            row["length_metric"],
            f"{row['n_compared']} of {row['n_tasks']}",
            row["left_out_tasks"] or "-",
            row["lost_cells"] or "-",
        ]
        for row in report.coverage.to_dict("records")
    ]
    headers = ["domain", "length", "tasks compared", "left out", "runs lost"]
    return markdown_table(headers, rows)


def _counts_section(report: Report) -> str:
    c = report.counts
    rows = [
        ["successful", c["success"]],
        ["failed", c["failed"]],
        ["timed out", c["timeout"]],
        ["unfinished (running or interrupted)", c["running"]],
        ["total", c["runs"]],
    ]
    if c["superseded"]:
        rows.append(["superseded by a re-run (not in total)", c["superseded"]])
    text = markdown_table(["runs", "count"], rows)
    not_ok = c["failed"] + c["timeout"]
    if not_ok:
        text += (
            f"\n\n{not_ok} run(s) failed or timed out: they are counted in every table "
            "(columns 'failed' / 'timeout', success rate) and listed at the end, and left "
            "out of the means."
        )
    return text


def counts_line(report: Report) -> str:
    c = report.counts
    return (
        f"{c['runs']} runs: {c['success']} successful, {c['failed']} failed, "
        f"{c['timeout']} timed out" + (f", {c['running']} unfinished" if c["running"] else "")
    )


def _summary_section(report: Report) -> str:
    parts: list[str] = []
    for domain in report.domains:
        cells = report.summary[report.summary["domain"] == domain]
        embodied = report.length_metric(domain) == "embodied_length"
        metrics = ["exec_length", *(["embodied_length"] if embodied else []), "planning_time_s"]
        headers = [
            "series",
            "N",
            *(f"{METRIC_LABELS[m].lower()}" for m in metrics),
            "success",
            "ok / failed / timeout",
            "tasks",
            "tasks/seed",
            "n",
        ]
        rows = []
        for row in cells.to_dict("records"):
            rate = row["success_rate"]
            rows.append(
                [
                    row["series"],
                    row["agents"],
                    *(
                        format_mean_std(
                            row[f"{m}_mean"], row[f"{m}_std"], row[f"{m}_n_seeds"], m, row["seeded"]
                        )
                        for m in metrics
                    ),
                    "n/a" if _is_nan(rate) else f"{float(rate) * 100:.0f} %",
                    f"{row['n_success']} / {row['n_failed']} / {row['n_timeout']}",
                    row["n_tasks"],
                    row["tasks_per_seed"] or "-",
                    n_label(row["exec_length_n_seeds"], row["seeded"]),
                ]
            )
        parts.append(f"### {domain}\n\n" + markdown_table(headers, rows))
    return "\n\n".join(parts)


def _changes_section(report: Report) -> str:
    changes = report.changes
    if changes.empty:
        return (
            "No change can be computed: it needs TwoStep runs with N >= 2 and SA or MA runs "
            "in the same domains."
        )
    rows = [
        [
            row["series"],
            row["baseline"],
            METRIC_NAMES.get(str(row["metric"]), str(row["metric"])),
            row["agents"],
            format_pct(row["change_pct"]),
            format_pct(row["change_pct_raw"]),
            format_pct(row["paper_change_pct"]),
            f"{row['n_domains']} ({row['domains'] or '-'})",
        ]
        for row in changes.to_dict("records")
    ]
    headers = [
        "TwoStep series",
        "against",
        "metric",
        "N",
        "change (normalised, as the paper)",
        "mean per-domain change (raw)",
        "paper",
        "domains",
    ]
    explanation = (
        "Change of TwoStep against SA (N = 1) and MA (same N), negative = TwoStep lower. "
        "As in the paper, each domain's averages (all series, all N; over the tasks every "
        "series solved, see the figures) are min-max normalised to [0, 1] and averaged "
        "across domains; the change is "
        "(TwoStep - baseline) / baseline of those normalised averages. The paper "
        "reports -50.1 / -60.3 / -64.7 % planning time and -7.7 / -7.1 / -13.2 % "
        "execution length for N = 2 / 3 / 4 without saying which baseline; both are shown. "
        "Normalised changes depend on which series are scaled together and are unstable "
        "when the baseline's normalised value is near 0; the raw column (mean over domains "
        "of the per-domain change of the averages) is a cross-check."
    )
    return explanation + "\n\n" + markdown_table(headers, rows)


def _planning_time_section(report: Report) -> list[str]:
    """TwoStep vs MA planning time per domain and N, when the report has both."""
    view = planning_time_view(report.summary, report.runs)
    if view.empty:
        return []
    intro = (
        "Mean planning time (s) per domain of SA (N = 1), MA and TwoStep (N), and TwoStep's "
        "change against MA, negative = TwoStep plans faster; the paper's figure (normalised "
        "across domains) beside the 'all' row, which averages the domains' means. Exec = "
        "execution length (steps). 'MA at limit': MA runs whose planner call used its whole "
        "time limit; 'TwoStep no helper': TwoStep runs with no accepted helper subgoal, which "
        "return the SA plan (its planner time counts)."
    )
    headers, rows = view_rows(view)
    return ["## TwoStep against MA: planning time per domain", intro, markdown_table(headers, rows)]


def _table1_cell(row: dict[str, object], domain: str, seeded: object = True) -> str:
    text = format_mean_std(
        row.get(f"{domain}_mean"),
        row.get(f"{domain}_std"),
        row.get(f"{domain}_n_seeds"),
        "exec_length",
        seeded,
    )
    tasks = row.get(f"{domain}_n_tasks")
    if (
        row.get("source") != "paper"
        and not _is_nan(tasks)
        and 0 < int(float(str(tasks))) < len(ANNOTATED_TASKS)
    ):
        text += f" ({int(float(str(tasks)))}/{len(ANNOTATED_TASKS)} tasks)"
    return text


def _table1_section(report: Report) -> str:
    ours = report.table1[report.table1["source"] != "paper"]
    intro = (
        f"Execution length (steps) on the annotated tasks {', '.join(map(str, ANNOTATED_TASKS))} "
        f"of each domain, N = {TABLE1_AGENTS}, averaged over those tasks; mean ± std over "
        "the n seeds of a series whose runs differ by seed, one distinct run (no ±) of a "
        "deterministic one. Macro = mean over the domains. The paper's rows are its reported "
        "figures (GPT-4o, 3 runs; the expert is a single run)."
    )
    if ours.empty:
        intro += (
            "\n\nThis report has no successful TwoStep run on those tasks with "
            f"N = {TABLE1_AGENTS} in {', '.join(TABLE1_DOMAINS)}: only the paper's rows "
            "are shown."
        )
    rows = []
    for row in report.table1.to_dict("records"):
        paper = row["source"] == "paper"
        seeded = True if paper else row.get("seeded", True)
        macro = format_mean_std(
            row["macro_mean"], row["macro_std"], row["macro_n_seeds"], "exec_length", seeded
        )
        n_domains = row["macro_n_domains"]
        partial = not _is_nan(n_domains) and int(n_domains) < len(TABLE1_DOMAINS)
        if row["source"] != "paper" and partial:
            macro += f" ({int(n_domains)}/{len(TABLE1_DOMAINS)} domains)"
        failed = "" if _is_nan(row["n_failed"]) else str(int(row["n_failed"]))
        if paper:
            n = "3 runs" if not _is_nan(row["macro_std"]) else "1 run"
        else:
            n = n_label(row["macro_n_seeds"], seeded)
        rows.append(
            [
                row["series"],
                *(_table1_cell(row, d, seeded) for d in TABLE1_DOMAINS),
                macro,
                n,
                failed if not paper else "",
            ]
        )
    headers = ["series", *TABLE1_DOMAINS, "macro avg", "n", "failed / timeout"]
    return intro + "\n\n" + markdown_table(headers, rows)


def _kitchen_limits(report: Report) -> str:
    """The planner alias and search limit(s) the kitchen runs were launched with."""
    runs = report.runs[report.runs["domain"] == TABLE2_DOMAIN]
    settings = []
    for param, unit in report.params.planner:
        column = f"{PARAM_PREFIX}{param}"
        if column in runs:
            values = sorted({str(v) for v in runs[column].dropna()})
            settings += [f"{v}{unit}" for v in values]
    return ", ".join(settings) or "see the runs' planner settings"


def _table2_sections(report: Report) -> list[str]:
    """The paper's Table II beside ours, when the report has kitchen runs."""
    if report.table2.empty:
        return []
    length = str(report.table2[report.table2["source"] == "ours"]["length"].iloc[0])
    intro = (
        f"Kitchen tasks ({TABLE2_DOMAIN} p01..p04), SA at N = 1, MA and TwoStep at "
        f"N = {TABLE2_AGENTS}. Length: {length} (steps), mean ± sample std over seeds; "
        "macro = mean of the task means ± mean of the task stds (as the paper). Planning "
        "time (s): 'timeout' when every run of the cell hit the planner's time limit "
        f"(the paper's limit: {PAPER_TIME_LIMIT_S / 60:.0f} min; ours: {_kitchen_limits(report)}"
        "); macro = number of such cells. The paper's rows are its reported figures "
        "(AI2-THOR, GPT-4o)."
    )
    headers, rows = table_two_rows(report.table2)
    return ["## Embodied execution (paper's Table II)", intro, markdown_table(headers, rows)]


def _failed_section(report: Report) -> str:
    runs = report.runs
    bad = runs[((runs["status"] != ReportStatus.SUCCESS) | ~runs["placed"]) & ~runs["superseded"]]
    if bad.empty:
        return "None."
    rows = []
    for row in bad.head(FAILED_ROWS_SHOWN).to_dict("records"):
        rows.append(
            [
                row["run_id"],
                row["domain"] or "?",
                "?" if _is_nan(row["task"]) else row["task"],
                row["series"] or row["method"] or "?",
                "?" if _is_nan(row["agents"]) else row["agents"],
                "?" if _is_nan(row["seed"]) else row["seed"],
                row["status"] if row["placed"] else f"{row['status']} (unplaced)",
                row["error"] or "-",
            ]
        )
    text = markdown_table(["run", "domain", "task", "series", "N", "seed", "status", "error"], rows)
    if len(bad) > FAILED_ROWS_SHOWN:
        text += f"\n\n... and {len(bad) - FAILED_ROWS_SHOWN} more: see runs.csv."
    return text


def render_markdown(report: Report, title: str, source: str, figures: Sequence[Path] = ()) -> str:
    """The whole report as Markdown; figure paths are linked by file name."""
    sections = [f"# {title}", source, "## Runs", _counts_section(report)]
    if report.notes:
        sections += ["## Notes", "\n".join(f"- {note}" for note in report.notes)]
    if figures:
        sections += ["## Figures", FIGURE_CAPTION, _coverage_section(report)]
        sections += [f"![{path.stem}]({path.name})" for path in figures]
    sections += [
        "## Results per domain",
        "Successful runs only. A deterministic series (SA, MA, TwoStep with an offline "
        "decomposer) repeats one distinct run in every seed: its value is that run's average "
        "over tasks, n = 1 distinct run, no ±. A series whose runs differ by seed (the LLM "
        "decomposer, the embodied executor): mean ± sample std (ddof = 1) over its n seeds of "
        "each seed's average over tasks. 'tasks/seed': tasks in each seed's average; the "
        "counts are per task and seed.",
        _summary_section(report) if len(report.summary) else "No run could be placed.",
        "## Change against SA and MA",
        _changes_section(report),
        *_planning_time_section(report),
        "## Expert subgoals versus decomposers (paper's Table I)",
        _table1_section(report),
        *_table2_sections(report),
        "## Failed, timed-out and unplaced runs",
        _failed_section(report),
    ]
    return "\n\n".join(sections) + "\n"


def format_console(report: Report) -> str:
    """A few lines for the terminal: counts, notes, and the changes beside the paper."""
    lines = [counts_line(report)]
    lines += [f"note: {note}" for note in report.notes]
    changes = report.changes
    if not changes.empty:
        lines.append(
            "change of TwoStep: normalised (as the paper) / raw (mean of the per-domain "
            "changes) | paper:"
        )
        for row in changes.to_dict("records"):
            lines.append(
                f"  {row['series']} vs {row['baseline']}, "
                f"{METRIC_NAMES.get(str(row['metric']), row['metric'])}, N={row['agents']}: "
                f"{format_pct(row['change_pct'])} normalised / "
                f"{format_pct(row['change_pct_raw'])} raw | "
                f"paper {format_pct(row['paper_change_pct'])}"
            )
    if not report.table2.empty:
        headers, rows = table_two_rows(report.table2)
        lines += ["Table II (embodied length; planning time):", markdown_table(headers, rows)]
    return "\n".join(lines)


# ------------------------------------------------------------------ files


def _write_csv(frame: pd.DataFrame, path: Path) -> Path:
    frame.to_csv(path, index=False)
    return path


def write_report(report: Report, out_dir: Path, title: str, source: str) -> list[Path]:
    """Write every CSV, figure and ``report.md`` into ``out_dir``; return the paths.

    ``title`` heads report.md, ``source`` (Markdown) says where the runs came from. Figure
    titles name domains only (no experiment or sweep names).
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    runs = report.runs.drop(columns=["placed", "counted"])
    paths = [
        _write_csv(report.summary, out_dir / "summary.csv"),
        _write_csv(report.compared, out_dir / "compared.csv"),
        _write_csv(report.coverage, out_dir / "coverage.csv"),
        _write_csv(report.changes, out_dir / "changes.csv"),
        _write_csv(planning_time_view(report.summary, report.runs), out_dir / "planning_time.csv"),
        _write_csv(report.table1, out_dir / "table1.csv"),
        *([_write_csv(report.table2, out_dir / "table2.csv")] if not report.table2.empty else []),
        _write_csv(report.per_seed, out_dir / "per_seed.csv"),
        _write_csv(report.per_task, out_dir / "per_task.csv"),
        _write_csv(report.normalised, out_dir / "normalised.csv"),
        _write_csv(report.cross_domain, out_dir / "cross_domain.csv"),
        _write_csv(runs, out_dir / "runs.csv"),
    ]
    figures = plot_report(report, out_dir)
    markdown = out_dir / "report.md"
    pictures = [path for path in figures if path.suffix == ".png"]
    markdown.write_text(render_markdown(report, title, source, pictures))
    return [markdown, *paths, *figures]
