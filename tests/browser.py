"""Headless Chromium for the UI tests: open a page, click through it with a script, read
its text and take a screenshot (the Chrome DevTools Protocol over a websocket).

Debian's ``chromium`` package; :func:`chromium_binary` is None where it is absent (the
tests then skip with a message). Every browser runs with a fresh profile and no network
of its own (no updates, sync or QUIC), and is stopped by its PID.
"""

from __future__ import annotations

import base64
import itertools
import json
import shutil
import subprocess
import time
import urllib.request
from pathlib import Path
from typing import Any

from websockets.sync.client import ClientConnection, connect

from flows.servers import free_port, stop_process

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--remote-allow-origins=*",
)


def chromium_binary() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


class Browser:
    """One headless Chromium with one page."""

    def __init__(self, binary: str, profile: Path, size: tuple[int, int] = (1600, 1000)) -> None:
        port = free_port()
        command = [binary, *FLAGS, f"--user-data-dir={profile}", f"--remote-debugging-port={port}"]
        command += [f"--window-size={size[0]},{size[1]}", "about:blank"]
        self.process = subprocess.Popen(
            command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
        )
        self.ids = itertools.count(1)
        try:
            self.socket = self._connect(port)
            self.call("Page.enable")
            self.call("Runtime.enable")
        except BaseException:
            self.close()
            raise

    def _connect(self, port: int, timeout_s: float = 60.0) -> ClientConnection:
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5) as r:
                    pages = [t for t in json.load(r) if t.get("type") == "page"]
                if pages:
                    return connect(pages[0]["webSocketDebuggerUrl"], max_size=2**26)
            except OSError:
                pass
            if time.monotonic() > deadline or self.process.poll() is not None:
                raise RuntimeError("headless Chromium did not start")
            time.sleep(0.2)

    def call(self, method: str, **params: Any) -> dict[str, Any]:
        """One DevTools command; its result (events in between are skipped)."""
        number = next(self.ids)
        self.socket.send(json.dumps({"id": number, "method": method, "params": params}))
        while True:
            message = json.loads(self.socket.recv(timeout=120))
            if message.get("id") == number:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                result: dict[str, Any] = message.get("result", {})
                return result

    def run(self, script: str) -> Any:
        """The value of a JavaScript expression on the page."""
        answer = self.call("Runtime.evaluate", expression=script, returnByValue=True)
        return answer.get("result", {}).get("value")

    def text(self) -> str:
        return str(self.run("document.body ? document.body.innerText : ''") or "")

    def open(self, url: str) -> None:
        self.call("Page.navigate", url=url)

    def wait_for(self, texts: list[str], timeout_s: float = 90.0, action: str = "") -> str:
        """Poll the page's text until every one of ``texts`` is in it (running ``action``,
        a script, before each look); the text (raises with what is missing on timeout)."""
        deadline = time.monotonic() + timeout_s
        while True:
            if action:
                self.run(action)
            text = self.text()
            missing = [t for t in texts if t not in text]
            if not missing:
                return text
            if time.monotonic() > deadline:
                raise AssertionError(f"not on the page after {timeout_s:.0f} s: {missing}")
            time.sleep(1.0)

    def screenshot(self, path: Path) -> Path:
        data = self.call("Page.captureScreenshot", format="png")["data"]
        path.write_bytes(base64.b64decode(data))
        return path

    def close(self) -> None:
        socket = getattr(self, "socket", None)
        if socket is not None:
            socket.close()
        stop_process(self.process.pid, grace_s=10.0)
        self.process.wait()
