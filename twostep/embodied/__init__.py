"""Embodied execution: agents' PDDL plans run asynchronously on a grid kitchen.

:mod:`~twostep.embodied.floorplan` (grid, furniture, location cells),
:mod:`~twostep.embodied.layouts` (real AI2-THOR scenes from the alfworld wheel),
:mod:`~twostep.embodied.navigation` (shortest paths around furniture and agents),
:mod:`~twostep.embodied.executor` (the step-by-step execution and its trace) and
:mod:`~twostep.embodied.render` (GIF and timeline pictures; needs matplotlib) and
:mod:`~twostep.embodied.run` (a finished run executed on its task's floor plan).
"""

from twostep.embodied.executor import (
    EmbodiedError,
    EmbodiedResult,
    EmbodiedStatus,
    Embodiment,
    ExecutorSettings,
    TraceStep,
    embody,
    execute,
    execute_plans,
    failure_line,
)
from twostep.embodied.floorplan import (
    FloorPlan,
    FloorPlanError,
    alfworld_position,
    build_floor_plan,
    floor_plan_from_dict,
    floor_plan_from_locations,
    floor_plan_to_dict,
    load_floor_plan,
)
from twostep.embodied.layouts import OPEN_GRID, find_scene, floor_plan_for_task, scene_floor_plan
from twostep.embodied.run import (
    draws_pictures,
    embodied_failure,
    embodied_fields,
    task_floor_plan,
    write_pictures,
)

__all__ = [
    "OPEN_GRID",
    "EmbodiedError",
    "EmbodiedResult",
    "EmbodiedStatus",
    "Embodiment",
    "ExecutorSettings",
    "FloorPlan",
    "FloorPlanError",
    "TraceStep",
    "alfworld_position",
    "build_floor_plan",
    "draws_pictures",
    "embodied_failure",
    "embodied_fields",
    "embody",
    "execute",
    "execute_plans",
    "failure_line",
    "find_scene",
    "floor_plan_for_task",
    "floor_plan_from_dict",
    "floor_plan_from_locations",
    "floor_plan_to_dict",
    "load_floor_plan",
    "scene_floor_plan",
    "task_floor_plan",
    "write_pictures",
]
