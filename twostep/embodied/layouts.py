"""Real AI2-THOR scenes: the layouts the ``alfworld`` wheel ships, and AlfWorld problems on them.

The wheel (pip extra ``embodied``) ships, for each of the 120 scenes,
``alfworld/gen/layouts/FloorPlanN-layout.npy`` (the reachable (x, z) points of the scene,
in metres, on AI2-THOR's 0.25 m navigation grid) and ``FloorPlanN-openable.json`` (the
receptacles' object ids, ``Fridge|-00.53|+00.00|-01.55``). The files are read from the
installed package's folder; the package itself is never imported (its modules pull in
AI2-THOR and torch).

AlfWorld names a location after the grid point an agent stands on to reach something:
``loc|x|z|rotation|horizon`` in grid units (mangled in PDDL as ``loc_bar_4_bar_1_bar_0_bar_30``),
and a receptacle after its object id, whose numbers are its position in metres. So a real
problem is placed on its scene as it is: every location on its grid point, every
receptacle drawn at its own position, every point the scene does not list as reachable
blocked.

Grid frame: cell ``(x, y)`` of the floor plan is grid point ``(x0 + x, z0 - y)``
(:attr:`~twostep.embodied.floorplan.FloorPlan.origin` is ``(x0, z0)``), so that north
(+z) is up in the pictures.
"""

from __future__ import annotations

import importlib.util
import json
import re
from collections.abc import Iterable
from functools import cache
from pathlib import Path

from twostep.embodied.floorplan import (
    FLOOR_PLAN_FILE,
    Cell,
    FloorPlan,
    FloorPlanError,
    alfworld_position,
    build_floor_plan,
    floor_plan_from_locations,
    load_floor_plan,
    unmangle,
)
from twostep.util.files import NotTextError, exists, read_text_file

OPEN_GRID = "open"  # layout value: made-up coordinates on an open grid, no scene
GRID_M = 0.25  # AI2-THOR's navigation grid, metres
TRAJ_DATA = "traj_data.json"  # ALFRED's trajectory file beside a problem: names its scene
_SCENE = re.compile(r"floorplan(\d+)", re.IGNORECASE)
_OBJECT_ID = re.compile(r"^([a-z]+)\|([-+]?[\d.]+)\|([-+]?[\d.]+)\|([-+]?[\d.]+)")


def layouts_folder() -> Path:
    """``alfworld/gen/layouts`` of the installed wheel (found without importing it)."""
    spec = importlib.util.find_spec("alfworld")
    if spec is not None and spec.submodule_search_locations:
        folder = Path(next(iter(spec.submodule_search_locations))) / "gen" / "layouts"
        if folder.is_dir():
            return folder
    raise FloorPlanError(
        "real AlfWorld scenes need the alfworld wheel's layouts: install the 'embodied' "
        "extra (make setup does)"
    )


def scene_names() -> list[str]:
    """Every scene the wheel ships (``FloorPlan1`` ...), in numeric order."""
    names = {p.name.split("-")[0] for p in layouts_folder().glob("FloorPlan*-layout.npy")}
    return sorted(names, key=lambda n: int(n[len("FloorPlan") :]))


def scene_name(value: str) -> str:
    """``FloorPlan14``, ``floorplan14`` or ``14`` -> ``FloorPlan14``."""
    match = _SCENE.fullmatch(value.strip()) or re.fullmatch(r"(\d+)", value.strip())
    if match is None:
        raise FloorPlanError(f"'{value}' is not a scene name (expected FloorPlanN)")
    return f"FloorPlan{int(match.group(1))}"


@cache
def reachable_points(scene: str) -> frozenset[Cell]:
    """The scene's reachable grid points ``(x, z)`` (0.25 m units)."""
    import numpy as np

    path = layouts_folder() / f"{scene}-layout.npy"
    if not path.is_file():
        raise FloorPlanError(f"no layout {scene} in the alfworld wheel ({path.parent})")
    points = np.load(path)
    return frozenset(
        (round(float(x) / GRID_M), round(float(z) / GRID_M)) for x, z in points.tolist()
    )


@cache
def receptacle_ids(scene: str) -> frozenset[str]:
    """The object ids (lower case) of the scene's receptacles with an interaction point."""
    path = layouts_folder() / f"{scene}-openable.json"
    if not path.is_file():
        return frozenset()
    return frozenset(key.lower() for key in json.loads(path.read_text()))


def object_point(name: str) -> Cell | None:
    """The grid point of an AI2-THOR object id (``Fridge|-00.53|+00.00|-01.55``, or its
    PDDL spelling): its x and z in metres on the 0.25 m grid."""
    match = _OBJECT_ID.match(unmangle(name.lower()))
    if match is None or match.group(1) == "loc":  # a location: loc|x|z|rotation|horizon
        return None
    return round(float(match.group(2)) / GRID_M), round(float(match.group(4)) / GRID_M)


def _object_id(name: str) -> str:
    return unmangle(name.lower())


