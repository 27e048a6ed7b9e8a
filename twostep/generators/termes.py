"""Termes task generator: build towers of blocks on a flat grid.

Positions are ``pos-R-C`` on a ``rows x cols`` grid, all at height ``n0``; numbers
``n0 .. n(K-1)`` are the possible heights. The robot starts at the depot, a position of
the border column ``pos-R-0`` other than the corner ``pos-0-0``. The goal fixes the height
of every position (the towers, every other position back at ``n0``) and forbids a held
block at the end. The benchmark tasks build towers of the heights the paper's tasks
build (``sizes.py``), on random positions other than the depot.
"""

from __future__ import annotations

from itertools import pairwise
from random import Random

from twostep.generators.sizes import TaskSize
from twostep.generators.spec import TaskSpec
from twostep.pddl import Fact

DOMAIN = "termes"
SCALE_UNIT = "towers"
GRIDS = {12: (4, 3), 20: (5, 4)}  # positions -> (rows, columns) of the benchmark's grids
SCALED_TOWER = 3  # height of every tower of the larger tasks


def make_task(
    name: str, rows: int, cols: int, numbers: int, towers: list[int], rng: Random
) -> TaskSpec:
    """A grid with one tower per entry of ``towers`` (its height, < ``numbers``).

    The positions left flat stay connected to the depot, so the robot can walk from the
    depot to every side of the towers once they stand (a rule of ours: the paper's tasks
    do not always keep it, but without it some of our random layouts wall the grid in two
    and lama-first does not solve them within 60 s).
    """
    cells = [(r, c) for r in range(rows) for c in range(cols)]
    pos = {cell: f"pos-{cell[0]}-{cell[1]}" for cell in cells}
    heights = [f"n{i}" for i in range(numbers)]
    depot = (rng.randint(1, rows - 1), 0)
    while True:
        sites = rng.sample([cell for cell in cells if cell != depot], len(towers))
        if _flat_part_connected(set(cells) - set(sites), depot):
            break
    target = {cell: 0 for cell in cells}
    target.update(zip(sites, towers, strict=True))
    objects = tuple((h, "numb") for h in heights) + tuple((pos[cell], "position") for cell in cells)
    init: list[Fact] = [("height", pos[cell], "n0") for cell in cells]
    init.append(("at", pos[depot]))
    init += [("succ", high, low) for low, high in pairwise(heights)]
    for cell in cells:
        init += [("neighbor", pos[cell], pos[other]) for other in _neighbours(cell) if other in pos]
    init.append(("is-depot", pos[depot]))
    goal = [("height", pos[cell], heights[target[cell]]) for cell in cells]
    return TaskSpec(name, DOMAIN, objects, tuple(init), tuple(goal), (("has-block",),))


def _neighbours(cell: tuple[int, int]) -> list[tuple[int, int]]:
    r, c = cell
    return [(r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)]


def _flat_part_connected(flat: set[tuple[int, int]], depot: tuple[int, int]) -> bool:
    """Whether every flat position is reachable from the depot over flat positions."""
    seen, todo = {depot}, [depot]
    while todo:
        for other in _neighbours(todo.pop()):
            if other in flat and other not in seen:
                seen.add(other)
                todo.append(other)
    return seen == flat


def benchmark_task(name: str, size: TaskSize, rng: Random) -> TaskSpec:
    rows, cols = GRIDS[size.count("position")]
    return make_task(name, rows, cols, size.count("numb"), list(size.goal_shape["towers"]), rng)


def example_task(name: str, rng: Random) -> TaskSpec:
    return make_task(name, 3, 3, 3, [2], rng)


def scaled_task(name: str, size: int, rng: Random) -> TaskSpec:
    """``size`` towers of height 3 on a grid of 5 rows and ``max(4, size)`` columns.

    From 4 towers on (the paper's larger 5 x 4 grid), lama-first plans run to a few
    hundred steps, as the paper's termes plans do.
    """
    return make_task(name, 5, max(4, size), SCALED_TOWER + 1, [SCALED_TOWER] * size, rng)
