"""The embodied kitchen domain (``data/alfworld``): the paper's four tasks and larger kitchens.

A :class:`Kitchen` is both a PDDL world (receptacles, the locations they are reached from,
what each receptacle can do) and a floor plan (a grid with furniture, the cell of every
location), so the tasks and the floor plan the embodied executor walks on come from one
description and cannot disagree. :func:`paper_task` builds the paper's Table II tasks
(p01..p04) in :data:`PAPER_KITCHEN`, with objects inside closed drawers, cabinets and the
fridge where the paper says "some objects are inside containers"; :func:`scaled_task`
makes kitchens of growing size (more counters, cabinets and objects) for scaling runs.

Every task has one agent, ``alice``: the single-agent task of the paper. Execution with
several agents gives each planning agent its own body (:mod:`twostep.embodied`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from random import Random

from twostep.generators.describe import join, natural_key
from twostep.generators.spec import TaskSpec
from twostep.pddl import Fact

DOMAIN = "alfworld"
AGENT = "alice"
START = "loc-door"
SCALE_UNIT = "objects"

OPENABLE = frozenset({"fridge", "cabinet", "drawer", "microwave"})
KIND_PREDICATES = {"sink": "sink", "microwave": "microwave", "fridge": "fridge"}
SWITCHABLE = frozenset({"stoveburner", "coffeemachine"})
SLICEABLE = frozenset({"apple", "bread", "tomato", "potato", "lettuce"})
KNIVES = frozenset({"knife", "butterknife"})


@dataclass(frozen=True)
class Receptacle:
    """A piece of furniture or an appliance: what it is, where it stands, where it is reached.

    ``rect`` is ``(x, y, width, height)`` in grid cells; ``None`` for receptacles inside
    another one's footprint (a cabinet above a counter, a drawer below it).
    """

    name: str
    kind: str
    location: str
    rect: tuple[int, int, int, int] | None = None


@dataclass(frozen=True)
class Kitchen:
    """One kitchen: a grid, its walls, its receptacles and its locations' cells."""

    name: str
    width: int
    height: int
    receptacles: tuple[Receptacle, ...]
    locations: Mapping[str, tuple[int, int]]
    walls: tuple[tuple[int, int, int, int], ...] = ()
    start: str = START

    def receptacle(self, name: str) -> Receptacle:
        for receptacle in self.receptacles:
            if receptacle.name == name:
                return receptacle
        raise KeyError(name)

    def static_facts(self) -> list[Fact]:
        """What never changes: reachability and what each receptacle is and can do."""
        facts: list[Fact] = []
        for r in self.receptacles:
            facts.append(("reached-from", r.name, r.location))
            if r.kind in OPENABLE:
                facts.append(("openable", r.name))
            if r.kind in KIND_PREDICATES:
                facts.append((KIND_PREDICATES[r.kind], r.name))
            if r.kind in SWITCHABLE:
                facts.append(("switchable", r.name))
        return facts

    def floor_plan_yaml(self) -> str:
        """The floor plan as the embodied executor reads it (``kitchen.yaml``)."""
        lines = [
            f"# Floor plan of the '{self.name}' kitchen: a {self.width} x {self.height} grid,",
            "# x to the right, y downwards. Walls and furniture block cells; each location is",
            "# the free cell an agent stands on to reach the receptacles listed with it.",
            f"name: {self.name}",
            f"width: {self.width}",
            f"height: {self.height}",
            "walls:",
        ]
        lines += [f"  - [{x}, {y}, {w}, {h}]" for x, y, w, h in self.walls] or ["  []"]
        if not self.walls:
            lines[-2:] = ["walls: []"]
        lines.append("furniture:")
        for r in self.receptacles:
            if r.rect is not None:
                x, y, w, h = r.rect
                lines.append(f"  {r.name}: [{x}, {y}, {w}, {h}]")
        lines.append("locations:")
        for name, (x, y) in self.locations.items():
            reaches = [r.name for r in self.receptacles if r.location == name]
            note = f"  # {', '.join(reaches)}" if reaches else "  # where agents start"
            lines.append(f"  {name}: [{x}, {y}]{note}")
        return "\n".join(lines) + "\n"


def _counter_block(prefix: int, x: int, location: tuple[str, tuple[int, int]]) -> list[Receptacle]:
    """A counter with a cabinet above and a drawer below, all reached from one place."""
    loc = location[0]
    return [
        Receptacle(f"countertop{prefix}", "countertop", loc, (x, 1, 2, 1)),
        Receptacle(f"cabinet{prefix}", "cabinet", loc),
        Receptacle(f"drawer{prefix}", "drawer", loc),
    ]


