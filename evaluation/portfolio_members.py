"""Which portfolio members are worth their planning time, replayed from a portfolio's rows
without planning: what plan-deal plus a subset of the members (N agents each) would have
kept (:func:`replay`), and its macro exec/SA and added planning time (:func:`evaluate`).
``bench/bench_portfolio_members.py`` is the command line.
"""

from __future__ import annotations

import statistics
from collections import defaultdict
from collections.abc import Sequence
from typing import Any

PLAN_DEAL = "plan-deal"


def members(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The TwoStep members the rows hold, in their order of appearance."""
    seen: dict[str, None] = {}
    for row in rows:
        for c in row["candidates"]:
            if "dealt_from" not in c and c["decomposer"] != PLAN_DEAL:
                seen.setdefault(c["decomposer"], None)
    return list(seen)


def replay(row: dict[str, Any], subset: Sequence[str]) -> tuple[float, float]:
    """The length a portfolio of plan-deal and ``subset`` (N agents) would have kept for
    one run, and the planning time ``subset`` adds to plan-deal's."""
    candidates = row["candidates"]
    deal = next(c for c in candidates if c["decomposer"] == PLAN_DEAL)
    best, added = float(deal["exec_length"]), 0.0
    for index, c in enumerate(candidates):
        if c["decomposer"] not in subset or c["agents"] != row["agents"]:
            continue
        added += c.get("planning_time_s") or 0.0
        if c.get("exec_length") is not None:
            best = min(best, c["exec_length"])
        source = c.get("same_as", index)
        for again in candidates:
            if again.get("dealt_from") == source and "same_as" not in again:
                added += again.get("planning_time_s") or 0.0
                if again.get("exec_length") is not None:
                    best = min(best, again["exec_length"])
    return best, added


def evaluate(rows: Sequence[dict[str, Any]], agents: int, subset: Sequence[str]) -> dict[str, Any]:
    ratios: dict[str, list[float]] = defaultdict(list)
    times: dict[str, list[float]] = defaultdict(list)
    for row in rows:
        if row["agents"] != agents or not row.get("sa_length"):
            continue
        best, added = replay(row, subset)
        ratios[row["domain"]].append(best / row["sa_length"])
        times[row["domain"]].append(added)
    medians = {d: statistics.median(t) for d, t in times.items()}
    return {
        "macro": statistics.mean(statistics.mean(r) for r in ratios.values()),
        "domains": {d: statistics.mean(r) for d, r in ratios.items()},
        "added_s": max(medians.values()),
        "added_by_domain": medians,
    }
