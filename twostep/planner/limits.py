"""Which of a result.json's planner calls a time limit stopped: the planner's own limit
(its exit code) or the wall-clock guard (a safety net that comes first only on a machine
too loaded for the limit).

The reports' Table II reads a run with a call the planner's limit stopped as ``timeout``
and leaves guard stops out of its planning time; the MLflow record logs both counts. Only
the exit codes are read here, so a single run's logging imports nothing of the reports.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from twostep.planner import returncodes
from twostep.util.outcome import limit_reached

#: Exit codes of a planner call stopped by its time limit (with or without a plan).
LIMIT_CODES: frozenset[int] = returncodes.OUT_OF_TIME | {
    returncodes.SEARCH_PLAN_FOUND_AND_OUT_OF_TIME,
    returncodes.SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY_AND_TIME,
}


def _calls(result: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    return [c for c in result.get("planner_calls") or [] if isinstance(c, Mapping)]


def _guard_stopped(call: Mapping[str, Any]) -> bool:
    """A call the wall-clock guard stopped (results before the flag: no exit code and the
    guard's message)."""
    if "guard_stopped" in call:
        return bool(call["guard_stopped"])
    return call.get("exit_code") is None and "wall-clock guard" in str(call.get("message") or "")


def planner_limit_hits(result: Mapping[str, Any]) -> int:
    """How many of a result.json's planner calls the planner's own time limit stopped
    (its exit code; a call the wall-clock guard stopped is not one: :func:`guard_stops`)."""
    hits = 0
    for call in _calls(result):
        code = call.get("exit_code")
        if not _guard_stopped(call) and (
            (isinstance(code, int) and code in LIMIT_CODES) or limit_reached(call.get("status"))
        ):
            hits += 1
    if not hits and limit_reached(result.get("status")) and not guard_stops(result):
        hits = 1
    return hits


def guard_stops(result: Mapping[str, Any]) -> int:
    """How many of a result.json's planner calls the wall-clock guard stopped."""
    return sum(1 for call in _calls(result) if _guard_stopped(call))
