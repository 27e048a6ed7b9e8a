"""Problem generators of our own, written from the domain files' semantics, for seven
domains of the IPC sample: blocks, gripper, visitall-sat11-strips, barman-sat11-strips,
termes-sat18-strips, storage and floortile-sat11-strips; the sizes
bench/bench_deal_generated.py runs, and each domain's agent predicates.

Only problems are generated: the domain files are the sample's (``../shared/ipc-sample``),
read in place. Every problem draws from its own RNG, seeded by its domain, size and seed,
so one problem can be rebuilt alone.
"""

from __future__ import annotations

import functools
import itertools
import random
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

# The agent predicates: the sample's agents.yaml for five domains, the for storage
# (a hoist's place, whether it is free, what it lifts) and floortile (a robot's tile and
# colour); where the problem has several hoists or robots, each agent has its own copy.
AGENT_PREDICATES: dict[str, list[str]] = {
    "blocks": ["handempty", "holding"],
    "gripper": ["at-robby", "free", "carry"],
    "barman-sat11-strips": ["handempty", "holding"],
    "termes-sat18-strips": ["at", "has-block"],
    "visitall-sat11-strips": ["at-robot"],
    "storage": ["at", "available", "lifting"],
    "floortile-sat11-strips": ["robot-at", "robot-has"],
}


@dataclass(frozen=True)
class Generated:
    """One generated problem: its PDDL text and the objects it declares, per type
    (``object`` for untyped domains), for the tests to count."""

    text: str
    objects: dict[str, list[str]] = field(default_factory=dict)


def _declare(objects: dict[str, list[str]], typed: bool = True) -> str:
    if not typed:
        return " ".join(name for names in objects.values() for name in names)
    return "\n    ".join(f"{' '.join(names)} - {kind}" for kind, names in objects.items() if names)


def _problem(
    name: str,
    domain: str,
    objects: dict[str, list[str]],
    init: Sequence[str],
    goal: Sequence[str],
    typed: bool = True,
    metric: bool = False,
) -> Generated:
    lines = [f"(define (problem {name})", f"  (:domain {domain})"]
    lines += [f"  (:objects\n    {_declare(objects, typed)})"]
    lines += ["  (:init", *(f"    {fact}" for fact in init), "  )"]
    lines += ["  (:goal (and", *(f"    {fact}" for fact in goal), "  ))"]
    if metric:
        lines.append("  (:metric minimize (total-cost))")
    lines.append(")")
    return Generated("\n".join(lines) + "\n", {k: list(v) for k, v in objects.items()})


# ------------------------------------------------------------------------------ blocks


def _towers(blocks: list[str], rng: random.Random) -> list[list[str]]:
    """The blocks in a random order, cut into towers of random heights (bottom first)."""
    order = blocks[:]
    rng.shuffle(order)
    towers: list[list[str]] = [[order[0]]]
    for block in order[1:]:
        if rng.random() < 0.35:
            towers.append([block])
        else:
            towers[-1].append(block)
    return towers


def gen_blocks(n: int, seed: int) -> Generated:
    """``n`` blocks in random towers, to be rebuilt as other random towers (the goal names
    only ``on`` facts, as IPC's blocks problems do)."""
    rng = random.Random(f"blocks-{n}-{seed}")
    blocks = [f"b{k}" for k in range(1, n + 1)]
    start = _towers(blocks, rng)
    while True:
        target = _towers(blocks, rng)
        goal = [f"(on {a} {b})" for tower in target for b, a in itertools.pairwise(tower)]
        held = {f"(on {a} {b})" for tower in start for b, a in itertools.pairwise(tower)}
        if goal and not set(goal) <= held:
            break
    init = ["(handempty)"]
    for tower in start:
        init.append(f"(ontable {tower[0]})")
        init += [f"(on {a} {b})" for b, a in itertools.pairwise(tower)]
        init.append(f"(clear {tower[-1]})")
    return _problem(f"blocks-{n}-s{seed}", "BLOCKS", {"object": blocks}, init, goal, typed=False)


# ----------------------------------------------------------------------------- gripper


