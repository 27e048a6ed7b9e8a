"""Tyreworld task generator: every hub has a flat tyre to replace by a spare from the boot.

Hub ``the-hubK`` carries the flat ``wK`` held by ``nutsK``; the intact, uninflated spare
``rK`` waits in the closed, unlocked ``boot`` with the tools. The tools (wrench, jack,
pump) are constants of the domain file, so the problem files do not declare them. The
goal puts every spare inflated on its hub with tight nuts, every flat and tool in the
boot, and the boot closed: 4 atoms per hub plus 4. The tasks are fully determined by
their number of hubs.
"""

from __future__ import annotations

from random import Random

from twostep.generators.sizes import TaskSize
from twostep.generators.spec import TaskSpec
from twostep.pddl import Fact

DOMAIN = "tyreworld"
SCALE_UNIT = "hubs"
TOOLS = ("wrench", "jack", "pump")  # the domain's constants, of type tool


def make_task(name: str, hubs: int) -> TaskSpec:
    """A car with ``hubs`` flat tyres."""
    ks = range(1, hubs + 1)
    objects = (
        tuple((f"the-hub{k}", "hub") for k in ks)
        + tuple((f"nuts{k}", "nut") for k in ks)
        + (("boot", "container"),)
        + tuple((wheel, "wheel") for k in ks for wheel in (f"r{k}", f"w{k}"))
    )
    init: list[Fact] = [("in", tool, "boot") for tool in TOOLS]
    init += [("unlocked", "boot"), ("closed", "boot")]
    goal: list[Fact] = []
    for k in ks:
        hub, nuts = f"the-hub{k}", f"nuts{k}"
        init += [
            ("intact", f"r{k}"),
            ("in", f"r{k}", "boot"),
            ("not-inflated", f"r{k}"),
            ("on", f"w{k}", hub),
            ("on-ground", hub),
            ("tight", nuts, hub),
            ("fastened", hub),
        ]
        goal += [
            ("on", f"r{k}", hub),
            ("inflated", f"r{k}"),
            ("tight", nuts, hub),
            ("in", f"w{k}", "boot"),
        ]
    goal += [("in", tool, "boot") for tool in TOOLS]
    goal.append(("closed", "boot"))
    return TaskSpec(name, DOMAIN, objects, tuple(init), tuple(goal))


def benchmark_task(name: str, size: TaskSize, rng: Random) -> TaskSpec:
    return make_task(name, size.count("hub"))


def example_task(name: str, rng: Random) -> TaskSpec:
    return make_task(name, 2)


def scaled_task(name: str, size: int, rng: Random) -> TaskSpec:
    """``size`` hubs."""
    return make_task(name, size)
