"""The results page of the rows ``bench/bench_faults.py`` writes (``make results``:
:mod:`tools.results`), and the rows' columns the bench prints.
"""

from __future__ import annotations

import contextlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tools import record as bench_record


@dataclass
class Row:
    """One scenario's line of the table (None: not measured there)."""

    scenario: str
    jobs: int
    completed: int
    recomputed: int | None = None
    runs: int | None = None
    duplicates: int | None = None
    missing: int | None = None
    stored_failures: int | None = None
    tracebacks: int = 0
    notes: list[str] = field(default_factory=list)


def records(out: Path) -> list[dict[str, Any]]:
    found = []
    for path in sorted(out.glob("multiruns/*/*/.twostep/jobs/*.json")):
        with contextlib.suppress(OSError, ValueError):  # a record being written
            found.append(json.loads(path.read_text()))
    return found


COLUMNS = ("jobs", "completed", "recomputed", "MLflow runs", "duplicates", "missing",
           "stored failures", "tracebacks")  # fmt: skip


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of a ``--json`` record (tools.results)."""
    data, *printed = records  # the later ones: runs of some scenarios, kept as printed
    rows = [Row(**r) for r in data["rows"]]
    settings = data.get("settings", {})
    lines = [
        "## Records after each mishap",
        "",
        "One row per scenario, each in an output root of its own; the columns come from the "
        "sweeps' job records, the job store and the MLflow store (read with MLflow's own "
        f"client). llm-faults: {settings.get('jobs')} jobs through a stand-in LLM server "
        f"that fails at random ({settings.get('fault_rate')} per fault kind), killed with "
        f"SIGKILL {settings.get('kills')} times, then run to the end (seed "
        f"{settings.get('seed')}).",
        "",
        "| " + " | ".join(["scenario", *COLUMNS]) + " |",
        "|" + "---|" * (len(COLUMNS) + 1),
    ]
    for row in rows:
        cells = [row.jobs, row.completed, row.recomputed, row.runs, row.duplicates, row.missing,
                 row.stored_failures, row.tracebacks]  # fmt: skip
        lines.append(
            f"| {row.scenario} | " + " | ".join("-" if c is None else str(c) for c in cells) + " |"
        )
    lines += [
        "",
        "Goals: recomputed, duplicates, missing, stored failures and tracebacks all 0. "
        "Bad-files: cases answered with one line naming the file (or read as the file "
        "without its byte-order mark).",
        "",
        "## What each scenario printed",
        "",
        *(f"- {' '.join(note.split())}" for row in rows for note in row.notes),  # one line each
        "",
    ]
    return lines + bench_record.printed_page(printed, figure)
