"""What a sweep prints: the progress line after each job, its header and its summary."""

from __future__ import annotations

import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from flows.sweep_state import SweepState, job_records


def clock(seconds: float) -> str:
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def progress_line(state: SweepState, now: float | None = None) -> str:
    """``[3/4 done | 0 failed | 1 reused | 0:41 elapsed, ~0:14 left]`` (``now``: the
    time to measure from, default the clock's)."""
    records = job_records(Path(state.sweep_dir))
    done = len(records)
    failed = sum(1 for r in records if r.get("status") == "failed")
    reused = sum(1 for r in records if r.get("reused"))
    elapsed = (time.time() if now is None else now) - state.started_at
    total = state.total_jobs
    parts = [f"{done}/{total if total is not None else '?'} done", f"{failed} failed"]
    if reused:
        parts.append(f"{reused} reused")
    timing = f"{clock(elapsed)} elapsed"
    if total is not None and 0 < done < total:
        # Throughput so far, whatever the parallelism of the launcher.
        timing += f", ~{clock(elapsed / done * (total - done))} left"
    parts.append(timing)
    return "[" + " | ".join(parts) + "]"


def header(state: SweepState) -> str:
    total = state.total_jobs if state.total_jobs is not None else "?"
    parts = [f"sweep: {total} jobs -> {state.sweep_dir}"]
    if state.prefect_api_url:
        parts.append(f"prefect {state.prefect_api_url}")
    elif state.server:
        parts.append("prefect server on demand")
    if state.experiment:
        parts.append(f"mlflow experiment '{state.experiment}'")
    if state.dask_address:
        parts.append(f"dask {state.dask_address}")
    return " | ".join(parts)


def footer(state: SweepState, summary: Mapping[str, Any], failed: list[dict[str, Any]]) -> str:
    lines = [
        f"sweep finished: {summary['jobs_done']}/{summary['jobs_total']} jobs, "
        f"{summary['jobs_failed']} failed, {summary['jobs_timeout']} timed out, "
        f"{summary['jobs_reused']} reused | planner calls: {summary['planner_calls_run']} run, "
        f"{summary['plan_cache_hits']} from cache | {clock(summary['sweep_wall_time_s'])}"
    ]
    for record in failed[:10]:
        lines.append(f"  failed: {record.get('name')}: {record.get('error')}")
    runs = summary.get("prefect_flow_runs")
    if runs is not None:
        shown = ", ".join(f"{n} {s.lower()}" for s, n in sorted(runs.items())) or "none"
        stopped = " (server stopped)" if summary.get("prefect_server_started") else ""
        lines.append(f"prefect: {summary['prefect_api_url']}: flow runs: {shown}{stopped}")
    if state.experiment:
        lines.append(f"mlflow: experiment '{state.experiment}' in {state.tracking_uri}")
    return "\n".join(lines)
