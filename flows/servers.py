"""The Prefect API servers we start: one for a whole sweep, started on demand, watched,
stopped by PID (long-lived ones are :mod:`flows.services`).

Without a server every process that runs a flow starts its own temporary one (8 s with
a warm database, over 30 s on a fresh one: STACK-NOTES). A sweep instead shares one
``prefect server start`` on 127.0.0.1 at a free port, which every job reaches through
``PREFECT_API_URL``.

* **On demand.** The first job that needs the API starts the server (under a file lock
  in the sweep directory, so parallel workers start exactly one) and records it in
  ``.twostep/server.json``; a sweep whose jobs are all finished never starts one.
* **Patient.** Jobs wait on ``/api/health`` until ``startup_timeout_s`` after the spawn:
  the first start on a fresh database runs its migrations (over 30 s on a small machine).
* **Watched.** The server runs under a small watchdog (``python -m flows.servers``) that
  stops it as soon as the sweep's launching process is gone, even after ``kill -9``, so
  an interrupted sweep leaves no server behind. The server has its own session, so
  Ctrl-C in the terminal reaches the jobs, not the server under them.
* **Stopped by PID** at the end of the sweep (SIGTERM to the watchdog, which stops the
  server and waits for it).
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import fcntl
import functools
import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from twostep.util.files import write_json_atomic

if TYPE_CHECKING:
    from flows.sweep_state import SweepState

# Server-side services a sweep does not use: schedules, deployments, work pools, pauses.
# The task run recorder stays on: it records the task runs (from their events). A server
# without the UI (a sweep's own) does not keep the events themselves either (the event
# persister: a third of the server's work per job); one with the UI
# (``twostep-services``) does, for its events pages.
_IDLE_SERVICES = (
    "SCHEDULER",
    "LATE_RUNS",
    "FOREMAN",
    "PAUSE_EXPIRATIONS",
    "CANCELLATION_CLEANUP",
    "REPOSSESSOR",
    "TRIGGERS",
    "DB_VACUUM",
)

_TASK_RUN_RECORDER = {"BATCH_SIZE": "100", "READ_BATCH_SIZE": "100", "FLUSH_INTERVAL": "1"}


class ServerError(Exception):
    """The Prefect server did not start, or stopped answering."""


@dataclass(frozen=True)
class ServerInfo:
    """What a job needs to reach (and wait for) a server."""

    api_url: str  # http://127.0.0.1:<port>/api
    pid: int | None  # the watchdog's PID; None for a server we did not start
    started_at: float  # time.time() of the spawn
    startup_timeout_s: float
    log_path: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ServerInfo:
        return cls(**data)


@dataclass(frozen=True)
class ServerSettings:
    home: str  # PREFECT_HOME of the server: its database lives there
    host: str = "127.0.0.1"
    startup_timeout_s: float = 180.0

    @classmethod
    def from_config(cls, orchestration: Any) -> ServerSettings:
        """The settings of a server we start, from the config's ``orchestration`` node."""
        return cls(
            home=str(orchestration.prefect_home),
            host=str(orchestration.server_host),
            startup_timeout_s=float(orchestration.server_startup_timeout_s),
        )


_HANDED_OUT: set[int] = set()
"""Ports :func:`free_port` gave this process already."""


def free_port(host: str = "127.0.0.1") -> int:
    """A port the system has free now, never one this process was given before: two servers
    started one after the other (Prefect, then MLflow) are each given a port before either
    has bound its own, and the system may offer the same free port twice."""
    while True:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
            sock.bind((host, 0))
            port = int(sock.getsockname()[1])
        if port not in _HANDED_OUT:
            _HANDED_OUT.add(port)
            return port


def server_environment(
    home: Path, host: str = "127.0.0.1", port: int = 4200, ui: bool = False
) -> dict[str, str]:
    """Environment of the server process: its database under ``home``, no telemetry, and
    its own address, which its UI hands to the browser (``/ui-settings``: without it the
    UI calls Prefect's default port 4200 and shows no flow runs)."""
    env = dict(os.environ)
    env.update(
        PREFECT_HOME=str(home),
        PREFECT_SERVER_API_HOST=host,
        PREFECT_SERVER_API_PORT=str(port),
        PREFECT_UI_API_URL=f"http://{url_host(host)}:{port}/api",
        PREFECT_SERVER_ANALYTICS_ENABLED="false",
        # The UI copies its files at start-up; a sweep's server is for its jobs. To watch
        # runs in the UI, start the long-lived services (``twostep-services up``).
        PREFECT_SERVER_UI_ENABLED="true" if ui else "false",
        # Block types are for the UI's catalog (a server with the UI registers them; the
        # database template has them); a sweep's server skips the work at its start.
        PREFECT_API_BLOCKS_REGISTER_ON_START="true" if ui else "false",
        PREFECT_LOGGING_LEVEL="WARNING",
        DO_NOT_TRACK="1",
    )
    for service in _IDLE_SERVICES:
        env[f"PREFECT_SERVER_SERVICES_{service}_ENABLED"] = "false"
    env["PREFECT_SERVER_SERVICES_EVENT_PERSISTER_ENABLED"] = "true" if ui else "false"
    # The task run recorder writes task runs from their events, by default one database
    # transaction per event: half of the server's CPU time per job (bench/bench_sweep.py).
    # In batches of up to 100, flushed at least every second (the UI shows a task run
    # within a second; the recorder flushes what it holds when the server stops).
    for key, value in _TASK_RUN_RECORDER.items():
        env.setdefault(f"PREFECT_SERVER_SERVICES_TASK_RUN_RECORDER_{key}", value)
    # A server must never talk to another server.
    env.pop("PREFECT_API_URL", None)
    return env