def find_scene(
    locations: Iterable[str],
    receptacles: Iterable[str] = (),
    folder: str | Path | None = None,
    problem_name: str = "",
) -> str:
    """The scene of a real AlfWorld problem: the ``traj_data.json`` beside it, else a
    ``FloorPlanN`` in its name, else the scene whose receptacle ids the problem uses
    (most matches), else the one scene whose reachable points hold every location."""
    if folder is not None and exists(Path(folder) / TRAJ_DATA):
        path = Path(folder) / TRAJ_DATA
        try:
            data = json.loads(read_text_file(path))
        except (NotTextError, ValueError, OSError) as error:
            raise FloorPlanError(f"{path}: cannot be read as JSON ({error})") from None
        if not isinstance(data, dict):
            raise FloorPlanError(f"{path}: expected a JSON object with its scene")
        scene = (data.get("scene") or {}).get("floor_plan") or (data.get("scene") or {}).get(
            "scene_num"
        )
        if scene is not None:
            return scene_name(str(scene))
    match = _SCENE.search(problem_name)
    if match is not None:
        return f"FloorPlan{int(match.group(1))}"
    ids = {_object_id(r) for r in receptacles}
    scenes = scene_names()
    if ids:
        score = {s: len(ids & receptacle_ids(s)) for s in scenes}
        best = max(score.values())
        winners = [s for s in scenes if score[s] == best]
        if best and len(winners) == 1:
            return winners[0]
    points = {p for p in (alfworld_position(loc) for loc in locations) if p is not None}
    if not points:
        raise FloorPlanError("no AlfWorld location (loc|x|z|rotation|horizon) to place")
    holding = [s for s in scenes if points <= reachable_points(s)]
    if len(holding) == 1:
        return holding[0]
    found = ", ".join(holding[:5]) + (" ..." if len(holding) > 5 else "") or "none"
    raise FloorPlanError(
        f"cannot tell the scene of this problem ({len(points)} location points; scenes "
        f"that hold them all: {found}): choose one with layout=FloorPlanN"
    )


def display_names(names: Iterable[str]) -> dict[str, str]:
    """Short names for pictures: an AI2-THOR object id becomes its kind and a number per
    kind (``cabinet2``, as AlfWorld's text games say); other names stay as they are."""
    counts: dict[str, int] = {}
    out = {}
    for name in sorted(set(names), key=lambda n: (object_point(n) or (0, 0), n)):
        if object_point(name) is None:
            point = alfworld_position(name)
            out[name] = name if point is None else f"loc({point[0]},{point[1]})"
            continue
        kind = _object_id(name).split("|")[0]
        if kind == "sink" and _object_id(name).endswith("|sinkbasin"):
            kind = "sinkbasin"
        counts[kind] = counts.get(kind, 0) + 1
        out[name] = f"{kind}{counts[kind]}"
    return out


def scene_floor_plan(
    scene: str, locations: Iterable[str], receptacles: Iterable[str] = ()
) -> FloorPlan:
    """The floor plan of ``scene`` with the problem's locations on their grid points and
    its receptacles drawn at their positions (:func:`display_names` labels them).

    Raises :class:`FloorPlanError` for a location that is not a reachable point."""
    reachable = reachable_points(scene)
    located = {loc.lower(): alfworld_position(loc) for loc in locations}
    unplaced = sorted(name for name, point in located.items() if point is None)
    if unplaced:
        raise FloorPlanError(
            "location(s) without a position in their name (expected loc|x|z|rotation|horizon): "
            + ", ".join(unplaced)
        )
    off = sorted(name for name, point in located.items() if point not in reachable)
    if off:
        raise FloorPlanError(
            f"{scene}: location(s) not on a reachable point of the scene: {', '.join(off)}"
        )
    objects = {r.lower(): object_point(r) for r in receptacles}
    drawn = {name: point for name, point in objects.items() if point is not None}
    xs = [p[0] for p in reachable] + [p[0] for p in drawn.values()]
    zs = [p[1] for p in reachable] + [p[1] for p in drawn.values()]
    x0, z0 = min(xs) - 1, max(zs) + 1
    width, height = max(xs) - x0 + 2, z0 - min(zs) + 2

    def cell(point: Cell) -> Cell:
        return point[0] - x0, z0 - point[1]

    free = {cell(p) for p in reachable}
    blocked = {(x, y) for x in range(width) for y in range(height)} - free
    return build_floor_plan(
        scene,
        width,
        height,
        {name: cell(point) for name, point in located.items() if point is not None},
        blocked_cells=blocked,
        fixtures={name: cell(point) for name, point in drawn.items()},
        origin=(x0, z0),
    )


def floor_plan_for_task(
    location_names: Iterable[str],
    folder: str | Path | None,
    layout: str | None = None,
    receptacles: Iterable[str] = (),
    problem_name: str = "",
) -> FloorPlan:
    """The floor plan of a task whose files live in ``folder``.

    ``layout`` None: ``<folder>/kitchen.yaml`` if there is one, else the AI2-THOR scene
    of the task's AlfWorld locations (:func:`find_scene`). ``FloorPlanN``: that scene.
    ``open``: the locations on an open grid by their x and z.
    """
    locations = list(location_names)
    if layout == OPEN_GRID:
        return floor_plan_from_locations(locations)
    if layout is None and folder is not None and exists(Path(folder) / FLOOR_PLAN_FILE):
        return load_floor_plan(Path(folder) / FLOOR_PLAN_FILE)  # a FIFO, a directory: named
    if layout is None and not (locations and all(alfworld_position(n) for n in locations)):
        raise FloorPlanError(
            f"no {FLOOR_PLAN_FILE} in {folder} and the locations are not AlfWorld's "
            "(loc|x|z|rotation|horizon): nowhere to place them"
        )
    receptacles = list(receptacles)
    scene = (
        scene_name(layout)
        if layout is not None
        else find_scene(locations, receptacles, folder, problem_name)
    )
    return scene_floor_plan(scene, locations, receptacles)
