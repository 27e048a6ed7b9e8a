"""Termes task generator: build towers of blocks on a flat grid.

Positions are ``pos-R-C`` on a ``rows x cols`` grid, all at height ``n0``; numbers
``n0 .. n(K-1)`` are the possible heights. The robot starts at the depot, a border
position. The goal fixes the height of every position (the towers, every other position
back at ``n0``) and forbids a held block at the end.
"""

from __future__ import annotations

from itertools import pairwise
from random import Random

from twostep.generators.sizes import TaskSize
from twostep.generators.spec import TaskSpec
from twostep.pddl import Fact

DOMAIN = "termes"
SCALE_UNIT = "grid side"
GRIDS = {12: (4, 3), 20: (5, 4)}  # positions -> (rows, columns) of the benchmark's grids
MAX_TOWER = 3  # taller towers need long staircases that make lama-first slow


def make_task(
    name: str, rows: int, cols: int, numbers: int, towers: list[int], rng: Random
) -> TaskSpec:
    """A grid with one tower per entry of ``towers`` (its height, < ``numbers``)."""
    cells = [(r, c) for r in range(rows) for c in range(cols)]
    pos = {cell: f"pos-{cell[0]}-{cell[1]}" for cell in cells}
    heights = [f"n{i}" for i in range(numbers)]
    border = [(r, c) for r, c in cells if r in (0, rows - 1) or c in (0, cols - 1)]
    depot = rng.choice(border)
    sites = rng.sample([cell for cell in cells if cell != depot], len(towers))
    target = {cell: 0 for cell in cells}
    target.update(zip(sites, towers, strict=True))
    objects = tuple((h, "numb") for h in heights) + tuple((pos[cell], "position") for cell in cells)
    init: list[Fact] = [("height", pos[cell], "n0") for cell in cells]
    init.append(("at", pos[depot]))
    init += [("succ", high, low) for low, high in pairwise(heights)]
    for r, c in cells:
        for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            if (r + dr, c + dc) in pos:
                init.append(("neighbor", pos[(r, c)], pos[(r + dr, c + dc)]))
    init.append(("is-depot", pos[depot]))
    goal = [("height", pos[cell], heights[target[cell]]) for cell in cells]
    return TaskSpec(name, DOMAIN, objects, tuple(init), tuple(goal), (("has-block",),))


def benchmark_task(name: str, size: TaskSize, rng: Random) -> TaskSpec:
    rows, cols = GRIDS[size.count("position")]
    numbers = size.count("numb")
    height = rng.randint(2, min(MAX_TOWER, numbers - 1))
    return make_task(name, rows, cols, numbers, [height], rng)


def example_task(name: str, rng: Random) -> TaskSpec:
    return make_task(name, 3, 3, 3, [2], rng)


def scaled_task(name: str, size: int, rng: Random) -> TaskSpec:
    """A ``size x size`` grid with one tower of height 2 or 3 per 3 rows."""
    towers = [rng.randint(2, MAX_TOWER) for _ in range(max(1, size // 3))]
    return make_task(name, size, size, MAX_TOWER + 1, towers, rng)
