"""The library's command-line tools (``twostep-score``, ``twostep-data``,
``twostep-prompts``), and :func:`console_main`: how every console script of the package
ends when its reader or its user stops it."""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable
from typing import Any, ParamSpec, TypeVar

P = ParamSpec("P")
R = TypeVar("R")

EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports Ctrl-C
EXIT_PIPE_CLOSED = 141  # 128 + SIGPIPE, as a shell reports `... | head`


def console_main(main: Callable[P, R]) -> Callable[P, R]:
    """A console script's ``main``, ended without a traceback when the reader of its output
    goes away (``twostep --help | head``: quietly) or the user presses Ctrl-C (one line)."""

    @functools.wraps(main)
    def run(*args: P.args, **kwargs: P.kwargs) -> R:
        try:
            try:
                return main(*args, **kwargs)
            finally:
                # Flushed here, not at exit: a buffered stdout (a pipe without
                # PYTHONUNBUFFERED) writes its last lines now, where a gone reader is caught.
                sys.stdout.flush()
        except BrokenPipeError:
            # Nothing reads stdout any more: let its last flush at exit go nowhere too.
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            sys.exit(EXIT_PIPE_CLOSED)
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr, flush=True)
            sys.exit(EXIT_INTERRUPTED)

    return run


class ReaderGoneSafe:
    """``sys.stdout`` for a command whose work matters more than its printing (the
    ``twostep`` runs): when the reader goes away (``twostep ... | head -1``), the rest of
    the output goes to ``/dev/null`` and the command goes on, recording every job and
    ending with the exit code of what it did, with no ``BrokenPipeError`` traceback (from
    a ``print``, a log handler or the flush at exit)."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream
        self.reader_gone = False

    def _gone(self) -> None:
        self.reader_gone = True
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), self._stream.fileno())
            self._stream.flush()  # what was buffered goes nowhere, quietly
        except (OSError, ValueError):
            pass

    def write(self, text: str) -> int:
        if not self.reader_gone:
            try:
                return int(self._stream.write(text))
            except BrokenPipeError:
                self._gone()
        return len(text)

    def flush(self) -> None:
        if not self.reader_gone:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self._gone()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)
