"""Seeded generators of the benchmark tasks (the ``data/`` folder) and of larger tasks.

Each domain module (barman, blocksworld, grippers, termes, tyreworld) turns sizes into a
:class:`~twostep.generators.spec.TaskSpec`; this module assembles whole folders in the
LLM+P layout as ``{file name: text}`` without touching the disk (the ``twostep-data``
command writes them). Every task draws from its own RNG, seeded by
``"{seed}:{domain}:{index}"``, so one task can be rebuilt alone and the output is
byte-identical from run to run. Static files (domain PDDL, its English description and the
example's single-agent plan) live in ``domains/`` beside this module.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from importlib import resources
from random import Random
from types import ModuleType

from twostep.generators import barman, blocksworld, grippers, termes, tyreworld
from twostep.generators.describe import describe_problem
from twostep.generators.sizes import BENCHMARK_SIZES, TaskSize
from twostep.generators.spec import TaskSpec
from twostep.pddl import Domain, Goal, Problem, parse_problem

EXAMPLE = "p_example"


@dataclass(frozen=True)
class DomainGenerator:
    """The task makers of one domain."""

    name: str
    benchmark: Callable[[str, TaskSize, Random], TaskSpec]
    example: Callable[[str, Random], TaskSpec]
    scaled: Callable[[str, int, Random], TaskSpec]
    scale_unit: str  # what the scale generator's size counts


def _generator(module: ModuleType) -> DomainGenerator:
    return DomainGenerator(
        module.DOMAIN,
        module.benchmark_task,
        module.example_task,
        module.scaled_task,
        module.SCALE_UNIT,
    )


GENERATORS: dict[str, DomainGenerator] = {
    g.name: g for g in map(_generator, (barman, blocksworld, grippers, termes, tyreworld))
}
DOMAINS = tuple(GENERATORS)


def task_rng(seed: int, domain: str, index: int | str) -> Random:
    """The RNG of one task: independent of every other task and of Python's hash seed."""
    return Random(f"{seed}:{domain}:{index}")


def static_file(domain: str, suffix: str) -> str:
    """A file shipped in ``domains/``: ``<domain>.pddl``, ``.nl`` or ``.example.sol``."""
    return (resources.files(__package__) / "domains" / f"{domain}{suffix}").read_text()


def task_name(domain: str, stem: str) -> str:
    return f"{domain}-{stem}".replace("_", "-")


def benchmark_task(domain: str, index: int, seed: int = 0) -> TaskSpec:
    """Task ``index`` (1-based, p01..p20) of ``domain``."""
    size = BENCHMARK_SIZES[domain][index - 1]
    stem = f"p{index:02d}"
    return GENERATORS[domain].benchmark(
        task_name(domain, stem), size, task_rng(seed, domain, index)
    )


def example_task(domain: str, seed: int = 0) -> TaskSpec:
    """The small in-context example task of ``domain`` (``p_example``)."""
    return GENERATORS[domain].example(task_name(domain, EXAMPLE), task_rng(seed, domain, EXAMPLE))


def scaled_task(domain: str, size: int, index: int = 1, seed: int = 0) -> TaskSpec:
    """Task ``index`` of the larger family of ``domain`` with ``size`` units."""
    rng = task_rng(seed, domain, f"scale{size}:{index}")
    return GENERATORS[domain].scaled(task_name(domain, f"s{size}-{index:02d}"), size, rng)


@cache
def domain_model(domain: str) -> Domain:
    """The parsed PDDL domain of ``domain`` (parsed once per process: it is a static file)."""
    example = example_task(domain)
    return parse_problem(static_file(domain, ".pddl"), example.to_pddl()).domain


def as_problem(task: TaskSpec, domain: Domain) -> Problem:
    """The parsed form of ``task`` without going through PDDL text (fast, same result)."""
    goal = Goal(frozenset(task.goal), frozenset(task.negative_goal))
    return Problem(task.name, domain, task.pddl_objects(), frozenset(task.init), goal)


def task_files(stem: str, task: TaskSpec, domain: Domain) -> dict[str, str]:
    """``<stem>.pddl`` and its English description ``<stem>.nl``."""
    nl = describe_problem(as_problem(task, domain), task.domain)
    return {f"{stem}.pddl": task.to_pddl(), f"{stem}.nl": nl}


def domain_files(domain: str) -> dict[str, str]:
    """The domain, its description and the in-context example with its plan.

    The example is always built from seed 0: its plan is a static file.
    """
    files = {"domain.pddl": static_file(domain, ".pddl"), "domain.nl": static_file(domain, ".nl")}
    files.update(task_files(EXAMPLE, example_task(domain), domain_model(domain)))
    files[f"{EXAMPLE}.sol"] = static_file(domain, ".example.sol")
    return files


def benchmark_files(domain: str, seed: int = 0) -> dict[str, str]:
    """Every file of ``data/<domain>/`` except the hand-written ``expert.yaml``."""
    files, model = domain_files(domain), domain_model(domain)
    for index in range(1, len(BENCHMARK_SIZES[domain]) + 1):
        files.update(task_files(f"p{index:02d}", benchmark_task(domain, index, seed), model))
    return files


def scale_files(domain: str, size: int, count: int = 1, seed: int = 0) -> dict[str, str]:
    """A folder of ``count`` larger tasks (p01..) in the same layout as ``data/<domain>``."""
    files, model = domain_files(domain), domain_model(domain)
    for index in range(1, count + 1):
        files.update(task_files(f"p{index:02d}", scaled_task(domain, size, index, seed), model))
    return files


__all__ = [
    "DOMAINS",
    "EXAMPLE",
    "GENERATORS",
    "DomainGenerator",
    "as_problem",
    "benchmark_files",
    "benchmark_task",
    "domain_files",
    "domain_model",
    "example_task",
    "scale_files",
    "scaled_task",
    "static_file",
    "task_files",
    "task_rng",
]
