"""The README's "What to compare" steps, done in the MLflow UI in a real browser.

A small sweep through the console script (grippers tasks 1 and 2, SA and TwoStep with N =
2 and 3: SA logs ``agents=1``), the services' MLflow UI, and headless Chromium clicking and
typing through the experiment's runs page as a user would: filter the job runs, add the
columns, group by ``method.name`` and ``agents`` (average), read the groups' mean
``exec_length`` and ``planning_time_s`` from the table, then the chart view: its bar chart
of ``exec_length`` per group and a scatter chart added through "Add chart" (X axis the
param ``agents``, Y axis the metric): the paper's Fig. 3 as points. Every number the page
shows must equal the one computed here from the jobs' ``result.json`` files (and the
sweep's ``results.csv``).

Slow (servers, a sweep, a browser: about 2 minutes); ``make ui-check`` runs it and keeps
the screenshots in ``docs/`` (``TWOSTEP_UI_SCREENSHOTS=<folder>``). Skips, with a message,
where Chromium is not installed.
"""

from __future__ import annotations

import csv
import json
import math
import re
import time
from collections import defaultdict
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

import pytest

from flows import services
from tests.browser import Browser, poll
from tests.ui_sweep import ui_sweep

SWEEP = ["domain=grippers", "task=1,2", "method=sa,twostep", "agents=2,3", "decomposer=goal-split"]
METRICS = ("exec_length", "planning_time_s")
JOB_RUNS = "tags.twostep.kind = 'job'"  # the runs filter the README gives
COLUMNS = ("domain.name", "task", "method.name", "agents", "seed", *METRICS)
UNTICK = ("Dataset", "Source", "Models")  # empty for these runs: room for the columns above
GROUP_BY = ("method.name", "agents")
SEARCH_RUNS = 'input[placeholder^="metrics.rmse"]'  # MLflow's example filter is its placeholder
SEARCH_COLUMNS = 'input[placeholder="Search columns"]'
SEARCH_CHARTS = 'input[placeholder="Search metric charts"]'
GROUP = re.compile(r"Group: method\.name: (\w+), agents: (\d+)\n(\d+)")

Groups = dict[tuple[str, int], dict[str, float]]


def expected_groups(sweep_dir: Path) -> Groups:
    """Per (method, N): the job count and the mean of each metric over the jobs'
    result.json files (N as logged: 1 for SA)."""
    values: dict[tuple[str, int], list[dict[str, float]]] = defaultdict(list)
    for path in sorted(sweep_dir.glob("*/result.json")):
        result = json.loads(path.read_text())
        assert result["success"], path
        values[(result["method"], int(result["agents"]))].append(result)
    return {
        key: {"runs": len(runs), **{m: sum(r[m] for r in runs) / len(runs) for m in METRICS}}
        for key, runs in values.items()
    }


def summary_rows(sweep_dir: Path) -> dict[tuple[str, int], float]:
    """(method, N) -> mean_exec_length from the sweep's results.csv ("twostep (goal-split)"
    is TwoStep)."""
    with (sweep_dir / "results.csv").open() as handle:
        return {
            (row["method"].split()[0], int(row["agents"])): float(row["mean_exec_length"])
            for row in csv.DictReader(handle)
        }


def table_rows(browser: Browser) -> dict[str, dict[str, str]]:
    """The runs table as rendered: row id -> column id -> the cell's text."""
    rows = browser.run(
        "(() => { const out = {};"
        " for (const c of document.querySelectorAll('.ag-row [col-id]')) {"
        "  const id = c.closest('.ag-row').getAttribute('row-id');"
        "  (out[id] = out[id] || {})[c.getAttribute('col-id')] = c.innerText.trim(); }"
        " return out; })()"
    )
    return dict(rows or {})


def table_groups(browser: Browser) -> Groups:
    """The group rows of the runs table: (method, N) -> runs and each metric's cell
    ("9.5 (average)" -> 9.5)."""
    groups: Groups = {}
    for cells in table_rows(browser).values():
        match = GROUP.search(cells.get("attributes.`Run Name`", ""))
        if match is None:
            continue
        found = {"runs": float(match[3])}
        for metric in METRICS:
            text = cells.get(f"metrics.`{metric}`", "")
            assert text.endswith(" (average)"), (metric, text)
            found[metric] = float(text.removesuffix(" (average)"))
        groups[(match[1], int(match[2]))] = found
    return groups


def charts(browser: Browser) -> list[dict[str, Any]]:
    """The data of every chart on the page (Plotly's traces: x, y and the bars' labels)."""
    data = browser.run(
        "[...document.querySelectorAll('.js-plotly-plot')].flatMap(g => g.data.map(t =>"
        " ({type: t.type, x: t.x, y: t.y, text: t.text})))"
    )
    return list(data or [])