def _die_with_parent() -> None:  # pragma: no cover - runs in the child before exec
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL("libc.so.6", use_errno=True)
            libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG: the watchdog died


def spawn(
    command: Sequence[str], env: Mapping[str, str], log_path: Path, owner_pid: int | None
) -> int:
    """Start ``command`` in a session of its own, output to ``log_path``; return its PID.

    With ``owner_pid`` it runs under the watchdog (stopped when that process is gone);
    without, it runs until stopped by PID (its process group: :func:`stop_process`).
    """
    full = list(command)
    if owner_pid is not None:
        full = [sys.executable, "-m", "flows.servers", "--owner", str(owner_pid), "--", *full]
    with open(log_path, "wb") as log:
        process = subprocess.Popen(
            full,
            env=dict(env),
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # Ctrl-C in the terminal must not stop it under the jobs
        )
    return process.pid


def url_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host


def spawn_server(settings: ServerSettings, owner_pid: int | None, ui: bool = False) -> ServerInfo:
    """Start ``prefect server start`` on a free port; return without waiting.

    ``owner_pid``: the process whose exit stops the server (a sweep's launcher, a single
    run); ``None`` for a long-lived server (``twostep-services``).
    """
    from flows.prefect_template import seed_home

    home = Path(settings.home)
    home.mkdir(parents=True, exist_ok=True)
    seed_home(home)  # a new home starts from the environment's migrated database
    port = free_port(settings.host)
    log_path = home / f"server-{port}.log"
    command = [sys.executable, "-m", "prefect", "server", "start"]
    command += ["--host", settings.host, "--port", str(port)]
    environment = server_environment(home, settings.host, port, ui)
    pid = spawn(command, environment, log_path, owner_pid)
    return ServerInfo(
        api_url=f"http://{url_host(settings.host)}:{port}/api",
        pid=pid,
        started_at=time.time(),
        startup_timeout_s=settings.startup_timeout_s,
        log_path=str(log_path),
    )


def is_healthy(api_url: str, timeout_s: float = 2.0) -> bool:
    """Whether ``GET <api_url>/health`` answers 200 (Prefect's API and MLflow's server).

    A plain HTTP probe on purpose: it runs before Prefect is imported (2 s), e.g. in
    every single run looking for the services (as :func:`count_flow_runs` at a sweep's end).
    """
    try:
        with urllib.request.urlopen(f"{api_url}/health", timeout=timeout_s) as response:
            return bool(response.status == 200)
    except (urllib.error.URLError, OSError, ValueError):
        return False


@functools.cache
def csrf_enforced(api_url: str, timeout_s: float = 5.0) -> bool:
    """Whether the server at ``api_url`` wants CSRF tokens (ours never do). Asked once per
    process: Prefect's client asks again in every flow run (one request each) unless told
    the server does not. In doubt (no answer), True: the client then asks itself."""
    try:
        with urllib.request.urlopen(f"{api_url}/csrf-token?client=twostep", timeout=timeout_s):
            return True
    except urllib.error.HTTPError as error:
        return not (error.code == 422 and b"CSRF protection is disabled" in error.read())
    except (urllib.error.URLError, OSError, ValueError):
        return True


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    # A zombie (exited, not yet reaped by its parent) counts as dead.
    with contextlib.suppress(OSError, IndexError):
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return fields[0] != "Z"
    return True


def wait_until_healthy(info: ServerInfo, poll_s: float = 0.25) -> float:
    """Block until the server answers; return the seconds waited here.

    The deadline counts from the spawn, so jobs that start late do not extend it. A
    server that died is reported at once, with the last line of its log.
    """
    start = time.monotonic()
    deadline = info.started_at + info.startup_timeout_s
    while True:
        if is_healthy(info.api_url):
            return time.monotonic() - start
        if info.pid is not None and not pid_alive(info.pid):
            raise ServerError(f"the Prefect server at {info.api_url} exited{_log_tail(info)}")
        if time.time() > deadline:
            raise ServerError(
                f"the Prefect server at {info.api_url} did not answer within "
                f"{info.startup_timeout_s:.0f} s (raise orchestration.server_startup_timeout_s)"
                f"{_log_tail(info)}"
            )
        time.sleep(poll_s)


