"""How a job ended, read from its result: :class:`JobStatus` and the one-line reason (the
``twostep.status`` and ``twostep.error`` tags, the sweep's job records, the Prefect flow
run's final state)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from twostep.util.outcome import JobStatus as JobStatus
from twostep.util.outcome import limit_reached


def job_status(result: Mapping[str, Any]) -> tuple[JobStatus, str | None]:
    """``twostep.status`` and ``twostep.error`` of a result.json dict."""
    if result.get("success"):
        return JobStatus.SUCCESS, None
    if limit_reached(result.get("status")):
        return JobStatus.TIMEOUT, result.get("message") or "planner time limit"
    message = (
        result.get("error") or result.get("message") or result.get("status") or JobStatus.FAILED
    )
    return JobStatus.FAILED, " ".join(str(message).split())[:500]


def reason_line(kind: str, reason: str) -> str:
    """``kind: reason`` (the console's summary, the Prefect state's message); a reason that
    names its kind already (an embodied verdict, ``embodied_failed: boxed_in at step 12,
    agent1``) alone."""
    return reason if reason.startswith(f"{kind}:") else f"{kind}: {reason}"
