"""Barman task generator: cocktails to serve in shot glasses, three shakers.

Each cocktail is a random ordered pair of two different ingredients out of three (no two
cocktails alike while the six pairs last); each dispenser gives one ingredient.
Everything starts clean, empty and on the table with both hands free. The goal serves
``goal_atoms`` shots (every cocktail at least once when there are enough goal atoms);
one shot or more stays spare. Shakers hold two shots of liquid (levels ``l0 < l1 < l2``).
"""

from __future__ import annotations

from itertools import pairwise, permutations
from random import Random

from twostep.generators.sizes import BARMAN_SHAKERS, TaskSize
from twostep.generators.spec import TaskSpec, numbered
from twostep.pddl import Fact

DOMAIN = "barman"
SCALE_UNIT = "cocktails"
INGREDIENTS = 3
LEVELS = ("l0", "l1", "l2")


def make_task(
    name: str,
    cocktails: int,
    shots: int,
    goal_atoms: int,
    rng: Random,
    shakers: int = BARMAN_SHAKERS,
) -> TaskSpec:
    """``cocktails`` recipes, ``shots`` glasses of which ``goal_atoms`` (< shots) get served."""
    ingredients = [f"ingredient{i}" for i in range(1, INGREDIENTS + 1)]
    objects = (
        ("left", "hand"),
        ("right", "hand"),
        *numbered("shaker", shakers, "shaker"),
        *numbered("shot", shots, "shot"),
        *numbered("ingredient", INGREDIENTS, "ingredient"),
        *numbered("cocktail", cocktails, "cocktail"),
        *numbered("dispenser", INGREDIENTS, "dispenser"),
        *((level, "level") for level in LEVELS),
    )
    init: list[Fact] = [("handempty", "left"), ("handempty", "right")]
    for container in [f"shaker{i}" for i in range(1, shakers + 1)] + [
        f"shot{i}" for i in range(1, shots + 1)
    ]:
        init += [("ontable", container), ("clean", container), ("empty", container)]
    for i in range(1, shakers + 1):
        init += [("shaker-empty-level", f"shaker{i}", "l0"), ("shaker-level", f"shaker{i}", "l0")]
    init += [("next", low, high) for low, high in pairwise(LEVELS)]
    dispensed = ingredients[:]
    rng.shuffle(dispensed)
    init += [("dispenses", f"dispenser{i}", ing) for i, ing in enumerate(dispensed, start=1)]
    recipes = list(permutations(ingredients, 2))  # distinct while there are enough of them
    rng.shuffle(recipes)
    for c in range(1, cocktails + 1):
        first, second = recipes[(c - 1) % len(recipes)]
        init += [
            ("cocktail-part1", f"cocktail{c}", first),
            ("cocktail-part2", f"cocktail{c}", second),
        ]
    drinks = list(range(1, cocktails + 1))
    rng.shuffle(drinks)
    drinks = drinks[:goal_atoms]
    drinks += [rng.randint(1, cocktails) for _ in range(goal_atoms - len(drinks))]
    served = sorted(rng.sample(range(1, shots + 1), goal_atoms))
    goal = [("contains", f"shot{s}", f"cocktail{c}") for s, c in zip(served, drinks, strict=True)]
    return TaskSpec(name, DOMAIN, objects, tuple(init), tuple(goal))


def benchmark_task(name: str, size: TaskSize, rng: Random) -> TaskSpec:
    return make_task(name, size.count("cocktail"), size.count("shot"), size.goal_atoms, rng)


def example_task(name: str, rng: Random) -> TaskSpec:
    return make_task(name, 1, 2, 1, rng)


def scaled_task(name: str, size: int, rng: Random) -> TaskSpec:
    """``size`` cocktails, each served once, one spare shot."""
    return make_task(name, size, size + 1, size, rng)
