"""Floor plans of the embodied executor: a grid, what blocks it, and where locations are.

A :class:`FloorPlan` is a ``width x height`` grid of cells ``(x, y)``; walls and furniture
block cells; every PDDL location object has the free cell an agent stands on to act
there. Plans are read from a YAML file (``data/alfworld/kitchen.yaml``)::

    name: paper-kitchen
    width: 13
    height: 11
    walls: [[0, 0, 13, 1], ...]        # rectangles [x, y, width, height]
    furniture: {fridge1: [1, 1, 2, 1]}  # drawn and blocking
    locations: {loc-fridge1: [1, 2]}

Real AlfWorld problems need no file: their location objects carry their own position
(``loc|x|z|rotation|horizon``, mangled in PDDL as ``loc_bar_4_bar__minus_3_bar_1_bar_45``)
and go on their AI2-THOR scene's layout (:mod:`twostep.embodied.layouts`);
:func:`floor_plan_from_locations` places them on an open grid by x and z instead (for
made-up coordinates).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from twostep.util.files import FileFormatError, NotTextError, read_yaml_file

Cell = tuple[int, int]
Rect = tuple[int, int, int, int]

MAX_SIDE = 1000
"""The widest and tallest grid a floor plan file may describe, in cells."""
MAX_CELLS = 250_000
"""The most cells a floor plan file's grid may have (width x height): every agent's walk
searches it."""
MAX_COVER = 4 * MAX_CELLS
"""The most cells a floor plan file's walls and furniture may cover in all (overlaps
counted each time): what reading them costs."""


class FloorPlanError(Exception):
    """A floor plan that cannot be used: a bad file, a location off the grid or blocked."""


@dataclass(frozen=True)
class FloorPlan:
    """A grid with blocked cells and the cell of every location."""

    name: str
    width: int
    height: int
    blocked: frozenset[Cell]
    locations: Mapping[str, Cell]
    furniture: Mapping[str, Rect] = field(default_factory=dict)
    walls: tuple[Rect, ...] = ()
    # Real scenes: receptacles drawn at their own cell without blocking (what blocks is
    # the scene's unreachable space), and the AI2-THOR grid point of cell (0, 0): cell
    # (x, y) is point (origin_x + x, origin_z - y).
    fixtures: Mapping[str, Cell] = field(default_factory=dict)
    origin: Cell | None = None

    def inside(self, cell: Cell) -> bool:
        return 0 <= cell[0] < self.width and 0 <= cell[1] < self.height

    def free(self, cell: Cell) -> bool:
        """On the grid and not a wall or furniture (other agents aside)."""
        return self.inside(cell) and cell not in self.blocked

    def free_cells(self) -> list[Cell]:
        return [
            (x, y)
            for y in range(self.height)
            for x in range(self.width)
            if (x, y) not in self.blocked
        ]

    def cell_of(self, location: str) -> Cell | None:
        return self.locations.get(location)

    def check(self) -> None:
        """Raise :class:`FloorPlanError` for a location that is off the grid or blocked."""
        for name, cell in self.locations.items():
            if not self.inside(cell):
                raise FloorPlanError(f"{self.name}: location {name} at {cell} is off the grid")
            if cell in self.blocked:
                raise FloorPlanError(
                    f"{self.name}: location {name} at {cell} is on a wall or furniture"
                )


def _cells(rects: Iterable[Rect]) -> set[Cell]:
    return {(x + dx, y + dy) for x, y, w, h in rects for dx in range(w) for dy in range(h)}


def build_floor_plan(
    name: str,
    width: int,
    height: int,
    locations: Mapping[str, Cell],
    walls: Iterable[Rect] = (),
    furniture: Mapping[str, Rect] | None = None,
    blocked_cells: Iterable[Cell] = (),
    fixtures: Mapping[str, Cell] | None = None,
    origin: Cell | None = None,
) -> FloorPlan:
    """A checked floor plan; walls, furniture rectangles and ``blocked_cells`` block."""
    walls = tuple(walls)
    furniture = dict(furniture or {})
    blocked = frozenset(_cells(walls) | _cells(furniture.values()) | set(blocked_cells))
    plan = FloorPlan(
        name, width, height, blocked, dict(locations), furniture, walls, dict(fixtures or {}),
        origin,
    )  # fmt: skip
    plan.check()
    return plan


def _integers(value: Any, what: str, shape: str, count: int) -> tuple[int, ...]:
    """``value`` as ``count`` integers (a number with a fraction is cut to its integer
    part, as before); anything else is a :class:`FloorPlanError` naming ``what``."""
    if not (isinstance(value, list | tuple) and len(value) == count):
        raise FloorPlanError(f"{what}: expected {shape}, got {value!r}")
    try:
        if any(isinstance(v, bool) for v in value):
            raise TypeError
        return tuple(int(v) for v in value)
    except (TypeError, ValueError, OverflowError):
        raise FloorPlanError(f"{what}: expected {shape} of integers, got {value!r}") from None


def _pair(value: Any, what: str) -> Cell:
    x, y = _integers(value, what, "[x, y]", 2)
    return x, y


def _rect(value: Any, what: str) -> Rect:
    x, y, w, h = _integers(value, what, "[x, y, width, height]", 4)
    return x, y, w, h


def _check_grid(width: int, height: int, source: str) -> None:
    """A grid of 1 to :data:`MAX_SIDE` cells a side and at most :data:`MAX_CELLS` cells."""
    if not (1 <= width <= MAX_SIDE and 1 <= height <= MAX_SIDE):
        raise FloorPlanError(
            f"{source}: a {width} x {height} grid: width and height must be 1 to {MAX_SIDE}"
        )
    if width * height > MAX_CELLS:
        raise FloorPlanError(
            f"{source}: a {width} x {height} grid has more than the {MAX_CELLS:,} cells a "
            "floor plan may have"
        )


def _check_rects(rects: Mapping[str, Rect], width: int, height: int, source: str) -> None:
    """Walls and furniture of a positive size, no larger than the grid, covering at most
    :data:`MAX_COVER` cells in all."""
    for what, (_, _, w, h) in rects.items():
        if not (1 <= w <= width and 1 <= h <= height):
            raise FloorPlanError(
                f"{source}: {what}: size {w} x {h} is out of range (1 to the grid's "
                f"{width} x {height})"
            )
    cover = sum(w * h for _, _, w, h in rects.values())
    if cover > MAX_COVER:
        raise FloorPlanError(
            f"{source}: walls and furniture cover {cover:,} cells in all, more than the "
            f"{MAX_COVER:,} a floor plan may"
        )


def floor_plan_from_dict(data: Mapping[str, Any], source: str = "floor plan") -> FloorPlan:
    """A floor plan from the parsed YAML layout above (bounded: :data:`MAX_SIDE`,
    :data:`MAX_CELLS`, :data:`MAX_COVER`; walls and furniture of a positive size)."""
    try:
        if isinstance(data["width"], bool) or isinstance(data["height"], bool):
            raise TypeError
        width, height = int(data["width"]), int(data["height"])
    except (KeyError, TypeError, ValueError, OverflowError):
        raise FloorPlanError(f"{source}: 'width' and 'height' must be integers") from None
    _check_grid(width, height, source)
    locations = {
        str(k).lower(): _pair(v, f"{source}: location {k}")
        for k, v in (data.get("locations") or {}).items()
    }
    walls = [_rect(v, f"{source}: wall") for v in data.get("walls") or []]
    furniture = {
        str(k).lower(): _rect(v, f"{source}: furniture {k}")
        for k, v in (data.get("furniture") or {}).items()
    }
    rects = {f"wall {i + 1}": rect for i, rect in enumerate(walls)}
    rects.update((f"furniture {name}", rect) for name, rect in furniture.items())
    _check_rects(rects, width, height, source)
    blocked = [_pair(v, f"{source}: blocked cell") for v in data.get("blocked") or []]
    fixtures = {
        str(k).lower(): _pair(v, f"{source}: fixture {k}")
        for k, v in (data.get("fixtures") or {}).items()
    }
    origin = data.get("origin")
    try:
        return build_floor_plan(
            str(data.get("name", source)), width, height, locations, walls, furniture,
            blocked, fixtures, None if origin is None else _pair(origin, f"{source}: origin"),
        )  # fmt: skip
    except FloorPlanError as error:
        raise FloorPlanError(f"{source}: {error}") from None


def floor_plan_to_dict(floor_plan: FloorPlan) -> dict[str, Any]:
    """The inverse of :func:`floor_plan_from_dict` (a real scene's blocked cells, its
    receptacles and its origin included)."""
    out: dict[str, Any] = {
        "name": floor_plan.name,
        "width": floor_plan.width,
        "height": floor_plan.height,
        "walls": [list(rect) for rect in floor_plan.walls],
        "furniture": {name: list(rect) for name, rect in floor_plan.furniture.items()},
        "locations": {name: list(cell) for name, cell in floor_plan.locations.items()},
    }
    if floor_plan.origin is not None:
        drawn = set(_cells(floor_plan.walls) | _cells(floor_plan.furniture.values()))
        out["layout"] = floor_plan.name
        out["origin"] = list(floor_plan.origin)
        out["blocked"] = [list(c) for c in sorted(floor_plan.blocked - drawn)]
        out["fixtures"] = {name: list(cell) for name, cell in floor_plan.fixtures.items()}
    return out


def load_floor_plan(path: str | Path) -> FloorPlan:
    """Read a floor plan YAML file (see the module docstring); a file that cannot be read
    as one (not a regular file, not text, not YAML) is a :class:`FloorPlanError` naming it."""
    path = Path(path)
    try:
        data = read_yaml_file(path)
    except (NotTextError, FileFormatError) as error:
        raise FloorPlanError(str(error)) from None
    except FileNotFoundError:
        raise FloorPlanError(f"{path}: no such floor plan file") from None
    except OSError as error:
        raise FloorPlanError(f"{path}: cannot be read ({error.strerror or error})") from None
    if not isinstance(data, dict):
        raise FloorPlanError(f"{path}: expected a mapping with width, height and locations")
    return floor_plan_from_dict(data, str(path))


# ------------------------------------------------------------- AlfWorld's own names

_MANGLED = (("_bar_", "|"), ("_minus_", "-"), ("_dot_", "."), ("_plus_", "+"))
_LOCATION = re.compile(r"^loc\|(-?[\d.]+)\|(-?[\d.]+)\|")


def unmangle(name: str) -> str:
    """AlfWorld's PDDL spelling back to its own: ``loc_bar_4_bar__minus_3`` -> ``loc|4|-3``."""
    for mangled, plain in _MANGLED:
        name = name.replace(mangled, plain)
    return name


