"""Embodied execution: agents' PDDL plans run asynchronously on a grid kitchen.

:mod:`~twostep.embodied.floorplan` (grid, furniture, location cells),
:mod:`~twostep.embodied.navigation` (shortest paths around furniture and agents),
:mod:`~twostep.embodied.executor` (the step-by-step execution and its trace) and
:mod:`~twostep.embodied.render` (GIF and timeline pictures; needs matplotlib).
"""

from twostep.embodied.executor import (
    EmbodiedError,
    EmbodiedResult,
    Embodiment,
    ExecutorSettings,
    TraceStep,
    embody,
    execute,
    execute_plans,
)
from twostep.embodied.floorplan import (
    FloorPlan,
    FloorPlanError,
    alfworld_position,
    build_floor_plan,
    floor_plan_for_task,
    floor_plan_from_dict,
    floor_plan_from_locations,
    load_floor_plan,
)

__all__ = [
    "EmbodiedError",
    "EmbodiedResult",
    "Embodiment",
    "ExecutorSettings",
    "FloorPlan",
    "FloorPlanError",
    "TraceStep",
    "alfworld_position",
    "build_floor_plan",
    "embody",
    "execute",
    "execute_plans",
    "floor_plan_for_task",
    "floor_plan_from_dict",
    "floor_plan_from_locations",
    "load_floor_plan",
]
