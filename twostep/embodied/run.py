"""A finished run and its floor plan: what the orchestration needs around the executor.

:func:`task_floor_plan` finds the floor plan of a task (its folder's ``kitchen.yaml``, else
the AlfWorld location names' coordinates); :func:`~twostep.embodied.executor.execute_plans`
executes a run's plans (in hand-off order) on it; :func:`embodied_fields` is what result.json gains (the trace and
the floor plan ride along under ``embodied_trace`` for the job's files, which
:func:`write_pictures` draws from the result dict alone, so a reused result can be drawn
again without re-executing; :func:`draws_pictures` says which jobs draw).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from twostep.embodied.executor import (
    LOCATION_TYPE,
    EmbodiedResult,
    TraceStep,
    failure_line,
)
from twostep.embodied.floorplan import FloorPlan, floor_plan_from_dict, floor_plan_to_dict
from twostep.embodied.layouts import floor_plan_for_task
from twostep.embodied.scene import Scene
from twostep.pddl import Problem

RECEPTACLE_TYPE = "receptacle"
TRACE_KEY = "embodied_trace"  # result dict key of the trace + floor plan (not in result.json)


def task_floor_plan(
    problem: Problem, folder: str | Path | None, layout: str | None = None
) -> FloorPlan:
    """The floor plan of ``problem`` whose files live in ``folder`` (``layout``: see
    :func:`~twostep.embodied.layouts.floor_plan_for_task`)."""

    def of_type(kind: str) -> list[str]:
        objects = problem.all_objects.items()
        return [name for name, t in objects if problem.domain.is_subtype(t, kind)]

    return floor_plan_for_task(
        of_type(LOCATION_TYPE), folder, layout, of_type(RECEPTACLE_TYPE), problem.name
    )


def embodied_fields(result: EmbodiedResult, floor_plan: FloorPlan) -> dict[str, Any]:
    """The fields a run's result dict gains from its embodied execution."""
    return {
        "executor": "embodied",
        "embodied_status": result.status,
        "embodied_length": result.embodied_length,
        "waits": result.waits,
        "backoffs": result.backoffs,
        "embodied": result.to_dict(),  # status, agent/step/reason of a failure, starts
        TRACE_KEY: {
            "status": result.status,
            "embodied_length": result.embodied_length,
            "start_positions": {a: list(c) for a, c in result.start_positions.items()},
            "scene": result.scene.to_dict(),
            "floor_plan": floor_plan_to_dict(floor_plan),
            "trace": [step.to_dict() for step in result.trace],
        },
    }


def embodied_failure(fields: Mapping[str, Any]) -> str | None:
    """None when a result's embodied execution succeeded (or there was none), else its
    one-line verdict (``embodied_failed: boxed_in at step 12, agent1``): what a run's
    success, exit code and stored status follow."""
    summary = fields.get("embodied")
    if fields.get("executor") != "embodied" or not isinstance(summary, Mapping):
        return None
    return failure_line(str(summary.get("status")), summary.get("step"), summary.get("agent"))


def result_from_fields(fields: Mapping[str, Any]) -> tuple[EmbodiedResult, FloorPlan]:
    """The execution and floor plan back from :func:`embodied_fields` (to draw them)."""
    summary = fields["embodied"]
    recorded = fields[TRACE_KEY]
    trace = [
        TraceStep(
            step=int(t["step"]),
            agent=str(t["agent"]),
            primitive=str(t["primitive"]),
            position=(int(t["position"][0]), int(t["position"][1])),
            action=t.get("action"),
            applied=t.get("applied"),
            holding=tuple(t.get("holding") or ()),
            reason=t.get("reason"),
            scene=Scene.from_dict(t["scene"]) if t.get("scene") else None,
        )
        for t in recorded["trace"]
    ]
    result = EmbodiedResult(
        status=str(summary["status"]),
        agents=list(summary["agents"]),
        embodied_length=summary.get("embodied_length"),
        steps=int(summary["steps"]),
        waits=int(summary["waits"]),
        backoffs=int(summary["backoffs"]),
        trace=trace,
        start_positions={a: (int(c[0]), int(c[1])) for a, c in summary["start_positions"].items()},
        floor_plan=str(summary["floor_plan"]),
        seed=int(summary["seed"]),
        agent=summary.get("agent"),
        step=summary.get("step"),
        reason=str(summary.get("reason") or ""),
        unmet_goal=list(summary.get("unmet_goal") or []),
        scene=Scene.from_dict(recorded.get("scene") or {}),
    )
    return result, floor_plan_from_dict(recorded["floor_plan"], "recorded floor plan")


GIF_NAME = "kitchen.gif"
TIMELINE_NAME = "timeline.png"


def draws_pictures(render: bool | None, seed: int, in_sweep: bool) -> bool:
    """Whether a job draws its execution's GIF and timeline (about 2 s a run): as
    ``render`` says when it is set; by default (None) every single run, and in a sweep
    only the jobs of seed 0, so that the other seeds' jobs end without drawing."""
    if render is not None:
        return render
    return not in_sweep or seed == 0


def write_pictures(fields: Mapping[str, Any], folder: str | Path) -> dict[str, Path]:
    """The animation and the timeline of an execution given as :func:`embodied_fields`."""
    from twostep.embodied.render import save_animation, save_timeline

    result, floor_plan = result_from_fields(fields)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    title = f"{floor_plan.name}: {result.message}"
    return {
        "timeline": save_timeline(result, folder / TIMELINE_NAME, title),
        "animation": save_animation(result, floor_plan, folder / GIF_NAME),
    }
