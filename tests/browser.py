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
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

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


T = TypeVar("T")


def chromium_binary() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def poll(
    look: Callable[[], T | None], missing: Callable[[], object], timeout_s: float, interval_s: float
) -> T:
    """What ``look`` returns once it returns something (not None), looking again every
    ``interval_s``; after ``timeout_s`` without it, an AssertionError naming what
    ``missing`` says is still not on the page (asked after the last look)."""
    deadline = time.monotonic() + timeout_s
    while (found := look()) is None:
        if time.monotonic() > deadline:
            raise AssertionError(f"not on the page after {timeout_s:.0f} s: {missing()}")
        time.sleep(interval_s)
    return found


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
        last = ""

        def look() -> str | None:
            nonlocal last
            if action:
                self.run(action)
            last = self.text()
            return last if all(t in last for t in texts) else None

        return poll(look, lambda: [t for t in texts if t not in last], timeout_s, 1.0)

    def find(
        self, selector: str, text: str = "", prefix: bool = False, nth: int = 0
    ) -> dict[str, float] | None:
        """The centre of the first (``nth``: the one after ``nth`` others) visible element
        matching the CSS ``selector`` whose text (trimmed) is ``text`` (or starts with it:
        ``prefix``; any text when empty), scrolled into view; None if there is none."""
        script = f"""(() => {{
          const want = {json.dumps(text)}, prefix = {json.dumps(prefix)};
          let skip = {nth};
          for (const e of document.querySelectorAll({json.dumps(selector)})) {{
            const own = (e.innerText || e.value || '').trim();
            if (want && !(prefix ? own.startsWith(want) : own === want)) continue;
            e.scrollIntoView({{block: 'nearest', inline: 'nearest'}});
            const r = e.getBoundingClientRect();
            if (r.width > 0 && r.height > 0 && skip-- === 0)
              return {{x: r.x + r.width / 2, y: r.y + r.height / 2}};
          }}
          return null;
        }})()"""
        found = self.run(script)
        return dict(found) if found else None

    def locate(
        self,
        selector: str,
        text: str = "",
        prefix: bool = False,
        nth: int = 0,
        timeout_s: float = 30.0,
    ) -> tuple[float, float]:
        """:meth:`find`, waiting for the element to appear; its centre (x, y)."""
        where = poll(
            lambda: self.find(selector, text, prefix, nth),
            lambda: f"{selector} {text!r}",
            timeout_s,
            0.5,
        )
        return where["x"], where["y"]

    def click(
        self,
        selector: str,
        text: str = "",
        prefix: bool = False,
        nth: int = 0,
        timeout_s: float = 30.0,
    ) -> None:
        """A real mouse click (move, press and release, as a user's) on the element
        :meth:`locate` finds."""
        x, y = self.locate(selector, text, prefix, nth, timeout_s)
        self._mouse("mouseMoved", x, y)
        self._mouse("mousePressed", x, y)
        self._mouse("mouseReleased", x, y)
        time.sleep(0.5)  # let the page react (menus open, tables re-render)

    def drag(self, selector: str, dx: float, dy: float, nth: int = 0) -> None:
        """Press the mouse on the element, move it by (dx, dy) in steps, release (a
        column's or a card's resize handle)."""
        x, y = self.locate(selector, nth=nth)
        self._mouse("mouseMoved", x, y)
        self._mouse("mousePressed", x, y)
        for step in range(1, 11):
            self._mouse("mouseMoved", x + dx * step / 10, y + dy * step / 10, pressed=True)
        self._mouse("mouseReleased", x + dx, y + dy)
        time.sleep(0.5)

    def _mouse(self, kind: str, x: float, y: float, pressed: bool = False) -> None:
        buttons = {"button": "left", "clickCount": 1} if kind != "mouseMoved" else {}
        if pressed:
            buttons = {"button": "left", "buttons": 1}
        self.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, **buttons)

    def type(self, text: str) -> None:
        """Keystrokes into the focused element (as typed, one character at a time)."""
        for char in text:
            self.call("Input.dispatchKeyEvent", type="keyDown", text=char, key=char)
            self.call("Input.dispatchKeyEvent", type="keyUp", key=char)

    def press(self, key: str, times: int = 1) -> None:
        """A special key on the focused element, ``times`` times: Enter, Escape, Tab,
        Backspace, End (to the end of a text box's text)."""
        code = {"Enter": 13, "Escape": 27, "Tab": 9, "Backspace": 8, "End": 35}[key]
        params: dict[str, Any] = {"key": key, "code": key, "windowsVirtualKeyCode": code}
        for _ in range(times):
            text = {"text": "\r"} if key == "Enter" else {}
            self.call(
                "Input.dispatchKeyEvent", type="keyDown" if text else "rawKeyDown", **text, **params
            )
            self.call("Input.dispatchKeyEvent", type="keyUp", **params)
        time.sleep(0.5)

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
