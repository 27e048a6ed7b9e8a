"""A stand-in for an OpenAI-compatible chat server on 127.0.0.1, with injectable faults.

Tests and ``bench/bench_faults.py`` point ``llm.api_base`` at it, so the real litellm HTTP
path runs offline. Each request takes the next reply from a script; a reply is answer
text, or a fault: an HTTP status (429 rate limit, 500/503 server error, 401 auth), a
delay longer than the client's timeout, or a closed connection. Answers here are written
by the tests: they are never a model's.
"""

from __future__ import annotations

import json
import threading
import time
from collections import deque
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any


@dataclass(frozen=True)
class Fault:
    """``status``: answer with this HTTP status; ``delay_s``: sleep first; ``close``: hang up."""

    status: int | None = None
    delay_s: float = 0.0
    close: bool = False


Reply = str | Fault


@dataclass
class StandIn:
    """The server's script and what it saw (thread-safe enough for one test at a time)."""

    replies: deque[Reply] = field(default_factory=deque)
    default: Reply = "none"
    requests: list[dict[str, Any]] = field(default_factory=list)
    authorizations: list[str] = field(default_factory=list)
    address: str = ""
    lock: threading.Lock = field(default_factory=threading.Lock)

    @property
    def api_base(self) -> str:
        return f"{self.address}/v1"

    def script(self, replies: Iterable[Reply]) -> None:
        with self.lock:
            self.replies.extend(replies)

    def next_reply(self, request: dict[str, Any], authorization: str) -> Reply:
        with self.lock:
            self.requests.append(request)
            self.authorizations.append(authorization)
            return self.replies.popleft() if self.replies else self.default


def _completion(model: str, text: str) -> bytes:
    body = {
        "id": "chatcmpl-standin",
        "object": "chat.completion",
        "created": int(time.time()),
        "model": model,
        "choices": [
            {
                "index": 0,
                "message": {"role": "assistant", "content": text},
                "finish_reason": "stop",
            }
        ],
        "usage": {"prompt_tokens": 1, "completion_tokens": 1, "total_tokens": 2},
    }
    return json.dumps(body).encode()


def _handler(state: StandIn) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args: Any) -> None:  # keep test output clean
            pass

        def do_POST(self) -> None:
            length = int(self.headers.get("Content-Length") or 0)
            request = json.loads(self.rfile.read(length) or b"{}")
            reply = state.next_reply(request, self.headers.get("Authorization", ""))
            if isinstance(reply, Fault):
                if reply.delay_s:
                    time.sleep(reply.delay_s)
                if reply.close:
                    self.close_connection = True
                    return
                if reply.status is not None:
                    payload = json.dumps({"error": {"message": "injected fault"}}).encode()
                    self.send_response(reply.status)
                    self.send_header("Content-Type", "application/json")
                    self.send_header("Content-Length", str(len(payload)))
                    self.end_headers()
                    self.wfile.write(payload)
                    return
                reply = state.default
            payload = _completion(str(request.get("model", "standin")), str(reply))
            self.send_response(200)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(payload)))
            self.end_headers()
            self.wfile.write(payload)

    return Handler


@contextmanager
def standin_server(replies: Iterable[Reply] = (), default: Reply = "none") -> Iterator[StandIn]:
    """Serve on 127.0.0.1 (a free port) for the duration of the ``with`` block."""
    state = StandIn(deque(replies), default)
    server = ThreadingHTTPServer(("127.0.0.1", 0), _handler(state))
    server.daemon_threads = True
    host, port = server.server_address[:2]
    state.address = f"http://{host!s}:{port}"
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield state
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)
