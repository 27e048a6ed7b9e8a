"""The Prefect server's start-up, timed in a fresh process: ``bench/bench_orchestration.py``
and ``bench/bench_sweep.py`` report it beside their runs."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def server_startup(home: Path, env: dict[str, str]) -> float:
    """Seconds from spawning ``prefect server start`` to a healthy API (then stopped)."""
    code = (
        "import os, time, sys; from flows.servers import ServerSettings, spawn_server, "
        "stop_server, wait_until_healthy; t = time.perf_counter(); "
        f"info = spawn_server(ServerSettings(home={str(home)!r}, startup_timeout_s=600), os.getpid()); "
        "wait_until_healthy(info); print(time.perf_counter() - t); stop_server(info)"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=REPO, check=True
    )
    return float(done.stdout.strip().splitlines()[-1])
