"""A sweep's results at a glance: one row per (domain, method, N) from the jobs' records
(``.twostep/jobs/*.json``): jobs, successes, mean execution length and mean planning time
of the successful jobs; printed as a table at the end of the sweep and written as
``results.csv`` in the sweep directory. The paper's views (means over seeds, normalised
changes, figures) are ``twostep-report``'s.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

RESULTS_CSV = "results.csv"


@dataclass(frozen=True)
class ResultRow:
    domain: str
    method: str  # twostep jobs: ``twostep (<decomposer>)``
    agents: int | None  # the N the jobs ran (1 for SA)
    jobs: int
    successes: int
    mean_exec_length: float | None  # over successful jobs
    mean_planning_time_s: float | None


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return None if math.isnan(value) else float(value)


def _mean(values: Sequence[float]) -> float | None:
    return sum(values) / len(values) if values else None


def result_rows(records: Sequence[Mapping[str, Any]]) -> list[ResultRow]:
    """One row per (domain, method, N) of the records that say what they ran, sorted."""
    groups: dict[tuple[str, str, int | None], list[Mapping[str, Any]]] = {}
    for record in records:
        if not record.get("domain") or not record.get("method"):
            continue  # a record from before the job knew its task (it failed on input)
        method = str(record["method"])
        if record.get("decomposer"):
            method = f"{method} ({record['decomposer']})"
        agents = record.get("agents")
        key = (str(record["domain"]), method, agents if isinstance(agents, int) else None)
        groups.setdefault(key, []).append(record)
    rows = []
    for (domain, method, agents), group in groups.items():
        solved = [r for r in group if r.get("success") is True]
        lengths = [v for v in (_number(r.get("exec_length")) for r in solved) if v is not None]
        times = [v for v in (_number(r.get("planning_time_s")) for r in solved) if v is not None]
        rows.append(
            ResultRow(domain, method, agents, len(group), len(solved), _mean(lengths), _mean(times))
        )
    return sorted(rows, key=lambda r: (r.domain, r.method, -1 if r.agents is None else r.agents))


def _shown(value: float | None, digits: int) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def format_results(rows: Sequence[ResultRow]) -> str:
    """The rows as an aligned text table (empty without rows)."""
    if not rows:
        return ""
    header = ("domain", "method", "N", "success", "exec length", "planning time (s)")
    body = [
        (
            r.domain,
            r.method,
            "?" if r.agents is None else str(r.agents),
            f"{r.successes}/{r.jobs}",
            _shown(r.mean_exec_length, 1),
            _shown(r.mean_planning_time_s, 2),
        )
        for r in rows
    ]
    widths = [max(len(line[i]) for line in (header, *body)) for i in range(len(header))]
    numeric = {2, 3, 4, 5}

    def line(cells: Sequence[str]) -> str:
        parts = [
            c.rjust(w) if i in numeric else c.ljust(w)
            for i, (c, w) in enumerate(zip(cells, widths, strict=True))
        ]
        return "  ".join(parts).rstrip()

    return "\n".join([line(header), "  ".join("-" * w for w in widths), *map(line, body)])


def write_results_csv(rows: Sequence[ResultRow], path: Path) -> Path:
    """The rows as CSV (empty cells for values that do not exist)."""
    names = [f.name for f in fields(ResultRow)]
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(names)
        for row in rows:
            writer.writerow(["" if getattr(row, n) is None else getattr(row, n) for n in names])
    return path
