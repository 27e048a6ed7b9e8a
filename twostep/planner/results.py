"""What a planner call returns: a :class:`Status` that says exactly what happened, and the plan.

"Proven unsolvable" and "search incomplete" are different answers: the first says no plan
exists; the second only that this (incomplete) search found none.
"""

from __future__ import annotations

from dataclasses import dataclass

from twostep.programs.processes import LimitReached
from twostep.util.outcome import PlannerStatus

Status = PlannerStatus  # the outcome vocabulary's planner statuses (twostep.util.outcome)


@dataclass(frozen=True)
class PlanResult:
    """One planner call's outcome. A timeout, an unsolvable task or a crash is a status.

    ``cost`` is the plan's cost as the plan file's trailer states it: the sum of the
    action costs in a domain with ``:action-costs``, else the number of actions. Left
    unset with a plan, it is the number of actions (unit cost).
    """

    status: Status
    plan: tuple[str, ...] | None
    planner_time_s: float  # the driver's reported planner time (wall time if killed)
    wall_time_s: float
    message: str = ""
    exit_code: int | None = None
    plans_found: int = 0
    cost: int | None = None
    # The wall-clock guard stopped the planner (a safety net, not the planner's own time
    # limit: on a machine that gives the search too little CPU the guard can come first).
    guard_stopped: bool = False
    # The resource limit that ended the call (its message says so), or None.
    limit: LimitReached | None = None

    def __post_init__(self) -> None:
        if self.cost is None and self.plan is not None:
            object.__setattr__(self, "cost", len(self.plan))

    @property
    def solved(self) -> bool:
        return self.status is Status.SOLVED

    def to_dict(self) -> dict[str, object]:
        return {
            "status": self.status.value,
            "plan": list(self.plan) if self.plan is not None else None,
            "cost": self.cost,
            "planner_time_s": round(self.planner_time_s, 4),
            "wall_time_s": round(self.wall_time_s, 4),
            "message": self.message,
            "exit_code": self.exit_code,
            "plans_found": self.plans_found,
            "guard_stopped": self.guard_stopped,
        }