def _paper_kitchen() -> Kitchen:
    locations = {
        "loc-fridge1": (1, 2),
        "loc-counter1": (4, 2),
        "loc-sinkbasin1": (6, 2),
        "loc-counter2": (8, 2),
        "loc-microwave1": (10, 2),
        "loc-stoveburner1": (11, 2),
        "loc-counter3": (2, 6),
        "loc-cabinet4": (10, 6),
        "loc-diningtable1": (6, 7),
        START: (6, 9),
    }
    receptacles = [
        Receptacle("fridge1", "fridge", "loc-fridge1", (1, 1, 2, 1)),
        *_counter_block(1, 3, ("loc-counter1", locations["loc-counter1"])),
        Receptacle("sinkbasin1", "sink", "loc-sinkbasin1", (5, 1, 2, 1)),
        *_counter_block(2, 7, ("loc-counter2", locations["loc-counter2"])),
        Receptacle("microwave1", "microwave", "loc-microwave1", (9, 1, 2, 1)),
        Receptacle("stoveburner1", "stoveburner", "loc-stoveburner1", (11, 1, 1, 1)),
        Receptacle("countertop3", "countertop", "loc-counter3", (1, 5, 1, 3)),
        Receptacle("drawer3", "drawer", "loc-counter3"),
        Receptacle("cabinet4", "cabinet", "loc-cabinet4", (11, 5, 1, 3)),
        Receptacle("diningtable1", "diningtable", "loc-diningtable1", (5, 5, 3, 2)),
        Receptacle("garbagecan1", "garbagecan", "loc-door", (7, 9, 1, 1)),  # beside the door
    ]
    walls = ((0, 0, 13, 1), (0, 10, 13, 1), (0, 1, 1, 9), (12, 1, 1, 9))
    return Kitchen("paper-kitchen", 13, 11, tuple(receptacles), locations, walls)


PAPER_KITCHEN = _paper_kitchen()


@dataclass(frozen=True)
class KitchenTask:
    """Where the objects are and what the goal asks, in one kitchen."""

    title: str
    placements: Mapping[str, str]  # item -> receptacle it starts in
    goal: tuple[Fact, ...]
    negative_goal: tuple[Fact, ...] = ()
    opened: tuple[str, ...] = ()  # openable receptacles that start open
    initial: tuple[Fact, ...] = field(default=())  # extra facts (a clean plate, a hot mug)


def _kind(item: str) -> str:
    return item.rstrip("0123456789")


def build_task(name: str, kitchen: Kitchen, task: KitchenTask) -> TaskSpec:
    """The PDDL task of ``task`` in ``kitchen``, with the one agent ``alice`` at the door."""
    items = sorted(task.placements, key=natural_key)
    objects = [(AGENT, "agent")]
    objects += [(loc, "location") for loc in kitchen.locations]
    objects += [(r.name, "receptacle") for r in kitchen.receptacles]
    objects += [(item, "item") for item in items]
    init: list[Fact] = [("at", AGENT, kitchen.start), ("handempty", AGENT)]
    init += kitchen.static_facts()
    init += [
        ("accessible", r.name)
        for r in kitchen.receptacles
        if r.kind not in OPENABLE or r.name in task.opened
    ]
    for item in items:
        if _kind(item) in SLICEABLE:
            init.append(("sliceable", item))
        if _kind(item) in KNIVES:
            init.append(("knife", item))
    init += [("in", item, task.placements[item]) for item in items]
    init += task.initial
    return TaskSpec(name, DOMAIN, tuple(objects), tuple(init), task.goal, task.negative_goal)


_TABLE = "diningtable1"
_SINK = "sinkbasin1"

