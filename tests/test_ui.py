"""Both UIs in a real browser: ``twostep-services up``, a 2-job sweep, then headless
Chromium on the Prefect UI's flow runs and the MLflow UI's runs table of the sweep's
experiment; each page must show the sweep's jobs (read from the rendered page's text).

Slow (servers, a sweep, a browser: about 2 minutes); ``make ui-check`` runs it and keeps
the screenshots in ``docs/`` (``TWOSTEP_UI_SCREENSHOTS=<folder>``). Skips, with a message,
where Chromium is not installed (``apt-get install -y chromium``).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from flows import services
from flows.sweep_state import SweepState
from flows.tracking.runs import sweep_run_ids
from tests.browser import Browser, chromium_binary

REPO = Path(__file__).resolve().parent.parent
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
    assert data_root.is_dir()
    binary = chromium_binary()
    if binary is None:
        pytest.skip("no Chromium here: apt-get install -y chromium (the UI test needs a browser)")
    shots = Path(os.environ.get("TWOSTEP_UI_SCREENSHOTS") or tmp_path)
    shots.mkdir(parents=True, exist_ok=True)
    root = tmp_path / "out"
    try:
        running = services.up(root, timeout_s=240)
        # The console script, as a user runs it (its name is the runs' mlflow.source.name);
        # the package's own data (data_root: skip when it is not there).
        done = subprocess.run(
            [str(Path(sys.executable).parent / "twostep"), "-m", "domain=grippers", "task=1",
             "method=sa,twostep", "agents=2", "decomposer=goal-split", f"output.root={root}"],
            capture_output=True, text=True, cwd=REPO, timeout=600,
        )  # fmt: skip
        assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
        assert "prefect UI: " in done.stdout and "mlflow UI: " in done.stdout
        (sweep_dir,) = root.glob("multiruns/*/*")
        state = SweepState.load(sweep_dir)
        assert state is not None and (sweep_dir / "results.csv").is_file()
        ids = sweep_run_ids(state)
        assert ids is not None

        browser = Browser(binary, tmp_path / "chromium")
        try:
            browser.open(running["prefect"].ui_url)
            browser.wait_for(["Completed", *FLOW_RUNS])
            browser.screenshot(shots / "ui-prefect-flow-runs.png")

            browser.open(services.experiment_page(running["mlflow"].url, ids[0]))
            # The runs table (its "Run Name" column), not the GenAI overview; the job runs.
            browser.wait_for(["Run Name", *JOBS], action=EXPAND)
            browser.screenshot(shots / "ui-mlflow-runs.png")
        finally:
            browser.close()
    finally:
        services.down(root)