def compare_in_mlflow(
    browser: Browser, page: str, shots: Path
) -> tuple[Groups, dict[str, str], dict[str, dict[int, float]]]:
    """The README's steps on an experiment's runs page; (groups read from the table,
    {group: bar} of the exec_length bar chart, {metric: {N: y}} of the scatter charts)."""
    browser.open(page)
    browser.wait_for(["Run Name", "matching runs"])
    time.sleep(2)  # the assistant panel opens after the table
    if browser.find('button[data-component-id="mlflow.assistant.chat_panel.close"]'):
        browser.click('button[data-component-id="mlflow.assistant.chat_panel.close"]')

    # 1. The job runs only: the filter box, Enter (Escape first closes its suggestions).
    browser.click(SEARCH_RUNS)
    browser.type(JOB_RUNS)
    browser.press("Escape")
    browser.press("Enter")
    # The page took it: its state (the URL after "#") carries the filter. The count stays
    # "9 matching runs": MLflow keeps listing the job runs' parent.
    href = str(browser.run("location.href"))
    assert parse_qs(urlsplit(href.partition("#")[2]).query)["searchFilter"] == [JOB_RUNS], href

    # 2. Columns: tick the params and metrics (searching the list), untick the empty ones.
    browser.click("button", "Columns")
    for name in (*COLUMNS, *UNTICK):
        browser.click(SEARCH_COLUMNS)
        browser.type(name)
        browser.click("[class*=tree-title]", name)
        browser.click(SEARCH_COLUMNS)
        browser.press("Backspace", times=len(name))
    browser.press("Escape")

    # 3. Group by method.name, then agents; the aggregate: Average.
    for key in GROUP_BY:
        browser.click("button", "Group by", prefix=True)
        browser.click("[role=menuitemcheckbox]", key)
    browser.click("button", "Group by", prefix=True)
    browser.click('button[aria-label="Change aggregation function"]')
    browser.click("[role=menuitemradio]", "Average")
    browser.press("Escape")
    browser.press("Escape")
    # A wider "Run Name" column shows the groups' names whole.
    browser.drag('.ag-header-cell[col-id="attributes.`Run Name`"] .ag-header-cell-resize', 160, 0)
    groups = poll(
        lambda: found if len(found := table_groups(browser)) >= 3 else None,
        lambda: f"three groups in the runs table (read: {sorted(table_groups(browser))})",
        timeout_s=60,
        interval_s=1.0,
    )
    browser.screenshot(shots / "ui-mlflow-compare.png")

    # 4. Chart view: a bar chart per metric (one bar per group); add a scatter chart,
    # X axis agents, Y axis the metric, for exec_length and planning_time_s.
    browser.click('[role=radiogroup] label:has(input[value="CHART"])')
    for metric in METRICS:
        browser.click("button", "Add chart")
        browser.click("[role=menuitem]", "Scatter chart")
        for nth, name in enumerate(("agents", metric)):
            browser.click("[role=dialog] input[role=combobox]", nth=nth)
            browser.type(name)
            browser.click("[class*=select-item-option-content]", name)
        browser.click("[role=dialog] button", "Add chart")
    scatter: dict[str, dict[int, float]] = {}
    bars: dict[str, str] = {}
    for metric in METRICS:
        browser.click(SEARCH_CHARTS)
        browser.press("Backspace", times=40)
        browser.type(metric)
        browser.wait_for([f"agents vs. {metric}"])
        time.sleep(2)
        for trace in charts(browser):
            if trace["type"] == "scatter":
                points = zip(trace["x"], trace["y"], strict=True)
                scatter[metric] = {int(float(x)): float(y) for x, y in points}
            if trace["type"] == "bar" and metric == "exec_length":
                bars = dict(zip(trace["y"], trace["text"], strict=True))
        if metric == "exec_length":
            # The scatter card (after the bar chart) made wider: its toolbar, top right, no
            # longer hides SA's point at the top left.
            browser.drag('[data-testid="draggable-card-resize-handle"]', 260, 0, nth=1)
            browser.click(SEARCH_CHARTS)  # the pointer off the charts
            time.sleep(2)
            browser.screenshot(shots / "ui-mlflow-compare-chart.png")
    return groups, bars, scatter


@pytest.mark.slow
@pytest.mark.integration
def test_compare_methods_by_agents_in_the_mlflow_ui(data_root: Path, tmp_path: Path) -> None:
    assert data_root.is_dir()
    with ui_sweep(tmp_path, SWEEP, timeout_s=900) as sweep:
        expected = expected_groups(sweep.sweep_dir)
        assert sorted(expected) == [("sa", 1), ("twostep", 2), ("twostep", 3)]
        assert summary_rows(sweep.sweep_dir) == {k: v["exec_length"] for k, v in expected.items()}

        browser = Browser(sweep.binary, tmp_path / "chromium", size=(1400, 1000))
        try:
            page = services.experiment_page(sweep.running["mlflow"].url, sweep.parent_run_id)
            groups, bars, scatter = compare_in_mlflow(browser, page, sweep.shots)
        finally:
            browser.close()

    # The table's groups: one per (method, N), its run count and averages.
    assert set(groups) == set(expected)
    for key, want in expected.items():
        assert groups[key]["runs"] == want["runs"], key
        for metric in METRICS:
            assert math.isclose(groups[key][metric], want[metric], rel_tol=1e-9), (key, metric)
    # The bar chart: one bar per group, labelled with its mean (two decimals).
    for (method, agents), want in expected.items():
        label = bars[f"param.method.name.{method},param.agents.{agents}"]
        assert label == f"{want['exec_length']:.2f}", (method, agents, label)
    # The scatter charts: a point per group at (N, mean).
    for metric in METRICS:
        points = {n: want[metric] for (_, n), want in expected.items()}
        assert scatter[metric].keys() == points.keys(), scatter
        for n, y in points.items():
            assert math.isclose(scatter[metric][n], y, rel_tol=1e-9), (metric, n)
