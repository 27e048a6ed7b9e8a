"""``expert``: hand-written helper subgoals from ``<data>/<domain>/expert.yaml``.

The file maps a task (``p01``) to a number of agents and the list of helper goals in
PDDL, as a PDDL expert annotated them for the paper's TwoStep-Human ablation::

    p01:
      2:
        - "(and (on-table b2) (arm-empty))"

A task or agent count without an entry gets no helper (TwoStep returns the SA plan).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from twostep.decomposers.base import DecompositionRequest, SubgoalProposal
from twostep.tasks.benchmark import BenchmarkError
from twostep.util.files import FileFormatError, NotTextError, exists, read_yaml_file


def load_expert_subgoals(path: Path) -> dict[str, dict[int, list[str]]]:
    """``{"p01": {N: [subgoal of helper 1, ...]}}`` from an ``expert.yaml`` (none: empty);
    a file that cannot be read that way is a :class:`BenchmarkError` naming it."""
    if not exists(path):
        return {}
    try:
        raw: Any = read_yaml_file(path) or {}
        return {
            str(task): {int(n): [str(g) for g in goals or []] for n, goals in (per_n or {}).items()}
            for task, per_n in raw.items()
        }
    except (NotTextError, FileFormatError) as error:
        raise BenchmarkError(str(error)) from None
    except OSError as error:
        raise BenchmarkError(f"{path}: cannot be read ({error.strerror or error})") from None
    except (AttributeError, TypeError, ValueError):
        raise BenchmarkError(
            f"{path}: expected 'p01: {{N: [helper 1's subgoal, ...]}}' entries"
        ) from None


class ExpertDecomposer:
    name = "expert"

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        table = load_expert_subgoals(request.task.domain_path.parent / "expert.yaml")
        goals = table.get(f"p{request.task.task_id:02d}", {}).get(request.agents, [])
        return [
            SubgoalProposal(helper=i, pddl=g)
            for i, g in enumerate(goals[: request.agents - 1], start=1)
        ]
