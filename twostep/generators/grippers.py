"""Grippers task generator: robots with two grippers each carry balls between rooms.

Robots ``robotK`` own ``lgripperK`` and ``rgripperK``; balls ``ballK`` (of the root type
``object``) start in random rooms and must each end in another random room. The PDDL
domain is named ``gripper-strips``, as in the paper's task files, so that those files read
with it as they are; the folder and the generator keep the name ``grippers``.
"""

from __future__ import annotations

from random import Random

from twostep.generators.sizes import TaskSize
from twostep.generators.spec import TaskSpec, numbered
from twostep.pddl import Fact

DOMAIN = "grippers"
PDDL_NAME = "gripper-strips"  # the name inside the PDDL (the paper's problems name it)
SCALE_UNIT = "balls"


def make_task(name: str, robots: int, balls: int, rooms: int, rng: Random) -> TaskSpec:
    """``robots`` robots, ``balls`` balls, ``rooms`` rooms (>= 2); every ball must move."""
    room_names = [f"room{i}" for i in range(1, rooms + 1)]
    objects = numbered("robot", robots, "robot") + numbered("room", rooms, "room")
    grippers: list[tuple[str, str]] = []
    for k in range(1, robots + 1):
        grippers += [(f"lgripper{k}", "gripper"), (f"rgripper{k}", "gripper")]
    objects += tuple(grippers) + numbered("ball", balls, "object")
    init: list[Fact] = []
    for k in range(1, robots + 1):
        init += [
            ("at-robby", f"robot{k}", rng.choice(room_names)),
            ("free", f"robot{k}", f"lgripper{k}"),
            ("free", f"robot{k}", f"rgripper{k}"),
        ]
    goal: list[Fact] = []
    for k in range(1, balls + 1):
        start = rng.choice(room_names)
        init.append(("at", f"ball{k}", start))
        goal.append(("at", f"ball{k}", rng.choice([r for r in room_names if r != start])))
    return TaskSpec(name, DOMAIN, objects, tuple(init), tuple(goal), pddl_domain=PDDL_NAME)


def benchmark_task(name: str, size: TaskSize, rng: Random) -> TaskSpec:
    return make_task(name, size.count("robot"), size.count("object"), size.count("room"), rng)


def example_task(name: str, rng: Random) -> TaskSpec:
    return make_task(name, 1, 3, 3, rng)


def scaled_task(name: str, size: int, rng: Random) -> TaskSpec:
    """``size`` balls, 4 robots and one room per 5 balls (at least 4)."""
    return make_task(name, 4, size, max(4, size // 5), rng)
