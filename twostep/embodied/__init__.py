"""Embodied execution: agents' PDDL plans run asynchronously on a grid kitchen.

:mod:`~twostep.embodied.floorplan` (grid, furniture, location cells),
:mod:`~twostep.embodied.navigation` (shortest paths around furniture and agents),
:mod:`~twostep.embodied.executor` (the step-by-step execution and its trace) and
:mod:`~twostep.embodied.render` (GIF and timeline pictures; needs matplotlib) and
:mod:`~twostep.embodied.run` (a finished run executed on its task's floor plan).
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
from twostep.embodied.run import (
    embodied_fields,
    task_floor_plan,
    write_pictures,
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
    "embodied_fields",
    "embody",
    "execute",
    "execute_plans",
    "floor_plan_for_task",
    "floor_plan_from_dict",
    "floor_plan_from_locations",
    "load_floor_plan",
    "task_floor_plan",
    "write_pictures",
]