PAPER_TASKS: tuple[KitchenTask, ...] = (
    KitchenTask(
        "Put an apple, a heated egg and a clean fork on the dining table",
        {
            "apple1": "countertop3",
            "egg1": "fridge1",
            "fork1": "drawer1",
            "bread1": "countertop1",
            "knife1": "drawer2",
            "mug1": "cabinet1",
        },
        (
            ("in", "apple1", _TABLE),
            ("in", "egg1", _TABLE),
            ("hot", "egg1"),
            ("in", "fork1", _TABLE),
            ("clean", "fork1"),
        ),
    ),
    KitchenTask(
        "Clear the dining table of the plate, the two bowls and the mug",
        {
            "plate1": _TABLE,
            "bowl1": _TABLE,
            "bowl2": _TABLE,
            "mug1": _TABLE,
            "bread1": _TABLE,
            "apple1": "countertop2",
            "spoon1": "drawer1",
        },
        (("handempty", AGENT),),
        (
            ("in", "plate1", _TABLE),
            ("in", "bowl1", _TABLE),
            ("in", "bowl2", _TABLE),
            ("in", "mug1", _TABLE),
        ),
    ),
    KitchenTask(
        "Put the apple, the egg and the wine bottle in the fridge",
        {
            "apple1": _TABLE,
            "egg1": "cabinet2",
            "winebottle1": "cabinet4",
            "tomato1": "fridge1",
            "cup1": "countertop1",
        },
        (("in", "apple1", "fridge1"), ("in", "egg1", "fridge1"), ("in", "winebottle1", "fridge1")),
    ),
    KitchenTask(
        "Clear the sink of the spoon, the cup, the knife and the apple",
        {
            "spoon1": _SINK,
            "cup1": _SINK,
            "knife1": _SINK,
            "apple1": _SINK,
            "plate1": "cabinet1",
            "egg1": "fridge1",
        },
        (("handempty", AGENT),),
        (
            ("in", "spoon1", _SINK),
            ("in", "cup1", _SINK),
            ("in", "knife1", _SINK),
            ("in", "apple1", _SINK),
        ),
    ),
)

EXAMPLE_TASK = KitchenTask(
    "Put a cold tomato on the dining table",
    {"tomato1": "countertop2", "cup1": "cabinet1"},
    (("in", "tomato1", _TABLE), ("cold", "tomato1")),
)


def paper_task(index: int) -> TaskSpec:
    """Task ``index`` (1..4) of the paper's Table II."""
    return build_task(f"alfworld-p{index:02d}", PAPER_KITCHEN, PAPER_TASKS[index - 1])


def example_task() -> TaskSpec:
    return build_task("alfworld-p-example", PAPER_KITCHEN, EXAMPLE_TASK)


# ---------------------------------------------------------------- larger kitchens

_SCALED_KINDS = ("apple", "egg", "mug", "cup", "plate", "bowl", "fork", "spoon", "tomato", "bread")


