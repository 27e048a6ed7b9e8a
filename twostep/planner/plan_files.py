"""Fast Downward's plan files: found, read, and trusted only when complete.

The search writes a plan file action by action and ends it with a trailer line
``; cost = N (unit cost)`` or ``; cost = N (general cost)``. A file without that last
line was cut off (the wall-clock guard killed the search mid-write, or the disk filled)
and is not a plan; Fast Downward's own ``driver/plan_manager.py`` deletes such files.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

# As in plan_manager.py: the line must end with its newline, or it was cut off too.
_TRAILER = re.compile(r"; cost = (\d+) \((unit cost|general cost)\)\n")


@dataclass(frozen=True)
class PlanFile:
    """A complete plan file: its actions and the cost its trailer states."""

    path: Path
    actions: tuple[str, ...]
    cost: int
    general_cost: bool
    """True for ``(general cost)``: the domain has action costs."""


def read_plan_file(path: Path) -> PlanFile | None:
    """The plan in ``path``, or None when the file is incomplete (no cost trailer)."""
    lines = path.read_text().splitlines(keepends=True)
    match = _TRAILER.fullmatch(lines[-1]) if lines else None
    if match is None:
        return None
    steps = (line.split(";", 1)[0].strip() for line in lines)
    # "(flip-all )": Fast Downward writes a space before the parenthesis of a 0-ary action
    actions = tuple(" ".join(step.split()).replace(" )", ")") for step in steps if step)
    return PlanFile(path, actions, int(match[1]), match[2] == "general cost")


def plan_files(folder: Path, name: str = "plan") -> list[Path]:
    """The plan files in ``folder``: ``plan``, or ``plan.1``, ``plan.2``, ... in order."""
    single = folder / name
    if single.is_file():
        return [single]
    numbered = [p for p in folder.glob(f"{name}.*") if p.suffix[1:].isdigit()]
    return sorted(numbered, key=lambda p: int(p.suffix[1:]))


def complete_plans(folder: Path, name: str = "plan") -> list[PlanFile]:
    """Every complete plan file, in the order written (an anytime search's best is last)."""
    plans = (read_plan_file(path) for path in plan_files(folder, name))
    return [plan for plan in plans if plan is not None]
