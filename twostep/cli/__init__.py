"""The library's command-line tools (``twostep-score``, ``twostep-data``,
``twostep-prompts``), and :func:`console_main`: how every console script of the package
ends when its reader or its user stops it."""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable
from typing import ParamSpec, TypeVar

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