def scaled_kitchen(counters: int) -> Kitchen:
    """A kitchen with ``counters`` counter blocks (counter + cabinet + drawer) along the top
    wall, a fridge, sink and microwave, and a dining table in the middle of the floor."""
    width = 3 * counters + 11
    locations: dict[str, tuple[int, int]] = {
        "loc-fridge1": (1, 2),
        "loc-sinkbasin1": (4, 2),
        "loc-microwave1": (7, 2),
    }
    receptacles = [
        Receptacle("fridge1", "fridge", "loc-fridge1", (1, 1, 2, 1)),
        Receptacle("sinkbasin1", "sink", "loc-sinkbasin1", (4, 1, 2, 1)),
        Receptacle("microwave1", "microwave", "loc-microwave1", (7, 1, 2, 1)),
    ]
    for i in range(1, counters + 1):
        x = 7 + 3 * i
        locations[f"loc-counter{i}"] = (x, 2)
        receptacles += _counter_block(i, x, (f"loc-counter{i}", (x, 2)))
    height = 12
    table_x = width // 2 - 2
    locations["loc-diningtable1"] = (table_x + 1, 8)
    locations[START] = (width // 2, height - 2)
    receptacles.append(Receptacle("diningtable1", "diningtable", "loc-diningtable1",
                                  (table_x, 5, 4, 3)))  # fmt: skip
    walls = ((0, 0, width, 1), (0, height - 1, width, 1), (0, 1, 1, height - 2),
             (width - 1, 1, 1, height - 2))  # fmt: skip
    return Kitchen(f"kitchen-{counters}", width, height, tuple(receptacles), locations, walls)


def scaled_task(name: str, size: int, rng: Random) -> tuple[TaskSpec, Kitchen]:
    """``size`` objects scattered over a kitchen with about size/3 counter blocks; the goal
    puts each on the dining table, heated, cooled or cleaned on the way for some."""
    kitchen = scaled_kitchen(max(2, size // 3))
    holders = [r.name for r in kitchen.receptacles if r.kind != "diningtable"]
    items = [f"{_SCALED_KINDS[i % len(_SCALED_KINDS)]}{i // len(_SCALED_KINDS) + 1}"
             for i in range(size)]  # fmt: skip
    placements = {item: rng.choice(holders) for item in items}
    goal: list[Fact] = []
    for item in items:
        goal.append(("in", item, _TABLE))
        treatment = rng.choice(("", "", "hot", "cold", "clean"))
        if treatment:
            goal.append((treatment, item))
    task = KitchenTask(f"{size} objects to the table", placements, tuple(goal))
    return build_task(name, kitchen, task), kitchen


# ---------------------------------------------------------------- English


_VERBS = {"hot": "heated", "cold": "cooled", "clean": "clean", "sliced": "sliced"}


def describe_task(spec: TaskSpec, kitchen: Kitchen) -> str:
    """The task in English, for the prompts (what is where, what must become true)."""
    facts = set(spec.init)
    items = [o for o, t in spec.objects if t == "item"]
    lines = [
        f"You are {AGENT}, a robot in a kitchen. You stand at {kitchen.start} with empty hands.",
    ]
    by_location: dict[str, list[str]] = {}
    for r in kitchen.receptacles:
        by_location.setdefault(r.location, []).append(r.name)
    for loc in kitchen.locations:
        if loc in by_location:
            lines.append(f"From {loc} you can reach {join(by_location[loc])}.")
    closed = [r.name for r in kitchen.receptacles if ("accessible", r.name) not in facts]
    if closed:
        lines.append(f"{join(closed)} {'is' if len(closed) == 1 else 'are'} closed.")
    for item in items:
        where = next(f[2] for f in spec.init if f[0] == "in" and f[1] == item)
        lines.append(f"{item} is in {where}.")
    knives = [i for i in items if ("knife", i) in facts]
    if knives:
        lines.append(f"{join(knives)} can slice things.")
    lines.append("Your goal is to reach a state where:")
    lines += _goal_sentences(spec.goal, negative=False)
    lines += _goal_sentences(spec.negative_goal, negative=True)
    return "\n".join(lines) + "\n"


def _goal_sentences(goal: Iterable[Fact], negative: bool) -> list[str]:
    out = []
    for fact in goal:
        if fact[0] == "in":
            out.append(f"{fact[1]} is {'no longer ' if negative else ''}in {fact[2]}.")
        elif fact[0] == "handempty":
            out.append(f"{fact[1]} holds nothing.")
        elif fact[0] in _VERBS:
            out.append(f"{fact[1]} is {'not ' if negative else ''}{_VERBS[fact[0]]}.")
        else:
            out.append(f"({' '.join(fact)}) is {'false' if negative else 'true'}.")
    return out


def data_files(
    tasks: Sequence[KitchenTask] = PAPER_TASKS, kitchen: Kitchen = PAPER_KITCHEN
) -> dict[str, str]:
    """Every generated file of ``data/alfworld`` (not the hand-written expert.yaml)."""
    from twostep.generators import static_file

    files = {
        "domain.pddl": static_file(DOMAIN, ".pddl"),
        "domain.nl": static_file(DOMAIN, ".nl"),
        "kitchen.yaml": kitchen.floor_plan_yaml(),
        "p_example.sol": static_file(DOMAIN, ".example.sol"),
    }
    example = build_task("alfworld-p-example", kitchen, EXAMPLE_TASK)
    files["p_example.pddl"] = example.to_pddl()
    files["p_example.nl"] = describe_task(example, kitchen)
    for index, task in enumerate(tasks, start=1):
        spec = build_task(f"alfworld-p{index:02d}", kitchen, task)
        files[f"p{index:02d}.pddl"] = spec.to_pddl()
        files[f"p{index:02d}.nl"] = describe_task(spec, kitchen)
    files["titles.yaml"] = "# One line per task (Table II lists them)\n" + "".join(
        f'p{index:02d}: "{task.title}"\n' for index, task in enumerate(tasks, start=1)
    )
    return files


def scale_files(size: int, count: int = 1, seed: int = 0) -> dict[str, str]:
    """A folder of ``count`` larger kitchen tasks with ``size`` objects (one floor plan)."""
    from twostep.generators import static_file, task_rng

    files = {
        "domain.pddl": static_file(DOMAIN, ".pddl"),
        "domain.nl": static_file(DOMAIN, ".nl"),
        "p_example.sol": static_file(DOMAIN, ".example.sol"),
    }
    example = example_task()
    files["p_example.pddl"] = example.to_pddl()
    files["p_example.nl"] = describe_task(example, PAPER_KITCHEN)
    for index in range(1, count + 1):
        rng = task_rng(seed, DOMAIN, f"scale{size}:{index}")
        spec, kitchen = scaled_task(f"alfworld-s{size}-{index:02d}", size, rng)
        files[f"p{index:02d}.pddl"] = spec.to_pddl()
        files[f"p{index:02d}.nl"] = describe_task(spec, kitchen)
        files["kitchen.yaml"] = kitchen.floor_plan_yaml()
    return files
