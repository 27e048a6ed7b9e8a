"""Data roots the tests lay out: LLM+P-shaped folders of tasks, ALFWorld layouts."""

from __future__ import annotations

import shutil
from pathlib import Path

from checkers.trace_check import alfworld_layouts_folder
from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from tests.examples import TWO_TOWERS


def make_root(tmp_path: Path) -> Path:
    folder = tmp_path / "blocks"
    folder.mkdir()
    (folder / "domain.pddl").write_text(BLOCKS_DOMAIN)
    (folder / "domain.nl").write_text("Blocks on a table.")
    (folder / "p01.pddl").write_text(
        blocks_problem(
            "(on-table a) (clear a) (on-table b) (clear b) (arm-empty)", "(on a b)", "a b"
        )
    )
    (folder / "p01.nl").write_text("Put a on b.")
    (folder / "p03.pddl").write_text(
        blocks_problem("(on-table a) (clear a) (arm-empty)", "(holding a)", "a")
    )
    (folder / "p_example.sol").write_text("(pickup a)\n; cost = 1 (unit cost)\n")
    return tmp_path


def make_data(root: Path) -> Path:
    """blocksworld p01 (3 blocks), p02 (two towers: goal-split helps), p03 (one block)."""
    make_blocksworld_data(root)
    folder = root / "blocksworld"
    (folder / "p02.pddl").write_text(TWO_TOWERS)
    (folder / "p03.pddl").write_text(
        blocks_problem("(on-table a) (clear a) (arm-empty)", "(holding a)", "a")
    )
    (folder / "p04.pddl").write_text(
        "(define (problem broken) (:domain blocks) (:init (on-table a)"
    )
    return root


def make_blocksworld_data(root: Path) -> Path:
    """A one-task blocksworld data root in the LLM+P layout."""
    folder = root / "blocksworld"
    folder.mkdir(parents=True)
    (folder / "domain.pddl").write_text(BLOCKS_DOMAIN)
    (folder / "domain.nl").write_text(DOMAIN_NL)
    (folder / "p01.pddl").write_text(
        blocks_problem(
            "(arm-empty) (on-table a) (on-table c) (on b c) (clear a) (clear b)",
            "(on a b) (on c a)",
            "a b c",
        )
    )
    (folder / "p01.nl").write_text(TASK_NL)
    (folder / "p_example.pddl").write_text(
        blocks_problem(
            "(arm-empty) (on-table a) (on-table b) (clear a) (clear b)", "(on b a)", "a b"
        )
    )
    (folder / "p_example.nl").write_text(EXAMPLE_NL)
    (folder / "p_example.sol").write_text("(pickup b)\n(stack b a)\n; cost = 2\n")
    return root


DOMAIN_NL = "Blocks sit on a table or on each other; one arm picks up and stacks clear blocks."


TASK_NL = (
    "You have 3 blocks: a, b and c.\nb is on top of c.\na and c are on the table.\n"
    "Your goal is to rearrange the blocks so that:\na should be on top of b.\n"
    "c should be on top of a."
)


EXAMPLE_NL = "You have 2 blocks: a and b.\nYour goal is to rearrange the blocks so that:\nb on a."


def alfred_root(tmp: Path, problem_text: str | None = None) -> Path:
    """A data root with the wheel's alfred.pddl beside our problem."""
    folder = tmp / "alfred"
    folder.mkdir(parents=True)
    wheel = Path(str(alfworld_layouts_folder())).parent.parent / "data" / "alfred.pddl"
    shutil.copy(wheel, folder / "domain.pddl")
    (folder / "p01.pddl").write_text(problem_text or ALFRED_P01.read_text())
    return tmp


ALFRED_P01 = (
    Path(__file__).resolve().parent.parent / "fixtures" / "alfred_scene" / "alfred" / "p01.pddl"
)
