"""Both UIs in a real browser: ``twostep-services up``, a 2-job sweep, then headless
Chromium on the Prefect UI's flow runs and the MLflow UI's runs table of the sweep's
experiment; each page must show the sweep's jobs (read from the rendered page's text).

Slow (servers, a sweep, a browser: about 2 minutes); ``make ui-check`` runs it and keeps
the screenshots in ``docs/`` (``TWOSTEP_UI_SCREENSHOTS=<folder>``). Skips, with a message,
where Chromium is not installed (``apt-get install -y chromium``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from flows import services
from tests.browser import Browser
from tests.ui_sweep import ui_sweep

SWEEP = ["domain=grippers", "task=1", "method=sa,twostep", "agents=2", "decomposer=goal-split"]
JOBS = ["grippers-p01-sa-n1-s0 (grid N=2)", "grippers-p01-twostep-n2-s0"]
FLOW_RUNS = ["grippers-p01-sa-n2-s0", "grippers-p01-twostep-n2-s0"]
EXPAND = (  # MLflow: open the sweep's parent run (its job runs are children), close the assistant
    "document.querySelectorAll('button[data-component-id*=\"runnamecellrenderer\"]')"
    ".forEach(b => { if (!b.dataset.twostepOpened) { b.dataset.twostepOpened = 1; b.click(); } });"
    "document.querySelectorAll('button[data-component-id=\"mlflow.assistant.chat_panel.close\"]')"
    ".forEach(b => b.click());"
)


@pytest.mark.slow
@pytest.mark.integration
def test_flow_runs_in_prefect_and_job_runs_in_mlflow(data_root: Path, tmp_path: Path) -> None:
    assert data_root.is_dir()  # the package's own data (data_root: skip when it is not there)
    with ui_sweep(tmp_path, SWEEP, timeout_s=600) as sweep:
        assert "prefect UI: " in sweep.output and "mlflow UI: " in sweep.output
        assert (sweep.sweep_dir / "results.csv").is_file()
        browser = Browser(sweep.binary, tmp_path / "chromium")
        try:
            browser.open(sweep.running["prefect"].ui_url)
            browser.wait_for(["Completed", *FLOW_RUNS])
            browser.screenshot(sweep.shots / "ui-prefect-flow-runs.png")

            browser.open(services.experiment_page(sweep.running["mlflow"].url, sweep.parent_run_id))
            # The runs table (its "Run Name" column), not the GenAI overview; the job runs.
            browser.wait_for(["Run Name", *JOBS], action=EXPAND)
            browser.screenshot(sweep.shots / "ui-mlflow-runs.png")
        finally:
            browser.close()
