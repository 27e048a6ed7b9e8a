"""The guard between twostep and one of Fast Downward's programs (run by path, standard
library only: it imports nothing of twostep, so it starts in milliseconds).

    python -I -S _guard.py PARENT_PID WORKDIR MEMORY_BYTES CPU_SECONDS -- COMMAND ...

(WORKDIR "": no folder to remove.)

It runs COMMAND in a process group of its own, under an address-space limit of
MEMORY_BYTES and a CPU-time limit of CPU_SECONDS (0: none; the soft CPU limit sends
SIGXCPU, which Fast Downward's translator answers with its exit code 21, and a second
later the hard limit kills). Its exit code is the command's, or 128 + the signal that
ended it.

It ends the command's whole group (the driver's translator and search included) and
removes WORKDIR when twostep is gone: the kernel sends it SIGTERM when its parent dies
(``PR_SET_PDEATHSIG``, even after a ``kill -9``), and a SIGTERM, SIGINT or SIGHUP from
anyone else does the same. The command itself gets SIGKILL if the guard dies.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import resource
import shutil
import signal
import subprocess
import sys
import time

PR_SET_PDEATHSIG = 1


def _prctl_death_signal(signum: int) -> None:
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signum)


def main(argv: list[str]) -> int:
    parent, workdir, memory, cpu = int(argv[0]), argv[1], int(argv[2]), int(argv[3])
    command = argv[argv.index("--") + 1 :]
    child: subprocess.Popen[bytes] | None = None

    def stop(signum: int, frame: object) -> None:
        # A signal handler: Popen.wait() may be what it interrupted (holding its lock), so
        # the child is reaped with os.waitpid, and the group waited for by polling it.
        if child is not None:
            with contextlib.suppress(OSError):
                os.killpg(child.pid, signal.SIGKILL)
            with contextlib.suppress(OSError):
                os.waitpid(child.pid, 0)
            for _ in range(200):  # the rest of the group (the driver's children), <= 2 s
                try:
                    os.killpg(child.pid, 0)
                except OSError:
                    break
                time.sleep(0.01)
        if workdir:
            shutil.rmtree(workdir, ignore_errors=True)
        os._exit(128 + signum)

    for signum in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(signum, stop)
    _prctl_death_signal(signal.SIGTERM)
    if os.getppid() != parent:  # twostep died before the death signal was set
        stop(signal.SIGTERM, None)

    def limit() -> None:  # in the child, before it runs COMMAND (the guard has no threads)
        if memory > 0:
            resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
        if cpu > 0:
            resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 1))
        _prctl_death_signal(signal.SIGKILL)

    child = subprocess.Popen(command, preexec_fn=limit, start_new_session=True)
    while True:
        try:
            code = child.wait()
            break
        except InterruptedError:  # pragma: no cover - PEP 475 retries wait() itself
            continue
    return code if code >= 0 else 128 - code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
