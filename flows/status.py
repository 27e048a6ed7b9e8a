"""How a job ended, read from its result: :class:`JobStatus` and the one-line reason (the
``twostep.status`` and ``twostep.error`` tags, the sweep's job records, the Prefect flow
run's final state)."""

from __future__ import annotations

from collections.abc import Mapping
from enum import StrEnum
from typing import Any


class JobStatus(StrEnum):
    """How a job ended (the ``twostep.status`` tag, the sweep's job records)."""

    SUCCESS = "success"
    FAILED = "failed"
    TIMEOUT = "timeout"


def job_status(result: Mapping[str, Any]) -> tuple[JobStatus, str | None]:
    """``twostep.status`` and ``twostep.error`` of a result.json dict."""
    if result.get("success"):
        return JobStatus.SUCCESS, None
    if result.get("status") == "timeout":
        return JobStatus.TIMEOUT, result.get("message") or "planner time limit"
    message = result.get("error") or result.get("message") or result.get("status") or "failed"
    return JobStatus.FAILED, " ".join(str(message).split())[:500]


def reason_line(kind: str, reason: str) -> str:
    """``kind: reason`` (the console's summary, the Prefect state's message); a reason that
    names its kind already (an embodied verdict, ``embodied_failed: boxed_in at step 12,
    agent1``) alone."""
    return reason if reason.startswith(f"{kind}:") else f"{kind}: {reason}"
