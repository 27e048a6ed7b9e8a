"""Grid navigation for the embodied executor: shortest paths and reachable cells.

Agents move one cell per step in the four compass directions. Breadth-first search on the
small kitchen grids is exact and fast enough to re-run whenever another agent steps into a
planned path; neighbours are tried in a fixed order so that paths, and so traces, are
reproducible.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Collection

from twostep.embodied.floorplan import Cell, FloorPlan

MOVES: tuple[Cell, ...] = ((1, 0), (0, 1), (-1, 0), (0, -1))


def _neighbours(plan: FloorPlan, cell: Cell) -> list[Cell]:
    x, y = cell
    out = []
    for dx, dy in MOVES:
        nxt = (x + dx, y + dy)
        if 0 <= nxt[0] < plan.width and 0 <= nxt[1] < plan.height and nxt not in plan.blocked:
            out.append(nxt)
    return out


def shortest_path(
    plan: FloorPlan, start: Cell, goal: Cell, obstacles: Collection[Cell] = ()
) -> list[Cell] | None:
    """The cells from ``start`` (excluded) to ``goal`` (included), or None if cut off.

    ``obstacles`` (other agents) block like furniture; ``[]`` when already there.
    """
    if start == goal:
        return []
    if goal in obstacles or not plan.free(goal):
        return None
    parent: dict[Cell, Cell] = {start: start}
    queue = deque([start])
    while queue:
        cell = queue.popleft()
        for nxt in _neighbours(plan, cell):
            if nxt in parent or nxt in obstacles:
                continue
            parent[nxt] = cell
            if nxt == goal:
                path = [nxt]
                while parent[path[-1]] != start:
                    path.append(parent[path[-1]])
                path.reverse()
                return path
            queue.append(nxt)
    return None


def reachable_cells(
    plan: FloorPlan, start: Cell, obstacles: Collection[Cell] = ()
) -> dict[Cell, int]:
    """Every cell reachable from ``start`` with its distance in steps (``start`` included)."""
    distance = {start: 0}
    queue = deque([start])
    while queue:
        cell = queue.popleft()
        for nxt in _neighbours(plan, cell):
            if nxt not in distance and nxt not in obstacles:
                distance[nxt] = distance[cell] + 1
                queue.append(nxt)
    return distance
