"""plan-deal on generated problems of the IPC sample's domains (not only the sample's p01).

Problem generators of our own, written from the domain files' semantics, for seven domains
of the IPC sample: blocks, gripper, visitall-sat11-strips, barman-sat11-strips,
termes-sat18-strips, storage and floortile-sat11-strips. The domain files are read from the
sample (``--sample``, default ../shared/ipc-sample): at run time each is copied into a
scratch folder and the generated problems are written beside it, so nothing of the sample
lands in the repository.

For each problem (sizes below, ``--seeds`` seeds each): the SA plan (lama-first,
``--time-limit`` s, the repo's planner; a problem it does not solve is skipped and
counted), then plan-deal for N = 2, 3, 4 (``--agents``) with the agent predicates of
:data:`AGENT_PREDICATES` (agents.yaml's, and the issue's for storage and floortile). Every
schedule, a fallback to the SA plan included, is re-validated by ``check_run`` and by the
independent validator on the generated files (``checkers``).

One row per problem: SA length, plan-deal length per N, the fallback reasons, both
verdicts, the dealing CPU seconds per N (plan-deal's own ``deal_seconds``: every phase after
the SA plan) and, in brackets, the CPU seconds of the whole ``run_plan_deal`` call measured
here (grounding the task and cleaning the plan included); then a summary per
domain: runs, dealt shorter than SA, fallbacks by reason, crashes, invalid schedules,
monotonicity violations (N longer than N-1, N = 1 being the SA plan) and the largest
dealing time.

    .venv/bin/python bench/bench_deal_generated.py --seeds 5 --json docs/bench/deal_generated.json
    .venv/bin/python bench/bench_deal_generated.py --domains storage --seeds 1 --sizes 1
    .venv/bin/python bench/bench_deal_generated.py --domains storage --only d1:c8:h3 \\
        --seed-list 1 --agents 2 --keep /tmp/generated

The last reproduces one row: ``--only`` takes the size label of the table, ``--seed-list``
the seed; ``--keep`` also writes the generated problem files into a folder.
"""

from __future__ import annotations

import argparse
import functools
import itertools
import random
import shutil
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench import record
from bench.bench_deal_ipc import (
    deal_seconds,
    deal_within,
    fallback_text,
    independent_verdict,
    our_verdict,
)
from checkers import IndependentValidator
from twostep.methods import MethodRequest, run_single_agent
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import BenchmarkTask, load_task

REPO = Path(__file__).resolve().parent.parent
SAMPLE = REPO.parent / "shared" / "ipc-sample"

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


# ------------------------------------------------------------------------------- runs


@dataclass
class Row:
    domain: str
    size: str
    seed: int
    sa: int | None = None
    lengths: dict[int, int | None] = field(default_factory=dict)  # None: crash
    fallbacks: dict[int, str] = field(default_factory=dict)
    ours: dict[int, str] = field(default_factory=dict)
    independent: dict[int, str] = field(default_factory=dict)
    cpu: dict[int, float] = field(default_factory=dict)  # plan-deal's own deal_seconds
    process_cpu: dict[int, float] = field(default_factory=dict)  # the whole call, measured here
    skipped: str = ""


def run_problem(
    task: BenchmarkTask,
    row: Row,
    preds: list[str],
    planner: PlannerSettings,
    agent_counts: Sequence[int],
    deal_limit: int,
) -> Row:
    sa = run_single_agent(MethodRequest(task, planner=planner))
    if sa.exec_length is None:
        row.skipped = f"no SA plan ({sa.message[:70]})"
        return row
    row.sa = sa.exec_length
    sa_plan = sa.planner_calls[0].result
    validator = IndependentValidator(task.domain_path, task.problem_path)
    for agents in agent_counts:
        request = MethodRequest(task, agents, planner, preds, sa_plan=sa_plan)
        start = time.process_time()
        run = deal_within(request, deal_limit, 90)
        if isinstance(run, str):
            row.lengths[agents] = None
            row.fallbacks[agents] = f"CRASH {run}"
            row.cpu[agents] = time.process_time() - start
            continue
        row.lengths[agents] = run.exec_length
        row.fallbacks[agents] = fallback_text(run, none="", width=90)
        row.ours[agents] = our_verdict(task, run, preds)
        row.independent[agents] = independent_verdict(validator, run, preds)
        row.cpu[agents] = deal_seconds(run)
        row.process_cpu[agents] = time.process_time() - start
    return row


