"""The sizes of the benchmark's 20 tasks per domain, as data.

Object counts per type and number of goal atoms of tasks p01..p20, the same as the
LLM+P benchmark used by the TwoStep paper (``benchmark-sizes.md``), with one deliberate
change that the paper also makes: every barman task has 3 shakers instead of 1. Where
the counts do not fix the shape of the goal, the paper's tasks do and it is kept here as
well: each termes task builds towers of the same heights as the paper's task of the
same number (1 or 2 towers in p01-p10, 3 to 6 in p11-p20), on positions of its own.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

BARMAN_SHAKERS = 3


@dataclass(frozen=True)
class TaskSize:
    """How many objects of each type a task has, and how many literals its goal has.

    ``goal_shape`` says what the goal builds where the object counts leave it open
    (termes: ``towers``, the height of each tower).
    """

    objects: Mapping[str, int]
    goal_atoms: int
    goal_shape: Mapping[str, tuple[int, ...]] = field(default_factory=dict)

    def count(self, type_name: str) -> int:
        return self.objects.get(type_name, 0)


def _size(
    goal_atoms: int, goal_shape: Mapping[str, tuple[int, ...]] | None = None, **objects: int
) -> TaskSize:
    return TaskSize(
        MappingProxyType(dict(sorted(objects.items()))),
        goal_atoms,
        MappingProxyType(dict(goal_shape or {})),
    )


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
    # (numbers, positions, tower heights); the goal fixes every position's height (the
    # towers, 0 elsewhere) and forbids a held block; the tallest tower uses every number
    rows = [(4, 12, (3,)), (4, 12, (3, 3)), (5, 12, (4,)), (5, 12, (4, 3)), (6, 12, (5,)),
            (6, 12, (5, 5)), (4, 20, (3,)), (4, 20, (3, 3)), (5, 20, (4,)), (5, 20, (4, 2)),
            (4, 12, (3, 3, 3)), (4, 12, (3, 2, 2, 2)), (5, 12, (4, 3, 3)),
            (5, 12, (4, 4, 3, 3)), (6, 12, (5, 3, 2)), (6, 12, (5, 5, 4, 2)),
            (4, 12, (3, 3, 3, 3, 3)), (4, 12, (3, 3, 2, 2, 2, 2)), (5, 12, (4, 4, 2, 2, 2)),
            (5, 12, (4, 4, 2, 2, 2, 2))]
    # fmt: on
    return tuple(
        _size(positions + 1, {"towers": towers}, numb=numbers, position=positions)
        for numbers, positions, towers in rows
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
