"""The services one sweep shares, started on demand by the first job that needs them:
the Prefect server (:func:`sweep_server`) and the MLflow experiment and parent run
(:func:`sweep_tracking`); and what the launching process asks of them at the end (the
server's count of the sweep's flow runs, stopping the server by PID).

A re-run of a finished sweep therefore starts no server and imports neither Prefect nor
MLflow.
"""

from __future__ import annotations

import contextlib
import json
import socket
import time
from pathlib import Path
from typing import TYPE_CHECKING

from flows.servers import (
    ServerError,
    ServerInfo,
    ServerSettings,
    file_lock,
    read_info,
    shared_server,
    stop_server,
)
from flows.sweep_state import SweepState
from twostep.files import write_json_atomic

if TYPE_CHECKING:
    from flows.tracking.client import Tracker


def sweep_server(state: SweepState) -> ServerInfo:
    """The sweep's Prefect server: the user's, or ours, started by the first job asking."""
    if state.prefect_api_url:
        return ServerInfo(state.prefect_api_url, None, time.time(), 30.0)
    if state.server is None:
        raise RuntimeError("this sweep runs without Prefect (orchestration.prefect=false)")
    if state.hostname and socket.gethostname() != state.hostname:
        # e.g. SLURM: the launching host's 127.0.0.1 is out of reach, and so is its PID.
        raise ServerError(
            f"this job runs on {socket.gethostname()}, the sweep was launched on "
            f"{state.hostname}: set orchestration.prefect_api_url to a server both reach "
            "(or orchestration.prefect=false)"
        )
    return shared_server(
        state.folder / "server.json", ServerSettings(**state.server), state.main_pid
    )


def sweep_tracking(state: SweepState) -> tuple[Tracker, str, str]:
    """(Tracker, experiment id, parent run id), made by the first job that logs.

    Under a lock because the first MlflowClient on a new SQLite file creates its
    tables, which two processes must not do at once: a lock beside the SQLite file, so
    that two sweeps sharing one store take turns too (else the sweep's own).
    """
    from flows.tracking.client import Tracker

    assert state.tracking_uri is not None and state.experiment is not None
    record = state.folder / "mlflow.json"
    lock = state.folder / "mlflow.lock"
    if state.tracking_uri.startswith("sqlite:///") and not state.tracking_uri.endswith(":memory:"):
        lock = Path(state.tracking_uri[len("sqlite:///") :] + ".lock")
    with file_lock(lock):
        tracker = Tracker(state.tracking_uri, state.artifact_location)
        with contextlib.suppress(OSError, ValueError, KeyError):
            data = json.loads(record.read_text())
            return tracker, str(data["experiment_id"]), str(data["parent_run_id"])
        experiment_id = tracker.experiment_id(state.experiment)
        folder = Path(state.sweep_dir)
        parent = tracker.sweep_run(
            experiment_id,
            state.sweep_key,
            name=f"sweep {folder.parent.name}/{folder.name}",
            tags={
                "twostep.sweep_dir": state.sweep_dir,
                "twostep.overrides": " ".join(state.overrides),
            },
        )
        write_json_atomic(record, {"experiment_id": experiment_id, "parent_run_id": parent})
        return tracker, experiment_id, parent


def stop_sweep_server(state: SweepState) -> bool:
    """Stop the server the sweep started (if any); True if there was one."""
    info = read_info(state.folder / "server.json")
    if info is None:
        return False
    stop_server(info)
    return True


def count_flow_runs(api_url: str, tag: str) -> dict[str, int] | None:
    """Flow runs with ``tag`` on the server, by state type (the server's own record)."""
    from prefect.client.orchestration import get_client
    from prefect.client.schemas.filters import FlowRunFilter, FlowRunFilterTags
    from prefect.settings import PREFECT_API_URL, temporary_settings

    counts: dict[str, int] = {}
    flow_run_filter = FlowRunFilter(tags=FlowRunFilterTags(all_=[tag]))
    page = 200
    try:
        with (
            temporary_settings(updates={PREFECT_API_URL: api_url}),
            get_client(sync_client=True) as client,
        ):
            offset = 0
            while True:
                runs = client.read_flow_runs(
                    flow_run_filter=flow_run_filter, limit=page, offset=offset
                )
                for run in runs:
                    state_type = run.state.type.value if run.state is not None else "UNKNOWN"
                    counts[state_type] = counts.get(state_type, 0) + 1
                if len(runs) < page:
                    return counts
                offset += len(runs)
    except Exception:  # the count is part of the summary, never a reason to fail
        return None
