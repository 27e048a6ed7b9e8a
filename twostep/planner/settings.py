"""How the planner is called: alias, time and memory limits, and the wall-clock guard."""

from __future__ import annotations

from dataclasses import dataclass

# The search time limit is CPU time of the search component alone: the planner's own limit,
# which decides a timeout (its exit code). The translator, the driver's own start-up and a
# loaded machine add wall time on top: with five jobs on two cores a search gets about a
# third of a core, so 20 s of CPU take about a minute. The guard is a safety net against a
# planner that hangs: it allows for that load before it kills the whole process group.
WALL_GUARD_FACTOR = 4.0
WALL_GUARD_OFFSET_S = 60.0


@dataclass(frozen=True)
class PlannerSettings:
    alias: str = "lama-first"
    search_time_limit_s: float = 60.0  # CPU time of the search component
    wall_time_limit_s: float | None = None  # guard on the whole call; default: derived
    memory_limit_mb: int | None = None

    def wall_guard(self) -> float:
        """Seconds of wall time after which the planner is stopped."""
        if self.wall_time_limit_s is not None:
            return self.wall_time_limit_s
        return self.search_time_limit_s * WALL_GUARD_FACTOR + WALL_GUARD_OFFSET_S

    def with_time_limit(self, seconds: float) -> PlannerSettings:
        return PlannerSettings(self.alias, seconds, None, self.memory_limit_mb)
