"""AlfWorld's own engine as a judge: replay plans, and embodied traces' actions in step
order, in TextWorld's PDDL game (the engine AlfWorld's text games run on).

The game is AlfWorld's: the ``alfworld`` wheel's ``alfred.pddl`` and ``alfred.twl2``
grammar with the problem as it is (a trace's bodies replace the task's agent, as in
:mod:`checkers.trace_check`). Each step is looked up among the ground actions the engine
itself finds applicable in its current state and applied there (its text commands name no
agent, so they cannot tell two agents apart); the engine says whether the goal is won.

The engine lives in a virtual environment of its own (``make alfworld-engine`` makes
``.venv-alfworld``: TextWorld 1.7.0 and the Fast Downward it builds, offline once
installed), because its ``fast-downward-textworld`` installs a ``fast_downward`` package
over the one our planner's translator comes from. This file is both sides: run as a
script by that environment's Python, it replays one JSON request from stdin; imported, it
sends the request. Only the standard library is imported at the top.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ENGINE_ENV = "TWOSTEP_ALFWORLD_PYTHON"  # the engine's Python, if not .venv-alfworld's
ENGINE_VENV = ".venv-alfworld"


@dataclass(frozen=True)
class EngineReplay:
    """How far the engine followed the steps, and whether it says the goal is won."""

    steps: int
    applied: int
    won: bool
    failure: str = ""

    @property
    def ok(self) -> bool:
        return self.applied == self.steps and self.won and not self.failure


def engine_python() -> Path | None:
    """The Python of the engine's environment: $TWOSTEP_ALFWORLD_PYTHON, else
    ``.venv-alfworld`` in the working directory or the project's root."""
    if os.environ.get(ENGINE_ENV):
        return Path(os.environ[ENGINE_ENV])
    for root in (Path.cwd(), Path(__file__).resolve().parent.parent):
        candidate = root / ENGINE_VENV / "bin" / "python"
        if candidate.is_file():
            return candidate
    return None


def game_files() -> tuple[str, str] | None:
    """``alfred.pddl`` and ``alfred.twl2`` of the installed alfworld wheel (not imported)."""
    spec = importlib.util.find_spec("alfworld")
    if spec is None or not spec.submodule_search_locations:
        return None
    data = Path(next(iter(spec.submodule_search_locations))) / "data"
    files = data / "alfred.pddl", data / "alfred.twl2"
    if not all(f.is_file() for f in files):
        return None
    return files[0].read_text(), files[1].read_text()


def replay(problem_text: str, steps: Sequence[str], timeout_s: float = 300) -> EngineReplay:
    """Issue ``steps`` (``(action arg ...)`` in alfred.pddl's terms) one by one in
    AlfWorld's game of ``problem_text``, in the engine's environment."""
    python, files = engine_python(), game_files()
    if python is None or files is None:
        raise RuntimeError(
            "AlfWorld's engine is not installed: make alfworld-engine (and the 'embodied' extra)"
        )
    request = {
        "domain": files[0],
        "grammar": files[1],
        "problem": problem_text,
        "steps": list(steps),
    }
    done = subprocess.run(
        [str(python), str(Path(__file__).resolve())],
        input=json.dumps(request),
        capture_output=True,
        text=True,
        timeout=timeout_s,
        check=False,
    )
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"AlfWorld's engine failed: {last}")
    answer = json.loads(done.stdout.strip().splitlines()[-1])
    return EngineReplay(
        len(steps), int(answer["applied"]), bool(answer["won"]), str(answer["failure"])
    )


def trace_steps(record: Mapping[str, Any]) -> list[str]:
    """A trace's applied actions in step order (one agent after another within a step)."""
    return [str(t["applied"]) for t in record["trace"] if t.get("applied")]


def replay_trace(
    record: Mapping[str, Any], problem_text: str, plays: Mapping[str, str]
) -> EngineReplay:
    """Replay an embodied trace's actions in the game of its bodies (``plays``: body ->
    the task agent it plays, :func:`checkers.trace_check.who_plays`)."""
    from checkers.trace_check import body_problem

    files = game_files()
    if files is None:
        raise RuntimeError("the alfworld wheel's game files are missing (extra 'embodied')")
    return replay(body_problem(files[0], problem_text, plays), trace_steps(record))


# ------------------------------------------------------------ the engine's side


def _engine_replay(request: Mapping[str, Any]) -> dict[str, Any]:
    """Replay in TextWorld's PDDL state (AlfWorld's game logic over Fast Downward's
    successor generator); its text commands name no agent, so steps are matched to the
    engine's applicable ground operators (``name arg ...``)."""
    import fast_downward
    from textworld.envs.pddl import logic

    game = logic.GameLogic(domain=request["domain"], grammar=request["grammar"])
    state = logic.PddlState(fast_downward.load_lib(), request["problem"], game)
    for index, step in enumerate(request["steps"]):
        wanted = " ".join(step.strip("() \n").lower().split())
        applicable = {
            " ".join(a.name.lower().split() + [v.name.lower() for v in a.mapping.values()]): a
            for a in state.all_applicable_actions()
        }
        if wanted not in applicable:
            return {
                "applied": index,
                "won": False,
                "failure": f"step {index + 1} {step}: not applicable",
            }
        state.apply(applicable[wanted])
    return {"applied": len(request["steps"]), "won": bool(state.check_goal()), "failure": ""}


if __name__ == "__main__":
    print(json.dumps(_engine_replay(json.loads(sys.stdin.read()))))
