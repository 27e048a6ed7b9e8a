"""``twostep-services up|down|status``: a long-lived Prefect server and MLflow UI, and
the Prefect server a run finds running (:func:`running_prefect_api`).

Without them a single run uses the library directly (logging to MLflow's SQLite store)
and each sweep starts a Prefect server of its own (``flows/server.py``). With them up,
every later run and sweep uses the warm Prefect server (a flow run costs about 2 s
instead of a server start-up), and the MLflow UI serves the same SQLite store that the
jobs keep logging to.

``up`` starts both on 127.0.0.1 at free ports, each in a session of its own, and records
their addresses and PIDs in ``<output root>/services.json``; ``down`` stops exactly those
process groups; ``status`` prints them. A record whose PID is dead is stale: reported and
removed (by every command, and by runs looking for the services).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import urllib.request
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from flows.environment import quiet_defaults
from flows.servers import (
    ServerSettings,
    free_port,
    is_healthy,
    pid_alive,
    spawn,
    spawn_server,
    stop_process,
    url_host,
)
from twostep.cli import console_main
from twostep.util.files import write_json_atomic

RECORD = "services.json"
# MLflow 3.17's UI shows the GenAI pages (traces) unless its "Model training" switch is on:
# the switch is the page's ``workflowType`` query (else the browser's saved choice); the
# experiment's ``mlflow.experimentKind`` tag alone does not change it.
MLFLOW_CLASSIC_UI = "workflowType=machine_learning"


@dataclass(frozen=True)
class Service:
    """One service we started: where it answers and the PID leading its process group."""

    name: str  # prefect | mlflow
    url: str  # Prefect: its API URL (…/api); MLflow: the UI and tracking server
    pid: int
    log_path: str
    started_at: float

    def alive(self) -> bool:
        return pid_alive(self.pid)

    def healthy(self, timeout_s: float = 2.0) -> bool:
        return self.alive() and is_healthy(self.url, timeout_s)  # both answer GET <url>/health

    @property
    def ui_url(self) -> str:
        """Where a person opens it: Prefect's flow-runs page, MLflow's experiments."""
        if self.name == "prefect":
            return self.url.removesuffix("/api") + "/runs"
        return f"{self.url}/#/experiments?{MLFLOW_CLASSIC_UI}"


def record_path(root: str | Path) -> Path:
    return Path(root) / RECORD


def read_record(root: str | Path) -> dict[str, Service]:
    try:
        data = json.loads(record_path(root).read_text())
        return {name: Service(**item) for name, item in data["services"].items()}
    except (OSError, ValueError, TypeError, KeyError, AttributeError):
        return {}


def _write_record(root: str | Path, services: dict[str, Service]) -> None:
    path = record_path(root)
    if not services:
        path.unlink(missing_ok=True)
        return
    write_json_atomic(path, {"services": {name: asdict(s) for name, s in services.items()}})


def clean_stale(root: str | Path) -> tuple[dict[str, Service], list[Service]]:
    """(the services still running, the stale entries removed from the record)."""
    services = read_record(root)
    stale = [s for s in services.values() if not s.alive()]
    if stale:
        _write_record(root, {n: s for n, s in services.items() if s.alive()})
    return {n: s for n, s in services.items() if s.alive()}, stale


def prefect_api_url(root: str | Path) -> str | None:
    """The API URL of the services' Prefect server if it is up and answering, else None.

    Cheap (one file and one local HTTP request): every run asks.
    """
    service = read_record(root).get("prefect")
    if service is None or not service.healthy(timeout_s=2.0):
        return None
    return service.url


def running_prefect_api(orchestration: Any, root: str | Path) -> str | None:
    """The running Prefect server a job or sweep uses, if any: ``orchestration.
    prefect_api_url``, else ``PREFECT_API_URL``, else the long-lived services' (up and
    answering)."""
    external = orchestration.prefect_api_url or os.environ.get("PREFECT_API_URL")
    return str(external) if external else prefect_api_url(root)


def _mlflow_command(root: Path, host: str, port: int) -> list[str]:
    return [
        sys.executable, "-m", "mlflow", "server",
        "--host", host, "--port", str(port),
        "--workers", "1",
        "--backend-store-uri", f"sqlite:///{root / 'mlflow.db'}",
        "--default-artifact-root", str(root / "mlruns"),
    ]  # fmt: skip


def _mlflow_environment() -> dict[str, str]:
    from flows.environment import DEFAULTS

    # Forced, not defaults: without them the server hangs at start-up offline
    # (STACK-NOTES: MLflow 3.17.2).
    return {**os.environ, **DEFAULTS}


def up(root: Path, host: str = "127.0.0.1", timeout_s: float = 180.0) -> dict[str, Service]:
    """Start whichever of the two services is not running; wait until both answer."""
    root = root.resolve()
    root.mkdir(parents=True, exist_ok=True)
    services, _ = clean_stale(root)
    if "prefect" not in services:
        info = spawn_server(ServerSettings(str(root / "prefect"), host, timeout_s), None, ui=True)
        assert info.pid is not None and info.log_path is not None
        services["prefect"] = Service("prefect", info.api_url, info.pid, info.log_path, time.time())
    if "mlflow" not in services:
        port = free_port(host)
        log_path = root / f"mlflow-server-{port}.log"
        pid = spawn(_mlflow_command(root, host, port), _mlflow_environment(), log_path, None)
        url = f"http://{url_host(host)}:{port}"
        services["mlflow"] = Service("mlflow", url, pid, str(log_path), time.time())
    _write_record(root, services)  # recorded before waiting: `down` can stop a slow start
    deadline = time.monotonic() + timeout_s
    waiting = dict(services)
    while waiting:
        for name, service in list(waiting.items()):
            if is_healthy(service.url):
                del waiting[name]
            elif not service.alive():
                raise RuntimeError(f"{name} exited during start-up; log: {service.log_path}")
        if waiting and time.monotonic() > deadline:
            names = ", ".join(waiting)
            raise RuntimeError(f"{names} did not answer within {timeout_s:.0f} s")
        time.sleep(0.25)
    return services


def down(root: Path) -> list[Service]:
    """Stop the recorded services (their process groups); return those that were running."""
    stopped = [s for s in read_record(root).values() if stop_process(s.pid, grace_s=20.0)]
    _write_record(root, {})
    return stopped


def status_lines(root: Path) -> tuple[list[str], bool]:
    """Lines for ``status`` and whether every recorded service answers."""
    services, stale = clean_stale(root)
    lines = [f"{s.name}: stale record (PID {s.pid} is not running): removed" for s in stale]
    ok = bool(services)
    for name in ("prefect", "mlflow"):
        service = services.get(name)
        if service is None:
            lines.append(f"{name}: down")
            ok = False
            continue
        healthy = service.healthy()
        ok = ok and healthy
        state = "up" if healthy else "running, not answering"
        lines.append(f"{name}: {state} at {service.url} (PID {service.pid})")
        lines.append(f"{name} UI: {service.ui_url}")
        latest = latest_experiment(service.url) if healthy and name == "mlflow" else None
        if latest is not None:
            lines.append(f"mlflow latest experiment: '{latest[0]}' {latest[1]}")
    return lines, ok


def experiment_page(mlflow_url: str, experiment_id: str) -> str:
    """The MLflow UI's page of one experiment, on its runs table."""
    return f"{mlflow_url.rstrip('/')}/#/experiments/{experiment_id}?{MLFLOW_CLASSIC_UI}"


