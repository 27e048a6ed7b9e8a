"""The sizes of the benchmark's 20 tasks per domain, as data.

Object counts per type and number of goal atoms of tasks p01..p20, the same as the
LLM+P benchmark used by the TwoStep paper (``benchmark-sizes.md``), with one deliberate
change that the paper also makes: every barman task has 3 shakers instead of 1.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

BARMAN_SHAKERS = 3


@dataclass(frozen=True)
class TaskSize:
    """How many objects of each type a task has, and how many literals its goal has."""

    objects: Mapping[str, int]
    goal_atoms: int

    def count(self, type_name: str) -> int:
        return self.objects.get(type_name, 0)


def _size(goal_atoms: int, **objects: int) -> TaskSize:
    return TaskSize(MappingProxyType(dict(sorted(objects.items()))), goal_atoms)


def _repeat(rows: Iterable[tuple[int, ...]], times: int) -> list[tuple[int, ...]]:
    return [row for row in rows for _ in range(times)]


def _barman() -> tuple[TaskSize, ...]:
    rows = _repeat([(3, 4, 3), (4, 5, 4), (5, 6, 5), (6, 8, 7), (7, 9, 8)], 4)
    return tuple(
        _size(
            goals,
            cocktail=cocktails,
            dispenser=3,
            hand=2,
            ingredient=3,
            level=3,
            shaker=BARMAN_SHAKERS,
            shot=shots,
        )
        for cocktails, shots, goals in rows
    )


def _blocksworld() -> tuple[TaskSize, ...]:
    # fmt: off
    rows = [(3, 2), (3, 2), (4, 2), (4, 3), (5, 2), (5, 3), (6, 2), (6, 3), (7, 6), (7, 6),
            (8, 5), (8, 7), (9, 7), (9, 8), (10, 7), (10, 7), (11, 7), (11, 8), (12, 8), (12, 8)]
    # fmt: on
    return tuple(_size(goals, block=blocks) for blocks, goals in rows)


def _grippers() -> tuple[TaskSize, ...]:
    # fmt: off
    # (robots, balls, rooms); each robot has two grippers, each ball one goal atom
    rows = [(2, 2, 2), (2, 4, 3), (2, 2, 5), (3, 4, 4), (2, 5, 2), (2, 1, 3), (3, 3, 4),
            (3, 5, 2), (3, 7, 4), (3, 4, 2), (1, 3, 2), (1, 5, 3), (1, 2, 3), (1, 5, 4),
            (1, 3, 5), (4, 8, 4), (4, 5, 2), (4, 6, 3), (4, 6, 5), (4, 2, 3)]
    # fmt: on
    return tuple(
        _size(balls, gripper=2 * robots, object=balls, robot=robots, room=rooms)
        for robots, balls, rooms in rows
    )


def _termes() -> tuple[TaskSize, ...]:
    # fmt: off
    # (numbers, positions); the goal fixes every position's height and forbids a held block
    rows = [(4, 12), (4, 12), (5, 12), (5, 12), (6, 12), (6, 12), (4, 20), (4, 20), (5, 20),
            (5, 20), (4, 12), (4, 12), (5, 12), (5, 12), (6, 12), (6, 12), (4, 12), (4, 12),
            (5, 12), (5, 12)]
    # fmt: on
    return tuple(
        _size(positions + 1, numb=numbers, position=positions) for numbers, positions in rows
    )


def _tyreworld() -> tuple[TaskSize, ...]:
    hubs = [1, 9, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20]
    return tuple(_size(4 * h + 4, container=1, hub=h, nut=h, tool=3, wheel=2 * h) for h in hubs)


BENCHMARK_SIZES: Mapping[str, tuple[TaskSize, ...]] = MappingProxyType(
    {
        "barman": _barman(),
        "blocksworld": _blocksworld(),
        "grippers": _grippers(),
        "termes": _termes(),
        "tyreworld": _tyreworld(),
    }
)
"""Domain -> sizes of tasks p01..p20 (index 0 is p01)."""
