"""``twostep-services``: long-lived Prefect and MLflow servers, found by runs, stopped by PID."""

from __future__ import annotations

import json
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from flows import services
from flows.servers import is_healthy, pid_alive
from tests.support.data import make_data

REPO = Path(__file__).resolve().parent.parent


def dead_pid() -> int:
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_stale_record_is_reported_and_removed(tmp_path: Path) -> None:
    pid = dead_pid()
    record = {
        "services": {
            "prefect": {
                "name": "prefect", "url": "http://127.0.0.1:9/api", "pid": pid,
                "log_path": "x.log", "started_at": 0.0,
            }
        }
    }  # fmt: skip
    (tmp_path / "services.json").write_text(json.dumps(record))
    assert services.prefect_api_url(tmp_path) is None  # a run does not use it
    lines, ok = services.status_lines(tmp_path)
    assert not ok
    assert f"prefect: stale record (PID {pid} is not running): removed" in lines
    assert not (tmp_path / "services.json").exists()
    assert services.main(["status", "--root", str(tmp_path)]) == 3  # nothing is up


def test_unreadable_record_means_no_services(tmp_path: Path) -> None:
    (tmp_path / "services.json").write_text("{not json")
    assert services.read_record(tmp_path) == {}
    assert services.prefect_api_url(tmp_path) is None


@pytest.mark.integration
def test_up_status_run_down_round_trip(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    root = tmp_path / "out"
    start = time.perf_counter()
    try:
        assert services.main(["up", "--root", str(root), "--timeout", "120"]) == 0
        print(f"services up in {time.perf_counter() - start:.1f} s", file=sys.stderr)
        record = services.read_record(root)
        assert set(record) == {"prefect", "mlflow"}
        prefect, mlflow = record["prefect"], record["mlflow"]
        assert prefect.url.startswith("http://127.0.0.1:") and prefect.url.endswith("/api")
        assert is_healthy(prefect.url) and is_healthy(mlflow.url)
        with urllib.request.urlopen(f"{mlflow.url}/version", timeout=10) as response:
            assert response.status == 200  # the MLflow server itself, not just a port
        lines, ok = services.status_lines(root)
        assert ok and f"prefect: up at {prefect.url} (PID {prefect.pid})" in lines
        # The UI asks /ui-settings where the API is: this server's port, not Prefect's 4200.
        base = prefect.url.removesuffix("/api")
        with urllib.request.urlopen(f"{base}/ui-settings", timeout=10) as response:
            assert json.load(response)["api_url"] == prefect.url
        assert (
            f"prefect UI: {base}/runs" in lines
            and f"mlflow UI: {mlflow.url}/#/experiments?workflowType=machine_learning" in lines
        )

        # `up` again starts nothing new.
        assert services.main(["up", "--root", str(root)]) == 0
        assert services.read_record(root) == record

        # A single run with the default orchestration.prefect (auto) uses the warm server.
        data = make_data(tmp_path / "data")
        done = subprocess.run(
            [sys.executable, "-m", "flows.cli", f"data.root={data}", f"output.root={root}",
             "domain=blocksworld", "task=1", "method=sa", "mlflow.enabled=false"],
            capture_output=True, text=True, cwd=REPO, timeout=240,
        )  # fmt: skip
        assert done.returncode == 0, done.stdout + done.stderr
        (result,) = root.glob("runs/*/*/result.json")
        assert json.loads(result.read_text())["orchestration"]["prefect"] is True
    finally:
        capsys.readouterr()
        services.main(["down", "--root", str(root)])
    out = capsys.readouterr().out
    assert f"prefect: stopped (PID {prefect.pid})" in out
    assert f"mlflow: stopped (PID {mlflow.pid})" in out
    deadline = time.monotonic() + 10
    while (pid_alive(prefect.pid) or pid_alive(mlflow.pid)) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not pid_alive(prefect.pid) and not pid_alive(mlflow.pid)
    assert not is_healthy(prefect.url) and not is_healthy(mlflow.url)
    assert not (root / "services.json").exists()
    print(f"round trip {time.perf_counter() - start:.1f} s", file=sys.stderr)


def test_two_servers_started_back_to_back_get_different_ports(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # `twostep-services` asks a port for Prefect, then one for MLflow, before either server
    # has bound its own; the system may offer the same free port twice (it did: MLflow took
    # the port and Prefect stopped with "address already in use"). A system that offers
    # 41001 twice, then 41002: the second server is given 41002.
    from flows import servers

    offered = iter([41001, 41001, 41002])

    class System:
        def __init__(self, *args: object) -> None:
            self.port = 0

        def __enter__(self) -> System:
            return self

        def __exit__(self, *args: object) -> None:
            pass

        def bind(self, address: tuple[str, int]) -> None:
            assert address[1] == 0  # the system chooses
            self.port = next(offered)

        def getsockname(self) -> tuple[str, int]:
            return ("127.0.0.1", self.port)

    monkeypatch.setattr(servers, "_HANDED_OUT", set(), raising=False)
    monkeypatch.setattr(servers.socket, "socket", System)
    assert [servers.free_port(), servers.free_port()] == [41001, 41002]