def alfworld_position(name: str) -> Cell | None:
    """The grid position ``(x, z)`` encoded in an AlfWorld location name, or None."""
    match = _LOCATION.match(unmangle(name.lower()))
    if match is None:
        return None
    try:
        return round(float(match.group(1))), round(float(match.group(2)))
    except ValueError:
        return None


def floor_plan_from_locations(locations: Iterable[str], margin: int = 1) -> FloorPlan:
    """An open grid on which AlfWorld location objects sit at their own x and z.

    Raises :class:`FloorPlanError` naming any location that does not encode a position.
    """
    positions: dict[str, Cell] = {}
    unplaced: list[str] = []
    for name in locations:
        position = alfworld_position(name)
        if position is None:
            unplaced.append(name)
        else:
            positions[name] = position
    if unplaced:
        raise FloorPlanError(
            "location(s) without a position in their name (expected loc|x|z|rotation|horizon): "
            + ", ".join(sorted(unplaced))
        )
    if not positions:
        raise FloorPlanError("no location objects to place")
    min_x = min(x for x, _ in positions.values()) - margin
    min_z = min(z for _, z in positions.values()) - margin
    width = max(x for x, _ in positions.values()) - min_x + margin + 1
    height = max(z for _, z in positions.values()) - min_z + margin + 1
    cells = {name: (x - min_x, z - min_z) for name, (x, z) in positions.items()}
    return build_floor_plan("alfworld-locations", width, height, cells)


FLOOR_PLAN_FILE = "kitchen.yaml"
