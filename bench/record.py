"""A bench run's record: the rows it measured and the run they came from, in one JSON file.

Every bench that writes JSON (``--json FILE``, or ``--out FILE`` where a bench had it
before) writes ``{"run": {...}, "rows": [...], ...}``: ``run`` says what ran and where
(the command line, the date, the git commit, the machine, the load average at the start
and at the end), ``rows`` what it measured, one dict per measurement; a bench may add
summary keys of its own. ``bench/results.py`` turns the records in ``docs/bench/`` into
the site's results pages. Rows files written before records existed (a bare JSON list)
still load, with no ``run``.

Helpers for the pages: :func:`table` (a Markdown table), :func:`run_lines` (the run's
header lines), :func:`svg` (a matplotlib figure saved as SVG that is the same bytes for
the same data: no date, fixed ids).
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import re
import shlex
import subprocess
import sys
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent


def _command(argv: Sequence[str]) -> str:
    script = Path(argv[0]).resolve() if argv else Path("?")
    try:
        shown = script.relative_to(REPO).as_posix()
    except ValueError:
        shown = argv[0] if argv else "?"
    return shlex.join(["python", shown, *argv[1:]])


def _git(*args: str) -> str:
    try:
        done = subprocess.run(["git", *args], cwd=REPO, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return done.stdout.strip() if done.returncode == 0 else ""


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _memory_gb() -> float | None:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                return round(int(line.split()[1]) / 1024**2, 1)
    except OSError:
        pass
    return None


def machine() -> dict[str, Any]:
    """What the run ran on: cores, CPU, memory, system, Python."""
    return {
        "cpus": os.cpu_count(),
        "cpu": _cpu_model(),
        "memory_gb": _memory_gb(),
        "system": platform.platform(terse=True),
        "python": platform.python_version(),
    }


def load_average() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


def started(argv: Sequence[str] | None = None) -> dict[str, Any]:
    """The ``run`` part of a record, at the start of a run: the command (``argv``, default
    this process's), the UTC date, the commit (``+modified`` when tracked files differ
    from it), the machine and the load average (1, 5, 15 minutes)."""
    commit = _git("rev-parse", "--short=10", "HEAD")
    if commit and _git("status", "--porcelain", "--untracked-files=no"):
        commit += "+modified"
    return {
        "command": _command(list(sys.argv if argv is None else argv)),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": commit or None,
        "machine": machine(),
        "load_start": load_average(),
    }


def write(path: Path, run: Mapping[str, Any], rows: Iterable[Any], **extra: Any) -> None:
    """The record to ``path`` (atomically), with the load average at the end added."""
    record = {"run": {**run, "load_end": load_average()}, "rows": list(rows), **extra}
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(record, indent=1, default=str) + "\n")
    tmp.replace(path)


def load(path: Path) -> dict[str, Any]:
    """A record: ``{"run": ... or None, "rows": [...], ...}``, from a record or a bare
    list of rows."""
    data = json.loads(Path(path).read_text())
    if isinstance(data, list):
        return {"run": None, "rows": data}
    return {"run": data.get("run"), **{k: v for k, v in data.items() if k != "run"}}


def rows_of(path: Path) -> list[dict[str, Any]]:
    return list(load(path)["rows"])


# ------------------------------------------------------------------------------ pages


def table(head: Sequence[str], rows: Iterable[Sequence[Any]]) -> list[str]:
    """A Markdown table."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join("" if c is None else str(c) for c in row) + " |" for row in rows]
    return lines


def printed_commands(printed: Path) -> list[str]:
    """The bench command lines a bench's printed output starts its runs with (``# bench/...``
    comment lines, as the methods bench prints them), in order, each once."""
    if not printed.is_file():
        return []
    found = [
        re.split(r"\s{2,}[(#]", line.removeprefix("# ").removeprefix("python "))[0].strip()
        for line in printed.read_text().splitlines()
        if line.startswith(("# bench/", "# python bench/"))
    ]  # fmt: skip (a trailing remark cut)
    return [f"python {c}" for c in dict.fromkeys(found)]


def run_lines(run: Mapping[str, Any] | None, source: str, printed: Path | None = None) -> list[str]:
    """The header of a results page: which rows, which command, when, at which commit, on
    what machine and at what load. Rows written before bench records have none of it: the
    commands their printed output (``printed``) names stand in for the command."""
    lines = [f"- rows: [`{source}`](../bench/{Path(source).name})"]
    if not run:
        lines.append(
            "- run: date, machine and load not recorded in the rows (written before bench records)"
        )
        commands = printed_commands(printed) if printed else []
        if commands and printed is not None:
            lines.append(f"- commands printed in [`{printed.name}`](../bench/{printed.name}):")
            lines += [f"    - `{c}`" for c in commands]
        return lines
    m = run.get("machine") or {}
    memory = f", {m['memory_gb']:g} GB" if m.get("memory_gb") else ""
    lines += [
        f"- command: `{run['command']}`",
        f"- date: {run['date']}" + (f", commit `{run['commit']}`" if run.get("commit") else ""),
        f"- machine: {m.get('cpus')} cores ({m.get('cpu')}){memory}, {m.get('system')}, "
        f"Python {m.get('python')}",
    ]
    start, end = run.get("load_start"), run.get("load_end")
    if start:
        load = (
            f"- load average (1 / 5 / 15 min): {' / '.join(f'{x:.2f}' for x in start)} at the start"
        )
        if end:
            load += f", {' / '.join(f'{x:.2f}' for x in end)} at the end"
        lines.append(load + f" (on {m.get('cpus')} cores)")
    return lines


def svg(figure: Any, path: Path) -> Path:
    """``figure`` as SVG at ``path``, the same bytes for the same figure (no date in the
    metadata, ids from a fixed salt)."""
    import matplotlib

    path.parent.mkdir(parents=True, exist_ok=True)
    with matplotlib.rc_context({"svg.hashsalt": "twostep", "svg.fonttype": "none"}):
        figure.savefig(path, format="svg", metadata={"Date": None})
    return path