def violations(row: Row, agent_counts: Sequence[int]) -> list[str]:
    """N longer than N-1 (N-1 = 1: the SA plan)."""
    found = []
    previous, label = row.sa, 1
    for agents in sorted(agent_counts):
        length = row.lengths.get(agents)
        if length is not None and previous is not None and length > previous:
            found.append(f"N={agents} {length} > N={label} {previous}")
        if length is not None:
            previous, label = length, agents
    return found


def format_row(row: Row, agent_counts: Sequence[int]) -> str:
    if row.skipped:
        return f"{row.domain} | {row.size} | {row.seed} | SKIPPED: {row.skipped}"
    lengths = "/".join(
        "CRASH" if row.lengths.get(n) is None else str(row.lengths[n]) for n in agent_counts
    )
    falls = "; ".join(f"N={n}: {row.fallbacks[n]}" for n in agent_counts if row.fallbacks.get(n))
    ours = _verdicts(row.ours, agent_counts)
    independent = _verdicts(row.independent, agent_counts)
    cpu = "/".join(f"{row.cpu.get(n, 0):.2f}" for n in agent_counts)
    cpu += " (call " + "/".join(f"{row.process_cpu.get(n, 0):.2f}" for n in agent_counts) + ")"
    cells = (row.domain, row.size, row.seed, row.sa, lengths, falls or "-", ours, independent, cpu)
    return " | ".join(str(c) for c in cells)


def _verdicts(verdicts: dict[int, str], agent_counts: Sequence[int]) -> str:
    """``ok`` when every N's verdict is ok (the checkers that read the files once), else each."""
    values = [verdicts.get(n, "-") for n in agent_counts]
    if all(v.startswith("ok") for v in values) and len(set(values)) == 1:
        return values[0]
    return "; ".join(f"N={n}: {v}" for n, v in zip(agent_counts, values, strict=True))


def summary(domain: str, rows: list[Row], agent_counts: Sequence[int]) -> list[str]:
    done = [r for r in rows if not r.skipped]
    runs = [(r, n) for r in done for n in agent_counts]
    shorter = sum(  # dealt: no fallback (the cleaned SA plan may be shorter than SA too)
        1
        for r, n in runs
        if not r.fallbacks.get(n) and (k := r.lengths.get(n)) is not None and k < (r.sa or 0)
    )
    reasons = Counter(r.fallbacks[n].split(" [")[0] for r, n in runs if r.fallbacks.get(n))
    crashes = sum(1 for r, n in runs if r.lengths.get(n) is None)
    invalid = sum(
        1
        for r, n in runs
        if "INVALID" in r.ours.get(n, "") or "INVALID" in r.independent.get(n, "")
    )
    monotone = sum(len(violations(r, agent_counts)) for r in done)
    slowest = max((r.cpu.get(n, 0.0) for r, n in runs), default=0.0)
    whole = max((r.process_cpu.get(n, 0.0) for r, n in runs), default=0.0)
    lines = [
        f"{domain}: {len(rows)} problems, {len(rows) - len(done)} skipped (no SA plan); "
        f"{len(runs)} runs, {shorter} dealt shorter than SA, {crashes} crashed, "
        f"{invalid} invalid, {monotone} monotonicity violations, max deal CPU {slowest:.2f} s "
        f"(the whole plan-deal call: {whole:.2f} s)"
    ]
    for reason, count in reasons.most_common():
        if not reason.startswith("CRASH"):
            lines.append(f"  fallback x{count}: {reason}")
    return lines


