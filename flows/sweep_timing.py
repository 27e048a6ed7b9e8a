"""Where a sweep's time went, at its end: its wall time, its planner's (and LLM's) time
summed over the jobs, and the share of the workers' time that went to neither (the
orchestration: Hydra, Prefect, MLflow, the job store, waits).

    time: 0:53 wall, 2 workers | planner 3.5 s, LLM 0.0 s over 12 jobs | beyond them 8.4 s per job (92 % of the workers' time)

``bench/bench_sweep.py`` measures the same per job; this line is what every sweep (the
paper's grid too) reports about itself.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from flows.console import clock


def sweep_timing(records: Sequence[Mapping[str, Any]], wall_s: float) -> dict[str, Any]:
    """``{"timing": ...}`` for the sweep's summary: wall time, planner and LLM time summed
    over the jobs' fresh calls, worker processes (those that ran a job), and what is left
    of the workers' time per job and as a share."""
    planner = sum(float(r.get("planner_wall_s") or 0.0) for r in records)
    llm = sum(float(r.get("llm_wall_s") or 0.0) for r in records)
    workers = {(r.get("launch") or {}).get("worker") for r in records} - {None}
    count = max(1, len(workers))
    busy = wall_s * count
    beyond = max(0.0, busy - planner - llm)
    return {
        "timing": {
            "wall_s": round(wall_s, 3),
            "workers": count,
            "jobs": len(records),
            "planner_s": round(planner, 3),
            "llm_s": round(llm, 3),
            "beyond_per_job_s": round(beyond / len(records), 3) if records else None,
            "overhead_share": round(beyond / busy, 4) if busy > 0 else None,
        }
    }


def timing_line(summary: Mapping[str, Any]) -> str:
    """The summary's timing as one line (:func:`sweep_timing`)."""
    t = summary.get("timing") or {}
    if not t.get("jobs"):
        return f"time: {clock(float(t.get('wall_s') or 0.0))} wall, no job ran"
    workers = int(t["workers"])
    share = t.get("overhead_share")
    return (
        f"time: {clock(float(t['wall_s']))} wall, {workers} worker{'s' if workers != 1 else ''}"
        f" | planner {float(t['planner_s']):.1f} s, LLM {float(t['llm_s']):.1f} s over "
        f"{t['jobs']} jobs | beyond them {float(t['beyond_per_job_s']):.2f} s per job"
        + (f" ({100 * float(share):.0f} % of the workers' time)" if share is not None else "")
    )
