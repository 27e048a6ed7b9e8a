"""Running the twostep commands in tests: the CLI, a sweep, the composed config, the
Prefect API."""

from __future__ import annotations

import json
import subprocess
import sys
import urllib.request
from pathlib import Path
from typing import Any


def api(url: str, path: str, body: dict[str, Any]) -> Any:
    request = urllib.request.Request(
        f"{url}{path}", data=json.dumps(body).encode(), headers={"Content-Type": "application/json"}
    )
    with urllib.request.urlopen(request, timeout=10) as response:
        return json.loads(response.read())


REPO = Path(__file__).resolve().parent.parent.parent


def run_cli(*overrides: str, cwd: Path = REPO) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "flows.cli", "orchestration.prefect=false", "mlflow.enabled=false", *overrides],
        capture_output=True, text=True, cwd=cwd, timeout=240,
    )  # fmt: skip


def compose_config(*overrides: str) -> Any:
    """The composed job config (conf/) with these overrides, output and data in /tmp/x."""
    from hydra import compose, initialize_config_dir

    from flows.config import register

    register()
    with initialize_config_dir(config_dir=str(REPO / "conf"), version_base="1.3"):
        return compose("config", overrides=["output.root=/tmp/x", "data.root=/tmp/x", *overrides])


TWOSTEP = Path(sys.executable).parent / "twostep"  # the console script of this venv


def mlflow_experiment(out: Path) -> tuple[Any, list[Any]]:
    from mlflow.tracking import MlflowClient

    client = MlflowClient(f"sqlite:///{out}/mlflow.db")
    (experiment,) = [e for e in client.search_experiments() if e.name.startswith("sweep ")]
    return client, list(client.search_runs([experiment.experiment_id]))


def run(args: list[str], timeout: float = 600) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(TWOSTEP), *args], capture_output=True, text=True, timeout=timeout)


def summary(sweep_dir: Path) -> dict[str, Any]:
    return dict(json.loads((sweep_dir / ".twostep" / "summary.json").read_text()))


def sweep_dirs(out: Path) -> list[Path]:
    return sorted(p.parent.parent for p in out.glob("multiruns/*/*/.twostep/sweep.json"))