def gen_gripper(n: int, seed: int) -> Generated:
    """One robot with two grippers, two rooms, ``n`` balls each in a random room, every
    ball to go to the other room; the robot starts in a random room."""
    rng = random.Random(f"gripper-{n}-{seed}")
    rooms, grippers = ["rooma", "roomb"], ["left", "right"]
    balls = [f"ball{k}" for k in range(1, n + 1)]
    start = {ball: rng.choice(rooms) for ball in balls}
    init = [f"(room {r})" for r in rooms] + [f"(gripper {g}) (free {g})" for g in grippers]
    init += [f"(ball {b}) (at {b} {start[b]})" for b in balls]
    init.append(f"(at-robby {rng.choice(rooms)})")
    goal = [f"(at {b} {rooms[1 - rooms.index(start[b])]})" for b in balls]
    objects = {"object": [*rooms, *balls, *grippers]}
    return _problem(f"gripper-{n}-s{seed}", "gripper-strips", objects, init, goal, typed=False)


# ---------------------------------------------------------------------------- visitall


def _connected_cells(cells: set[tuple[int, int]], start: tuple[int, int]) -> set[tuple[int, int]]:
    seen, todo = {start}, [start]
    while todo:
        x, y = todo.pop()
        for nxt in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
            if nxt in cells and nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


