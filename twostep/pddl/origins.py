"""Plans in the task's own terms: the identity, since the model is the task itself.

Plans, schedules and results always name the task's own actions (the grounded model is
Fast Downward's grounding of the task's own files, with no compiled variants). These two
functions remain for callers that still map plans through a domain's (empty) origins.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping


def original_action(origins: Mapping[str, object], action: str) -> str | None:
    """``action`` itself: a plan step is already in the task's own terms."""
    return action


def original_plan(origins: Mapping[str, object], plan: Iterable[str]) -> list[str]:
    """``plan`` itself, as a list."""
    return list(plan)
