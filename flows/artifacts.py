"""The files a job leaves in its Hydra job directory, which MLflow then stores as artifacts.

Layout (docs/tracking.md)::

    result.json              the run's result (RunResult.to_dict() + job key and timings)
    schedule.txt             the joint schedule, one column per agent
    plans/<agent>.plan       each agent's plan, one action per line
    subgoals/helper<k>.pddl  each helper's PDDL subgoal (TwoStep)
    llm/helper<k>.json       every prompt and answer behind helper k's subgoal (LLM)
    embodied/trace.json      executor=embodied: every agent's primitive per step, the floor plan
    embodied/kitchen.gif     ... the kitchen animated (agents, what they hold, where they go)
    embodied/timeline.png    ... agents x steps, coloured navigate / interact / wait / backoff
    error.txt                traceback of a job that raised (not an artifact)

Only ``result.json`` is written under that name: the reports read every result.json
below a sweep directory.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from flows.console import format_schedule
from twostep.embodied.run import GIF_NAME, TIMELINE_NAME, TRACE_KEY
from twostep.util.files import write_json_atomic

EMBODIED_FOLDER = "embodied"


def write_job_files(
    job_dir: Path, result: Mapping[str, Any], pictures: bool = True
) -> list[tuple[Path, str | None]]:
    """Write the job's files; return (file, artifact folder) pairs to log, result.json last.
    ``pictures``: draw an embodied execution's GIF and timeline
    (:func:`twostep.embodied.draws_pictures`).

    result.json goes last so that, in MLflow as on disk, its presence means the rest is there.
    """
    job_dir.mkdir(parents=True, exist_ok=True)
    files: list[tuple[Path, str | None]] = []
    plans = result.get("plans") or {}
    if plans:
        folder = job_dir / "plans"
        folder.mkdir(exist_ok=True)
        for agent, steps in sorted(plans.items()):
            path = folder / f"{agent}.plan"
            path.write_text("".join(f"{step}\n" for step in steps))
            files.append((path, "plans"))
    schedule = result.get("schedule") or []
    if schedule:
        path = job_dir / "schedule.txt"
        table = format_schedule(result)
        if not table:  # one agent: the plan is the schedule
            table = "\n".join(
                f"{t:>4}  " + "  ".join(f"{agent}: {action}" for agent, action in step)
                for t, step in enumerate(schedule, start=1)
            )
        path.write_text(table + "\n")
        files.append((path, None))
    for subgoal in result.get("subgoals") or []:
        helper = subgoal.get("helper")
        if subgoal.get("pddl"):
            folder = job_dir / "subgoals"
            folder.mkdir(exist_ok=True)
            path = folder / f"helper{helper}.pddl"
            comment = f"; helper {helper}: {subgoal.get('status')}"
            if subgoal.get("reason"):
                comment += f" ({subgoal['reason']})"
            path.write_text(f"{comment}\n{subgoal['pddl']}\n")
            files.append((path, "subgoals"))
        if subgoal.get("exchanges"):
            path = job_dir / "llm" / f"helper{helper}.json"
            write_json_atomic(path, {k: subgoal.get(k) for k in _LLM_KEYS})
            files.append((path, "llm"))
    files += _embodied_files(job_dir, result, pictures)
    path = job_dir / "result.json"
    write_json_atomic(path, {k: v for k, v in result.items() if k != TRACE_KEY})
    files.append((path, None))
    return files


def _embodied_files(
    job_dir: Path, result: Mapping[str, Any], pictures: bool
) -> list[tuple[Path, str | None]]:
    """The embodied trace (result.json keeps only its summary) and, with ``pictures``, its
    two pictures."""
    recorded = result.get(TRACE_KEY)
    if not isinstance(recorded, Mapping):
        return []
    folder = job_dir / EMBODIED_FOLDER
    path = folder / "trace.json"
    write_json_atomic(path, dict(recorded))
    files: list[tuple[Path, str | None]] = [(path, EMBODIED_FOLDER)]
    if not pictures:
        return files
    from twostep.embodied import write_pictures

    # Hydra logs INFO to the console; matplotlib's "Animation.save using ..." is noise there.
    logging.getLogger("matplotlib").setLevel(logging.WARNING)
    try:
        drawn = write_pictures(result, folder)
    except Exception as error:  # a picture is not worth the job: the trace is kept
        print(f"warning: embodied pictures not drawn: {error}", file=sys.stderr)
        return files
    return files + [(p, EMBODIED_FOLDER) for p in drawn.values()]


def picture_paths(job_dir: Path) -> list[tuple[str, Path]]:
    """The job's pictures that exist, labelled for the terminal."""
    folder = job_dir / EMBODIED_FOLDER
    named = (("timeline", folder / TIMELINE_NAME), ("animation", folder / GIF_NAME))
    return [(label, path) for label, path in named if path.is_file()]


_LLM_KEYS = ("helper", "english", "pddl", "status", "reason", "llm_time_s", "exchanges")
