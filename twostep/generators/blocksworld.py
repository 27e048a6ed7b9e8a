"""Blocksworld task generator: random towers of blocks, a partial target arrangement.

The initial state is a random set of towers; the goal is ``goal_atoms`` facts
(``on`` or ``on-table``) drawn from another random arrangement, never all true at the
start. Blocks are ``b1 .. bN``. The PDDL domain is untyped (blocks are plain objects) and
named ``blocksworld-4ops``, as in the paper's task files, so that those files read with it
as they are; the folder and the generator keep the name ``blocksworld``.
"""

from __future__ import annotations

from itertools import pairwise
from random import Random

from twostep.generators.sizes import TaskSize
from twostep.generators.spec import TaskSpec, numbered
from twostep.pddl import Fact

DOMAIN = "blocksworld"
PDDL_NAME = "blocksworld-4ops"  # the name inside the PDDL (the paper's problems name it)
SCALE_UNIT = "blocks"


def random_towers(blocks: list[str], towers: int, rng: Random) -> list[list[str]]:
    """Split a shuffled copy of ``blocks`` into ``towers`` non-empty towers (bottom first)."""
    order = blocks[:]
    rng.shuffle(order)
    cuts = sorted(rng.sample(range(1, len(order)), towers - 1))
    bounds = [0, *cuts, len(order)]
    return [order[a:b] for a, b in pairwise(bounds)]


def tower_facts(towers: list[list[str]]) -> list[Fact]:
    """``on-table`` for each bottom block, then ``on`` for every block above another."""
    facts: list[Fact] = [("on-table", tower[0]) for tower in towers]
    for tower in towers:
        facts += [("on", top, below) for below, top in pairwise(tower)]
    return facts


def make_task(name: str, blocks: int, goal_atoms: int, rng: Random) -> TaskSpec:
    """``blocks`` blocks; a goal of ``goal_atoms`` ``on``/``on-table`` facts (<= blocks)."""
    names = [f"b{i}" for i in range(1, blocks + 1)]
    start = random_towers(names, rng.randint(1, blocks), rng)
    init = tower_facts(start)
    init += [("clear", tower[-1]) for tower in start]
    init.append(("arm-empty",))
    while True:
        # enough 'on' facts to fill the goal with them alone, as the benchmark's goals do
        target = random_towers(names, rng.randint(1, max(1, blocks - goal_atoms)), rng)
        candidates = [f for f in tower_facts(target) if f[0] == "on"] or tower_facts(target)
        goal = sorted(rng.sample(candidates, min(goal_atoms, len(candidates))), key=_block_order)
        if not set(goal) <= set(init):
            break
    objects = numbered("b", blocks, "block")  # the kind of object; the PDDL has no types
    return TaskSpec(
        name, DOMAIN, objects, tuple(init), tuple(goal), pddl_domain=PDDL_NAME, typed=False
    )


def _block_order(fact: Fact) -> tuple[int, ...]:
    return tuple(int(term[1:]) for term in fact[1:])


def benchmark_task(name: str, size: TaskSize, rng: Random) -> TaskSpec:
    return make_task(name, size.count("block"), size.goal_atoms, rng)


def example_task(name: str, rng: Random) -> TaskSpec:
    return make_task(name, 4, 2, rng)


def scaled_task(name: str, size: int, rng: Random) -> TaskSpec:
    """``size`` blocks whose goal is a complete arrangement in about size/5 towers."""
    return make_task(name, size, size - max(1, size // 5), rng)
