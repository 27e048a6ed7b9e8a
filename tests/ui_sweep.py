"""What both UI tests start from: Chromium (skip without it), the screenshots' folder,
``twostep-services up``, a sweep through the console script as a user runs it (its name is
the runs' ``mlflow.source.name``), and the services stopped by PID at the end."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from flows import services
from flows.sweep_state import SweepState
from flows.tracking.runs import sweep_run_ids
from tests.support.skips import skip_without_chromium

REPO = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class UiSweep:
    binary: str  # Chromium
    shots: Path  # where screenshots go (TWOSTEP_UI_SCREENSHOTS, else the test's tmp_path)
    running: dict[str, services.Service]  # services.up's answer: Prefect and MLflow
    output: str  # the sweep's stdout
    sweep_dir: Path
    experiment_id: str  # the sweep's experiment in MLflow
    parent_run_id: str  # the sweep's parent run in MLflow


@contextmanager
def ui_sweep(tmp_path: Path, overrides: Sequence[str], timeout_s: float) -> Iterator[UiSweep]:
    binary = skip_without_chromium()
    shots = Path(os.environ.get("TWOSTEP_UI_SCREENSHOTS") or tmp_path)
    shots.mkdir(parents=True, exist_ok=True)
    root = tmp_path / "out"
    try:
        running = services.up(root, timeout_s=240)
        done = subprocess.run(
            [str(Path(sys.executable).parent / "twostep"), "-m", *overrides, f"output.root={root}"],
            capture_output=True, text=True, cwd=REPO, timeout=timeout_s,
        )  # fmt: skip
        assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
        (sweep_dir,) = root.glob("multiruns/*/*")
        state = SweepState.load(sweep_dir)
        assert state is not None
        ids = sweep_run_ids(state)
        assert ids is not None
        yield UiSweep(binary, shots, running, done.stdout, sweep_dir, ids[0], ids[1])
    finally:
        services.down(root)