def latest_experiment(mlflow_url: str, timeout_s: float = 5.0) -> tuple[str, str] | None:
    """(name, UI page) of the experiment updated last on an MLflow server, asked through
    its REST API (MLflow is not imported); None when there is none or no answer."""
    query = json.dumps(
        {
            "max_results": 1,
            "filter": "name != 'Default'",  # MLflow's own, always there
            "order_by": ["last_update_time DESC"],
            "view_type": "ACTIVE_ONLY",
        }
    ).encode()
    request = urllib.request.Request(
        f"{mlflow_url}/api/2.0/mlflow/experiments/search",
        data=query,
        headers={"Content-Type": "application/json"},
    )
    try:
        with urllib.request.urlopen(request, timeout=timeout_s) as response:
            found = json.load(response).get("experiments") or []
    except (OSError, ValueError):
        return None
    if not found:
        return None
    return str(found[0]["name"]), experiment_page(mlflow_url, str(found[0]["experiment_id"]))


@console_main
def main(argv: Sequence[str] | None = None) -> int:
    quiet_defaults()
    parser = argparse.ArgumentParser(
        prog="twostep-services",
        description="Long-lived Prefect server and MLflow UI for twostep runs and sweeps.",
    )
    parser.add_argument("command", choices=("up", "down", "status"))
    parser.add_argument(
        "--root", default="outputs", help="the runs' output.root (default: ./outputs)"
    )
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--timeout", type=float, default=180.0, help="start-up timeout (s)")
    args = parser.parse_args(argv)
    root = Path(args.root).resolve()
    if args.command == "up":
        try:
            services = up(root, args.host, args.timeout)
        except RuntimeError as error:
            print(f"error: {error} (stop what started: twostep-services down)", file=sys.stderr)
            return 1
        for service in services.values():
            print(f"{service.name}: up at {service.url} (PID {service.pid})")
            print(f"{service.name} UI: {service.ui_url}")
        print(f"record: {record_path(root)}")
        return 0
    if args.command == "down":
        stopped = down(root)
        for service in stopped:
            print(f"{service.name}: stopped (PID {service.pid})")
        if not stopped:
            print("no services were running")
        return 0
    lines, ok = status_lines(root)
    print("\n".join(lines))
    return 0 if ok else 3


if __name__ == "__main__":
    sys.exit(main())
