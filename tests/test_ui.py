"""Both UIs in a real browser: ``twostep-services up``, a 2-job sweep, then headless
Chromium on the Prefect UI's flow runs of the sweep (the link the sweep prints, filtered by
its tag), one flow run's page (its task runs named by step, role and agent; its log), and
the MLflow UI's runs table of the sweep's experiment; each page must show what the sweep
did (read from the rendered page's text), under the one name each job has everywhere.

Slow (servers, a sweep, a browser: about 2 minutes); ``make ui-check`` runs it and keeps
the screenshots in ``docs/`` (``TWOSTEP_UI_SCREENSHOTS=<folder>``). Skips, with a message,
where Chromium is not installed (``apt-get install -y chromium``).
"""

from __future__ import annotations

import json
import re
import urllib.request
from pathlib import Path
from typing import Any

import pytest

from flows import services
from tests.browser import Browser
from tests.ui_sweep import ui_sweep

SWEEP = ["domain=grippers", "task=1", "method=sa,twostep", "agents=2", "decomposer=goal-split"]
# one name per job, on the console, in Prefect and in MLflow (SA runs one agent: n1)
JOBS = ["grippers-p01-sa-n1-s0", "grippers-p01-twostep-goal-split-n2-s0"]
TASK_RUNS = ["plan sa", "plan helper agent1", "progress after agent1", "plan main agent0", "score"]
EXPAND = (  # MLflow: open the sweep's parent run (its job runs are children), close the assistant
    "document.querySelectorAll('button[data-component-id*=\"runnamecellrenderer\"]')"
    ".forEach(b => { if (!b.dataset.twostepOpened) { b.dataset.twostepOpened = 1; b.click(); } });"
    "document.querySelectorAll('button[data-component-id=\"mlflow.assistant.chat_panel.close\"]')"
    ".forEach(b => b.click());"
)


def flow_run_id(api_url: str, name: str, tag: str) -> str:
    """The id of the flow run of that name with the sweep's tag (Prefect's API)."""
    body = {"flow_runs": {"name": {"any_": [name]}, "tags": {"all_": [tag]}}}
    request = urllib.request.Request(
        f"{api_url}/flow_runs/filter",
        data=json.dumps(body).encode(),
        headers={"Content-Type": "application/json"},
    )
    with urllib.request.urlopen(request, timeout=10) as response:
        runs: list[dict[str, Any]] = json.loads(response.read())
    (run,) = runs
    return str(run["id"])


@pytest.mark.slow
@pytest.mark.integration
def test_flow_runs_in_prefect_and_job_runs_in_mlflow(data_root: Path, tmp_path: Path) -> None:
    assert data_root.is_dir()  # the package's own data (data_root: skip when it is not there)
    with ui_sweep(tmp_path, SWEEP, timeout_s=600) as sweep:
        assert (sweep.sweep_dir / "results.csv").is_file()
        for name in JOBS:  # the console's progress lines name the jobs as the UIs do
            assert f"] {name} | success" in sweep.output
        # the sweep's last lines: its flow runs (filtered by its tag), its experiment, and
        # the command that reports it
        (prefect_link,) = re.findall(r"^prefect UI: (\S+)$", sweep.output, re.M)
        tag = f"multirun:{sweep.sweep_dir.parent.name}_{sweep.sweep_dir.name}"
        assert prefect_link == f"{sweep.running['prefect'].ui_url}?tag={tag}"
        assert "mlflow UI: " in sweep.output
        assert f"report: twostep-report --experiment {sweep.experiment_id} " in sweep.output
        browser = Browser(sweep.binary, tmp_path / "chromium")
        try:
            browser.open(prefect_link)
            browser.wait_for(["Completed", *JOBS, tag])
            browser.screenshot(sweep.shots / "ui-prefect-flow-runs.png")

            api = sweep.running["prefect"].url
            run_id = flow_run_id(api, JOBS[1], tag)
            browser.open(f"{api.removesuffix('/api')}/runs/flow-run/{run_id}")
            # the task runs by step, role and agent (the timeline), the flow run's log
            browser.wait_for([*TASK_RUNS, f"start {JOBS[1]}", f"result: {JOBS[1]} | success"])
            browser.screenshot(sweep.shots / "ui-prefect-flow-run.png")

            browser.open(services.experiment_page(sweep.running["mlflow"].url, sweep.experiment_id))
            # The runs table (its "Run Name" column), not the GenAI overview; the job runs.
            browser.wait_for(["Run Name", *JOBS], action=EXPAND)
            browser.screenshot(sweep.shots / "ui-mlflow-runs.png")
        finally:
            browser.close()
