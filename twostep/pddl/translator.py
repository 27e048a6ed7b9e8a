"""Grounding a task with Fast Downward's own translator, run as a program.

One semantics with the planner: what twostep plans, progresses and scores is the task
Fast Downward grounds from the same files, so the grounding is the planner's own. The
translator ships with the up-fast-downward wheel (:mod:`twostep.downward`); it is GPL-3
like the planner, so it runs at arm's length, as a subprocess writing ``output.sas``,
which :mod:`twostep.pddl.sas` reads (0.1-0.6 s per IPC task here, start-up included).

Options, and why:

- ``--full-encoding``: every value is named after its atom (the facts of the model);
- ``--keep-unimportant-variables``: keep facts that do not lead to the goal (a helper's
  subgoal or a hand-off state may need them);
- ``--keep-no-ops``: keep actions without effects (a plan may name them);
- ``--invariant-generation-max-candidates 0``: no mutex invariants, so every variable is
  one atom, true or false, and every delete effect a single fact, exactly as in PDDL
  (multi-valued variables would only say "the variable's atom that held", which states
  assembled from two agents' facts need not respect);
- ``--skip-variable-reordering``: the order of variables does not matter here.

A goal that is not reachable even when deletes are ignored makes the translator write an
empty, unsolvable task; the grounding is then redone with an empty goal, so that the
actions are still there (a hand-off problem or a subgoal may well be solvable).
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from twostep.downward import translator_path
from twostep.pddl.errors import PDDLError

TRANSLATOR_OPTIONS = (
    "--full-encoding",
    "--keep-unimportant-variables",
    "--keep-no-ops",
    "--invariant-generation-max-candidates",
    "0",
    "--skip-variable-reordering",
)
TRANSLATOR_TIMEOUT_S = 300.0
_UNREACHABLE_GOAL = "No relaxed solution"


@dataclass(frozen=True)
class Translation:
    """The translator's output for one domain and problem."""

    sas: str
    """The text of ``output.sas``."""
    goal_unreachable: bool
    """Whether the translator found the goal unreachable (the task it wrote is empty)."""


@functools.lru_cache(maxsize=32)
def translate(domain_text: str, problem_text: str) -> Translation:
    """Run the translator on a domain and a problem given as text.

    Raises :class:`PDDLError` with the translator's own last words when it rejects the
    input (tasks are checked by the lifted reader first, which names file and line).
    """
    with tempfile.TemporaryDirectory(prefix="twostep-translate-") as tmp:
        folder = Path(tmp)
        (folder / "domain.pddl").write_text(domain_text)
        (folder / "problem.pddl").write_text(problem_text)
        env = dict(os.environ, PYTHONPATH=str(translator_path()))
        command = [
            sys.executable,
            "-m",
            "fast_downward.translate",
            "domain.pddl",
            "problem.pddl",
            "--sas-file",
            "output.sas",
            *TRANSLATOR_OPTIONS,
        ]
        try:
            done = subprocess.run(
                command,
                cwd=folder,
                env=env,
                capture_output=True,
                text=True,
                timeout=TRANSLATOR_TIMEOUT_S,
                check=False,
            )
        except subprocess.TimeoutExpired:
            raise PDDLError(
                f"Fast Downward's translator did not finish in {TRANSLATOR_TIMEOUT_S:.0f} s"
            ) from None
        output = done.stdout + done.stderr
        sas = folder / "output.sas"
        if done.returncode != 0 or not sas.is_file():
            tail = [line.strip() for line in output.splitlines() if line.strip()][-2:]
            raise PDDLError(
                "Fast Downward's translator rejects the task"
                f" (exit {done.returncode}): {' | '.join(tail) or 'no output'}"
            )
        return Translation(sas.read_text(), _UNREACHABLE_GOAL in output)
