"""A bench run's record: the rows it measured and the run they came from, in one JSON file.

Every bench that writes JSON (``--json FILE``, or ``--out FILE`` where a bench had it
before) writes ``{"run": {...}, "rows": [...], ...}``: ``run`` says what ran and where
(the command line, the date, the git commit, the machine, the load average at the start
and at the end), ``rows`` what it measured, one dict per measurement; a bench may add
summary keys of its own. ``tools/results.py`` turns the records in ``docs/bench/`` into
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
    lines.append(f"- command: `{run['command']}`")
    if run.get("converted_from"):  # printed output kept from before records: from_printed
        at = f" at commit `{run['commit']}`" if run.get("commit") else ""
        lines += [
            f"- date: {run['date']} ({run.get('date_from')})",
            f"- made once from its printed output, `{run['converted_from']}`{at} (git "
            "history; `python -m tools.record --from-txt`); the machine was not recorded in it",
        ]
        if run.get("load_end"):
            shown = " / ".join(f"{x:.2f}" for x in run["load_end"])
            lines.append(f"- load average (1 / 5 / 15 min): {shown}, as printed")
        return lines
    lines += [
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


# ------------------------------------------------------------------- printed output

# A bench that prints its results (tables of ``a | b | c`` lines, comment lines, a summary)
# keeps them as a record too: ``rows`` the cells of its ``|`` tables (a dict per line,
# keyed by the table's header), ``blocks`` the printed output in order (a table: its
# columns and which rows; anything else: its lines), so that :func:`printed_page` shows
# what the run printed, its tables as Markdown tables. Live runs write it with
# :func:`capture` (``--json FILE``); printed output kept from before is converted once
# with ``python -m tools.record --from-txt FILE ...`` (:func:`from_printed`).


def _cells(line: str) -> list[str]:
    text = line.strip()
    if text.startswith("|") and text.endswith("|"):
        text = text[1:-1]
    return [cell.strip() for cell in text.split("|")]


def _is_rule(line: str) -> bool:
    return bool(line.strip()) and set(line.replace("|", "").strip()) <= {"-", ":", " "}


def _split(line: str) -> list[tuple[int, int, str]]:
    """A line's cells where two or more spaces part them: (start, end, text)."""
    return [(m.start(), m.end(), m.group()) for m in re.finditer(r"\S+(?: \S+)*", line)]


def _aligned(lines: list[str], i: int) -> tuple[list[str], int, int] | None:
    """A space-aligned table at line ``i`` (a header, an optional ``----`` rule, then at
    least two lines of as many cells): its columns (the header cut at the data columns'
    right edges where its own cells run together), the first data line and the count."""
    header = lines[i]
    if not header.strip() or header.startswith(("#", " ")) or "|" in header:
        return None
    j = i + 1 + int(i + 1 < len(lines) and set(lines[i + 1].strip()) == {"-"})
    count = len(_split(lines[j])) if j < len(lines) else 0
    n = 0
    while j + n < len(lines) and len(_split(lines[j + n])) == count and count >= 3:
        n += 1
    if n < 2:
        return None
    heads = [c[2] for c in _split(header)]
    if len(heads) != count:
        edges = [max(_split(lines[j + k])[c][1] for k in range(n)) for c in range(count)]
        edges[-1] = max(edges[-1], len(header))
        if any(b < len(header) and " " not in header[b - 1 : b + 1] for b in edges[:-1]):
            return None  # a cut through a word: not a table
        heads = [header[a:b].strip() for a, b in zip([0, *edges[:-1]], edges, strict=True)]
    if not all(heads) or any("  " in h or h[0].isdigit() for h in heads):
        return None
    return heads, j, n


def parse_printed(text: str) -> dict[str, Any]:
    """``{"rows": [...], "blocks": [...]}`` of a bench's printed output: a line holding
    ``|`` whose next line holds as many cells (or is a ``---|---`` rule) starts a table,
    which runs while lines hold ``|``; every other line is text."""
    lines = text.rstrip("\n").splitlines()
    rows: list[dict[str, Any]] = []
    blocks: list[dict[str, Any]] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        after = lines[i + 1] if i + 1 < len(lines) else ""
        starts = (
            " | " in line
            and not line.startswith("#")
            and ": " not in line
            and (
                _is_rule(after) or (" | " in after and len(_cells(after)) >= len(_cells(line)) - 1)
            )
        )
        aligned = None if starts else _aligned(lines, i)
        if aligned:
            columns, i, count = aligned
            first = len(rows)
            rows += [dict(zip(columns, (c[2] for c in _split(lines[i + k])), strict=True))
                     for k in range(count)]  # fmt: skip
            blocks.append({"columns": columns, "first": first, "count": count})
            i += count
            continue
        if not starts:
            if blocks and "lines" in blocks[-1]:
                blocks[-1]["lines"].append(line)
            else:
                blocks.append({"lines": [line]})
            i += 1
            continue
        columns = _cells(line)
        i += 2 if _is_rule(after) else 1
        first = len(rows)
        while i < len(lines) and "|" in lines[i] and not lines[i].startswith("#"):
            cells = _cells(lines[i])
            row = dict(zip(columns, cells, strict=False))
            if len(cells) > len(columns):  # a cell holding " | " itself
                row[columns[-1]] = " | ".join(cells[len(columns) - 1 :])
            rows.append(row)
            i += 1
        blocks.append({"columns": columns, "first": first, "count": len(rows) - first})
    return {"rows": rows, "blocks": blocks}