def gen_visitall(side: int, seed: int, holes: bool, half: bool) -> Generated:
    """A ``side`` x ``side`` grid; ``holes``: about a tenth of the cells missing (the rest
    stays connected); the goal: every cell visited, or (``half``) a random half of them."""
    rng = random.Random(f"visitall-{side}-{holes}-{half}-{seed}")
    cells = {(x, y) for x in range(side) for y in range(side)}
    start = (rng.randrange(side), rng.randrange(side))
    if holes:
        for _ in range(max(1, side * side // 10)):
            candidates = sorted(cells - {start})
            for cell in rng.sample(candidates, len(candidates)):
                rest = cells - {cell}
                if len(_connected_cells(rest, start)) == len(rest):
                    cells = rest
                    break

    def name(cell: tuple[int, int]) -> str:
        return f"cell-{cell[0]}-{cell[1]}"

    places = sorted(cells)
    init = [f"(at-robot {name(start)})", f"(visited {name(start)})"]
    for x, y in places:
        init += [
            f"(connected {name((x, y))} {name(n)})"
            for n in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1))
            if n in cells
        ]
    targets = places
    if half:
        targets = sorted(rng.sample(places, len(places) // 2))
    goal = [f"(visited {name(c)})" for c in targets]
    label = f"visitall-{side}-s{seed}"
    return _problem(label, "grid-visit-all", {"place": [name(c) for c in places]}, init, goal)


# ------------------------------------------------------------------------------ barman


def gen_barman(cocktails: int, shakers: int, seed: int) -> Generated:
    """IPC-style barman: ``cocktails`` cocktails of two distinct ingredients each, one goal
    shot per cocktail and one spare shot (shots = cocktails + 1), ``shakers`` shakers of
    two levels, three dispensers (four from five cocktails on), two hands. The domain has
    action costs: the total cost starts at 0 and the metric minimises it."""
    rng = random.Random(f"barman-{cocktails}-{shakers}-{seed}")
    n_ing = 3 if cocktails <= 4 else 4
    ingredients = [f"ingredient{k}" for k in range(1, n_ing + 1)]
    dispensers = [f"dispenser{k}" for k in range(1, n_ing + 1)]
    drinks = [f"cocktail{k}" for k in range(1, cocktails + 1)]
    shots = [f"shot{k}" for k in range(1, cocktails + 2)]
    shaker_names = [f"shaker{k}" for k in range(1, shakers + 1)]
    levels = ["l0", "l1", "l2"]
    init = ["(= (total-cost) 0)", "(handempty left)", "(handempty right)"]
    init += ["(next l0 l1)", "(next l1 l2)"]
    init += [f"(dispenses {d} {i})" for d, i in zip(dispensers, ingredients, strict=True)]
    for container in [*shaker_names, *shots]:
        init += [f"(ontable {container})", f"(clean {container})", f"(empty {container})"]
    init += [f"(shaker-empty-level {s} l0) (shaker-level {s} l0)" for s in shaker_names]
    for drink in drinks:
        first, second = rng.sample(ingredients, 2)
        init += [f"(cocktail-part1 {drink} {first})", f"(cocktail-part2 {drink} {second})"]
    order = drinks[:]
    rng.shuffle(order)
    goal = [f"(contains {shot} {drink})" for shot, drink in zip(shots, order, strict=False)]
    objects = {
        "shaker": shaker_names,
        "hand": ["left", "right"],
        "shot": shots,
        "ingredient": ingredients,
        "cocktail": drinks,
        "dispenser": dispensers,
        "level": levels,
    }
    label = f"barman-{cocktails}-{shakers}-s{seed}"
    return _problem(label, "barman", objects, init, goal, metric=True)


# ------------------------------------------------------------------------------ termes


def gen_termes(rows: int, cols: int, towers: int, height: int, seed: int) -> Generated:
    """A ``rows`` x ``cols`` board, flat; the depot on a random border cell, the robot on
    it without a block; ``towers`` towers of random heights 1..``height`` on distinct cells
    other than the depot; numbers 0..the highest tower. Goal: the towers, every other cell
    at 0, and no block in hand (as IPC's termes goals)."""
    rng = random.Random(f"termes-{rows}x{cols}-{towers}-{height}-{seed}")
    cells = [(r, c) for r in range(rows) for c in range(cols)]
    border = [(r, c) for r, c in cells if r in (0, rows - 1) or c in (0, cols - 1)]
    depot = rng.choice(border)
    spots = rng.sample([c for c in cells if c != depot], towers)
    goal_height = {cell: rng.randint(1, height) for cell in spots}
    top = max(goal_height.values())
    numbers = [f"n{k}" for k in range(top + 1)]

    def pos(cell: tuple[int, int]) -> str:
        return f"pos-{cell[0]}-{cell[1]}"

    init = [f"(height {pos(c)} n0)" for c in cells] + [f"(at {pos(depot)})"]
    init += [f"(SUCC n{k + 1} n{k})" for k in range(top)]
    for r, c in cells:
        for n in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
            if n in cells:
                init.append(f"(NEIGHBOR {pos((r, c))} {pos(n)})")
    init.append(f"(IS-DEPOT {pos(depot)})")
    goal = [f"(height {pos(c)} n{goal_height.get(c, 0)})" for c in cells]
    goal.append("(not (has-block))")
    objects = {"numb": numbers, "position": [pos(c) for c in cells]}
    label = f"termes-{rows}x{cols}-{towers}-{height}-s{seed}"
    return _problem(label, "termes", objects, init, goal)


# ----------------------------------------------------------------------------- storage


def gen_storage(depots: int, crates: int, hoists: int, seed: int) -> Generated:
    """Storage: ``depots`` depots, each a grid of store areas two rows deep and wide enough
    for its crates, its hoists and one free area; one container holding the ``crates``
    crates, one container area each; one load area joining every container area and two
    areas of each depot (its first and last of the first row). Hoists start on distinct
    depot areas (spread over the depots); each crate must end in a random depot."""
    rng = random.Random(f"storage-{depots}-{crates}-{hoists}-{seed}")
    goal_depot = [rng.randrange(depots) for _ in range(crates)]
    hoist_depot = [h % depots for h in range(hoists)]
    areas: list[str] = []
    init: list[str] = []
    free: list[str] = []
    hoist_at: list[str] = []
    for d in range(depots):
        need = goal_depot.count(d) + hoist_depot.count(d) + 1
        width = max(2, -(-need // 2))
        grid = [[f"depot{d}-{r}-{c}" for c in range(1, width + 1)] for r in (1, 2)]
        cells = [a for row in grid for a in row]
        areas += cells
        init += [f"(in {a} depot{d})" for a in cells]
        for r in range(2):
            for c in range(width):
                if c + 1 < width:
                    init += [f"(connected {grid[r][c]} {grid[r][c + 1]})",
                             f"(connected {grid[r][c + 1]} {grid[r][c]})"]  # fmt: skip
                if r == 0:
                    init += [f"(connected {grid[0][c]} {grid[1][c]})",
                             f"(connected {grid[1][c]} {grid[0][c]})"]  # fmt: skip
        for access in {grid[0][0], grid[0][-1]}:
            init += [f"(connected {access} loadarea)", f"(connected loadarea {access})"]
        starts = rng.sample(cells, hoist_depot.count(d))
        hoist_at += starts
        free += [a for a in cells if a not in starts]
    slots = [f"container-0-{k}" for k in range(crates)]
    areas += slots
    crate_names = [f"crate{k}" for k in range(crates)]
    for slot, crate in zip(slots, crate_names, strict=True):
        init += [f"(in {slot} container0)", f"(on {crate} {slot})", f"(in {crate} container0)",
                 f"(connected {slot} loadarea)", f"(connected loadarea {slot})"]  # fmt: skip
    init += [f"(clear {a})" for a in free]
    hoist_names = [f"hoist{h}" for h in range(hoists)]
    init += [f"(at {h} {a}) (available {h})" for h, a in zip(hoist_names, hoist_at, strict=True)]
    goal = [f"(in {c} depot{d})" for c, d in zip(crate_names, goal_depot, strict=True)]
    objects = {
        "storearea": areas,
        "hoist": hoist_names,
        "crate": crate_names,
        "container": ["container0"],
        "depot": [f"depot{d}" for d in range(depots)],
        "transitarea": ["loadarea"],
    }
    label = f"storage-{depots}-{crates}-{hoists}-s{seed}"
    return _problem(label, "Storage-Propositional", objects, init, goal)


# --------------------------------------------------------------------------- floortile


def gen_floortile(rows: int, cols: int, seed: int) -> Generated:
    """Floortile: ``rows`` rows of ``cols`` tiles to paint in a chessboard of white and
    black, below them one unpainted row 0 (as IPC's files have); two robots on distinct
    random tiles, each holding a random colour; both colours available. The domain has
    action costs: the total cost starts at 0 and the metric minimises it."""
    rng = random.Random(f"floortile-{rows}x{cols}-{seed}")
    tiles = [(r, c) for r in range(rows + 1) for c in range(1, cols + 1)]

    def tile(cell: tuple[int, int]) -> str:
        return f"tile-{cell[0]}-{cell[1]}"

    colours = ["white", "black"]
    robots = ["robot1", "robot2"]
    spots = rng.sample(tiles, 2)
    init = ["(= (total-cost) 0)", "(available-color white)", "(available-color black)"]
    for robot, spot in zip(robots, spots, strict=True):
        init += [f"(robot-at {robot} {tile(spot)})", f"(robot-has {robot} {rng.choice(colours)})"]
    init += [f"(clear {tile(t)})" for t in tiles if t not in spots]
    for r, c in tiles:
        if r + 1 <= rows:
            init += [f"(up {tile((r + 1, c))} {tile((r, c))})",
                     f"(down {tile((r, c))} {tile((r + 1, c))})"]  # fmt: skip
        if c + 1 <= cols:
            init += [f"(right {tile((r, c + 1))} {tile((r, c))})",
                     f"(left {tile((r, c))} {tile((r, c + 1))})"]  # fmt: skip
    goal = [f"(painted {tile((r, c))} {colours[(r + c) % 2]})" for r, c in tiles if r >= 1]
    objects = {"tile": [tile(t) for t in tiles], "robot": robots, "color": colours}
    label = f"floortile-{rows}x{cols}-s{seed}"
    return _problem(label, "floor-tile", objects, init, goal, metric=True)


# ------------------------------------------------------------------------------- sizes

Maker = Callable[[int], Generated]


def _visitall_sizes() -> list[tuple[str, Maker]]:
    sizes: list[tuple[str, Maker]] = []
    for side, holes, half in [(3, False, False), (4, True, False), (5, False, True),
                              (6, True, False), (7, True, True), (8, False, False)]:  # fmt: skip
        label = f"{side}x{side}" + (":holes" if holes else "") + (":half" if half else ":all")
        sizes.append((label, functools.partial(gen_visitall, side, holes=holes, half=half)))
    return sizes


SIZES: dict[str, list[tuple[str, Maker]]] = {
    "blocks": [(f"n{n}", functools.partial(gen_blocks, n)) for n in (4, 6, 8, 10, 12, 14)],
    "gripper": [(f"n{n}", functools.partial(gen_gripper, n)) for n in (4, 8, 12, 16, 20)],
    "visitall-sat11-strips": _visitall_sizes(),
    "barman-sat11-strips": [
        (f"c{c}:sh{k}", functools.partial(gen_barman, c, k))
        for c, k in ((3, 1), (4, 2), (5, 3), (6, 2))
    ],
    "termes-sat18-strips": [
        (f"{r}x{c}:t{t}:h{h}", functools.partial(gen_termes, r, c, t, h))
        for r, c, t, h in ((3, 3, 1, 2), (4, 3, 2, 2), (4, 4, 2, 3), (5, 4, 3, 3))
    ],
    "storage": [
        (f"d{d}:c{c}:h{h}", functools.partial(gen_storage, d, c, h))
        for d, c, h in ((1, 2, 1), (1, 4, 2), (2, 4, 2), (1, 5, 3), (2, 6, 3), (1, 8, 3))
    ],
    "floortile-sat11-strips": [
        (f"{r}x{c}", functools.partial(gen_floortile, r, c))
        for r, c in ((3, 3), (3, 4), (4, 3), (3, 5), (4, 4), (4, 5))
    ],
}