def _log_tail(info: ServerInfo) -> str:
    if not info.log_path:
        return ""
    try:
        lines = [line for line in Path(info.log_path).read_text().splitlines() if line.strip()]
    except OSError:
        return ""
    return f"; log {info.log_path}: {lines[-1][:200]}" if lines else ""


def stop_server(info: ServerInfo | None, grace_s: float = 20.0) -> None:
    """Stop a server we started: SIGTERM to its watchdog, SIGKILL after ``grace_s``."""
    if info is None or info.pid is None:
        return
    stop_process(info.pid, grace_s, group=False)


def stop_process(pid: int, grace_s: float = 20.0, group: bool = True) -> bool:
    """Stop a process we started in its own session: SIGTERM (to its whole process group
    with ``group``; a watchdog stops its child itself), SIGKILL to the group after
    ``grace_s``. False if it was not running."""
    if not pid_alive(pid):
        return False
    with contextlib.suppress(ProcessLookupError, PermissionError):
        if group:
            os.killpg(pid, signal.SIGTERM)
        else:
            os.kill(pid, signal.SIGTERM)
    deadline = time.monotonic() + grace_s
    while pid_alive(pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    if pid_alive(pid):
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pid, signal.SIGKILL)  # the process leads its own session
    return True


# ----------------------------------------------------------------- on demand, shared


@contextlib.contextmanager
def file_lock(path: Path) -> Iterator[None]:
    """An exclusive lock between the processes of a sweep on this machine."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def read_info(path: Path) -> ServerInfo | None:
    try:
        return ServerInfo.from_dict(json.loads(Path(path).read_text()))
    except (OSError, ValueError, TypeError):
        return None


def shared_server(info_path: Path, settings: ServerSettings, owner_pid: int) -> ServerInfo:
    """The server recorded at ``info_path``, started now if there is none (or it died)."""
    from flows.prefect_template import template_path

    with file_lock(info_path.with_suffix(".lock")):
        info = read_info(info_path)
        if info is not None and info.pid is not None and pid_alive(info.pid):
            return info
        fresh = not any(Path(settings.home).glob("*.db"))
        info = spawn_server(settings, owner_pid)  # seeds a new home from the template
        write_json_atomic(info_path, info.to_dict())
        migrating = fresh and not template_path().is_file()
        wait = " (a new database: its first start migrates it, up to a minute)" if migrating else ""
        print(f"starting Prefect server at {info.api_url}{wait} ...", flush=True)
        return info


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


def stop_sweep_server(state: SweepState) -> bool:
    """Stop the server the sweep started (if any); True if there was one."""
    info = read_info(state.folder / "server.json")
    if info is None:
        return False
    stop_server(info)
    return True


def count_flow_runs(api_url: str, tag: str, timeout_s: float = 30.0) -> dict[str, int] | None:
    """Flow runs with ``tag`` on the server, by state type (the server's own record),
    asked over HTTP (``POST /flow_runs/filter``): the sweep's end does not import Prefect's
    client (seconds) for it."""
    counts: dict[str, int] = {}
    page, offset = 200, 0
    try:
        while True:
            body = {
                "flow_runs": {"tags": {"all_": [tag]}},
                "limit": page,
                "offset": offset,
            }
            request = urllib.request.Request(
                f"{api_url}/flow_runs/filter",
                data=json.dumps(body).encode(),
                headers={"Content-Type": "application/json"},
                method="POST",
            )
            with urllib.request.urlopen(request, timeout=timeout_s) as response:
                runs = json.load(response)
            for run in runs:
                state = run.get("state") or {}
                state_type = str(state.get("type") or run.get("state_type") or "UNKNOWN")
                counts[state_type] = counts.get(state_type, 0) + 1
            if len(runs) < page:
                return counts
            offset += len(runs)
    except Exception:  # the count is part of the summary, never a reason to fail
        return None


# ----------------------------------------------------------------- the watchdog


def watch(owner_pid: int, command: Sequence[str], poll_s: float = 0.2) -> int:
    """Run ``command``; stop it when ``owner_pid`` is gone or when we get SIGTERM/SIGINT."""
    # The child stays in the watchdog's session (one process group to kill) and gets
    # SIGTERM if the watchdog itself is killed.
    child = subprocess.Popen(list(command), preexec_fn=_die_with_parent)
    stopping = False

    def stop(signum: int, frame: object) -> None:
        nonlocal stopping
        stopping = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    while child.poll() is None and not stopping and pid_alive(owner_pid):
        time.sleep(poll_s)
    if child.poll() is None:
        child.terminate()
        try:
            child.wait(timeout=15)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
    return child.returncode or 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m flows.servers",
        description="Run a command until the owner process exits (the sweep's server watchdog).",
    )
    parser.add_argument("--owner", type=int, required=True, help="PID whose exit stops the command")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command given")
    return watch(args.owner, command)


if __name__ == "__main__":
    sys.exit(main())