def problems(
    domain: str, seeds: Sequence[int], only: Sequence[str] | None, max_sizes: int | None
) -> Iterator[tuple[str, int, Generated]]:
    sizes = SIZES[domain][:max_sizes] if max_sizes else SIZES[domain]
    for label, make in sizes:
        if only and label not in only:
            continue
        for seed in seeds:
            yield label, seed, make(seed)


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of plan-deal beyond the benchmark (bench.results): a figure of this
    bench's rows (plan-deal's length against the SA plan's, per N), then what each of the
    records printed (this bench's, bench_deal_ipc's, bench_deal_budget's, bench_dealing's)."""
    from matplotlib.figure import Figure

    rows = records[0]["rows"]
    column = next((c for c in rows[0] if c.startswith("plan-deal N=")), "") if rows else ""
    agents = column.removeprefix("plan-deal N=").split("/") if column else []
    fig = Figure(figsize=(6.4, 4.2))
    axes = fig.subplots()
    top = 1
    for k, n in enumerate(agents):
        points = [(int(r["SA"]), int(r[column].split("/")[k])) for r in rows
                  if r.get("SA", "").isdigit() and r.get(column, "").count("/") == len(agents) - 1]  # fmt: skip
        if points:
            top = max(top, *(sa for sa, _ in points))
            axes.scatter(*zip(*points, strict=True), s=12, alpha=0.6, label=f"N = {n}")
    axes.plot([0, top], [0, top], color="grey", linewidth=0.8, label="as long as SA")
    axes.set_xlabel("SA plan length")
    axes.set_ylabel("plan-deal exec length")
    axes.set_title("plan-deal on generated problems (seven IPC domains)")
    axes.legend()
    fig.tight_layout()
    alt = "plan-deal's exec length against the SA plan's length on the generated problems"
    return [figure(fig, "generated", alt), "", *record.printed_page(records, figure)]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sample", type=Path, default=SAMPLE)
    parser.add_argument("--domains", nargs="*", default=list(SIZES), choices=list(SIZES))
    parser.add_argument("--seeds", type=int, default=2, help="seeds per size: 1..SEEDS")
    parser.add_argument("--seed-list", type=int, nargs="*", help="these seeds instead")
    parser.add_argument("--sizes", type=int, help="only the first SIZES sizes of each domain")
    parser.add_argument("--only", nargs="*", help="only these size labels (as in the table)")
    parser.add_argument("--agents", type=int, nargs="*", default=[2, 3, 4])
    parser.add_argument("--time-limit", type=float, default=30.0, help="SA planner seconds")
    parser.add_argument("--deal-limit", type=int, default=60, help="seconds per plan-deal run")
    parser.add_argument("--keep", type=Path, help="also write the generated files here")
    parser.add_argument("--json", type=Path, help="also write what it prints as a record here")
    args = parser.parse_args(argv)
    with record.capture(args.json, title="plan-deal on generated problems of seven IPC domains"):
        return _run(args, argv)


def _run(args: argparse.Namespace, argv: Sequence[str] | None) -> int:
    seeds = args.seed_list or list(range(1, args.seeds + 1))
    planner = PlannerSettings("lama-first", args.time_limit)
    shown = " ".join(argv if argv is not None else sys.argv[1:])
    print(f".venv/bin/python bench/bench_deal_generated.py {shown}".rstrip())
    print(f"sample domains of {args.sample.name}, problems of our own generators; "
          f"SA lama-first {args.time_limit:g} s; plan-deal N = "
          f"{'/'.join(map(str, args.agents))}")  # fmt: skip
    header = ("domain", "size", "seed", "SA", "plan-deal N=" + "/".join(map(str, args.agents)),
              "fallback", "check_run", "independent validator", "deal CPU s (whole call)")  # fmt: skip
    print(" | ".join(header), flush=True)
    began = time.perf_counter()
    summaries: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp)
        for domain in args.domains:
            folder = scratch / domain
            folder.mkdir()
            shutil.copy(args.sample / domain / "domain.pddl", folder / "domain.pddl")
            rows = []
            for number, (label, seed, generated) in enumerate(
                problems(domain, seeds, args.only, args.sizes), 1
            ):
                path = folder / f"p{number:02d}.pddl"
                path.write_text(generated.text)
                if args.keep:
                    (args.keep / domain).mkdir(parents=True, exist_ok=True)
                    kept = f"{label.replace(':', '_')}-s{seed}.pddl"
                    shutil.copy(path, args.keep / domain / kept)
                row = Row(domain, label, seed)
                try:
                    task = load_task(domain, number, scratch)
                    run_problem(task, row, AGENT_PREDICATES[domain], planner, args.agents,
                                args.deal_limit)  # fmt: skip
                except Exception as error:  # the SA run or the reading: the row says so
                    row.skipped = f"error {type(error).__name__}: {str(error)[:90]}"
                rows.append(row)
                print(format_row(row, args.agents), flush=True)
                for found in violations(row, args.agents):
                    print(f"  monotonicity: {found}")
            summaries += summary(domain, rows, args.agents)
    print("summary per domain:")
    print("\n".join(summaries))
    print(f"total {time.perf_counter() - began:.0f} s wall")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