class _Tee:
    def __init__(self, stream: Any, kept: list[str]) -> None:
        self.stream, self.kept = stream, kept

    def write(self, text: str) -> int:
        self.kept.append(text)
        return int(self.stream.write(text))

    def flush(self) -> None:
        self.stream.flush()


class capture:
    """Print as usual and, with a ``path``, write what was printed as a printed-output
    record there at the end (``run``: :func:`started`)."""

    def __init__(self, path: Path | None, title: str = "", **extra: Any) -> None:
        self.path, self.title, self.extra = path, title, extra
        self.run = started()
        self.kept: list[str] = []

    def __enter__(self) -> capture:
        if self.path is not None:
            self.saved = sys.stdout
            sys.stdout = _Tee(sys.stdout, self.kept)  # type: ignore[assignment]
        return self

    def __exit__(self, *exc: object) -> None:
        if self.path is None:
            return
        sys.stdout = self.saved
        if exc[0] is None:
            parsed = parse_printed("".join(self.kept))
            write(self.path, self.run, parsed.pop("rows"), title=self.title, **parsed,
                  **self.extra)  # fmt: skip


def _git_date(path: Path) -> tuple[str | None, str | None]:
    out = _git("log", "-1", "--date=format-local:%Y-%m-%d %H:%M UTC", "--format=%ad %h",
               "--", str(path))  # fmt: skip
    if not out:
        return None, None
    date, _, commit = out.rpartition(" ")
    return date, commit


def from_printed(
    txt: Path,
    command: str,
    title: str = "",
    date: str | None = None,
    load: Sequence[float] | None = None,
    lines: tuple[int, int] | None = None,
) -> dict[str, Any]:
    """A printed-output record made from ``txt``, a bench's output kept as text: the
    ``command`` it names, its ``date`` (default: the date of the commit that last changed
    it, ``git log``), the load it names; the machine was not recorded (``None``);
    ``lines`` (first, last; 1-based, inclusive) keeps one block of a file that appended
    several runs."""
    text = Path(txt).read_text()
    if lines:
        text = "\n".join(text.splitlines()[lines[0] - 1 : lines[1]]) + "\n"
    committed, commit = _git_date(Path(txt))
    try:
        source = Path(txt).resolve().relative_to(REPO).as_posix()
    except ValueError:
        source = str(txt)
    run = {
        "command": command,
        "date": date or committed,
        "date_from": "the printed output" if date else "git log of the printed output",
        "commit": commit,
        "machine": None,
        "load_start": None,
        "load_end": list(load) if load else None,
        "converted_from": source,
    }
    parsed = parse_printed(text)
    return {"run": run, "rows": parsed.pop("rows"), "title": title, **parsed}


def printed_page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """A results page of printed-output records (:func:`parse_printed`): each record's
    title, then what it printed, its tables as Markdown tables and its other lines as a
    text block."""
    lines: list[str] = []
    for data in records:
        rows = data["rows"]
        if data.get("title"):
            lines += [f"## {data['title']}", ""]
        if "blocks" not in data and rows:  # a bench's own rows: a table of their plain values
            columns = [k for k, v in rows[0].items() if not isinstance(v, list | dict)]
            lines += [*table(columns, ([r.get(c) for c in columns] for r in rows)), ""]
            lines += [f"- {' '.join(str(x).split())}" for r in rows for v in r.values()
                      if isinstance(v, list) for x in v]  # fmt: skip
            lines += [""] if lines[-1] else []
        for block in data.get("blocks", []):
            if "columns" in block:
                chosen = rows[block["first"] : block["first"] + block["count"]]
                cells = [
                    [r.get(c, "").replace("|", "\\|") for c in block["columns"]] for r in chosen
                ]
                lines += [*table(block["columns"], cells), ""]
            else:
                text = "\n".join(block["lines"]).strip("\n")
                if text:
                    lines += ["```text", text, "```", ""]
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description="convert a bench's printed output to a record")
    parser.add_argument("--from-txt", type=Path, required=True, help="the printed output")
    parser.add_argument("--json", type=Path, required=True, help="the record to write")
    parser.add_argument("--command", required=True, help="the bench command that printed it")
    parser.add_argument("--title", default="")
    parser.add_argument("--date", help="when it ran, if the output says (else: git log)")
    parser.add_argument("--load", type=float, nargs=3, help="the load average it names")
    parser.add_argument("--lines", type=int, nargs=2, help="first and last line to keep")
    args = parser.parse_args(argv)
    data = from_printed(args.from_txt, args.command, args.title, args.date, args.load,
                        tuple(args.lines) if args.lines else None)  # fmt: skip
    args.json.write_text(json.dumps(data, indent=1) + "\n")
    print(f"{args.json}: {len(data['rows'])} rows from {args.from_txt}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
