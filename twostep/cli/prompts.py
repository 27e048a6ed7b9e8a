"""``twostep-prompts``: print the rendered TwoStep prompts of a benchmark task.

Shows the subgoal generator prompt (system + user) for one helper, with placeholders for
the subgoals of earlier helpers, and the translator prompt for an example subgoal. No LLM
is called.

    twostep-prompts --domain blocksworld --task 5 --agents 3 [--helper 1] [--data data]
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from pathlib import Path

from twostep.cli import console_main
from twostep.llm.prompts import (
    Message,
    generator_messages,
    goal_description,
    translator_messages,
)
from twostep.pddl import PDDLError
from twostep.programs.processes import ResourceLimitError
from twostep.tasks.benchmark import DEFAULT_DATA_ROOT, BenchmarkError, load_task

PLACEHOLDER = "<the subgoal generated for agent{}>"


def example_subgoal(task_goal_nl: str) -> str:
    """A sentence of the task's English goal, used as the translator's example input."""
    lines = [line.strip() for line in task_goal_nl.splitlines()[1:] if line.strip()]
    if lines:
        return re.sub(r"\bshould be\b", "is", lines[0]).rstrip(".")
    return "<English subgoal from the generator>"


def _show(title: str, messages: Sequence[Message]) -> str:
    out = []
    for message in messages:
        out.append(f"===== {title}: {message['role']} =====")
        out.append(message["content"])
        out.append("")
    return "\n".join(out)


@console_main
def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="twostep-prompts", description="Print the TwoStep LLM prompts of a task."
    )
    parser.add_argument("--domain", required=True)
    parser.add_argument("--task", type=int, required=True, help="task number, e.g. 5 for p05")
    parser.add_argument("--agents", type=int, default=2, help="N, including the main agent")
    parser.add_argument("--helper", type=int, default=1, help="which helper's prompt (1..N-1)")
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA_ROOT, help="data root")
    parser.add_argument("--subgoal", help="English subgoal for the translator prompt")
    parser.add_argument(
        "--no-fixed-example", action="store_true", help="leave out the fixed barman example"
    )
    args = parser.parse_args(argv)
    if args.agents < 2:
        parser.error("--agents must be at least 2 (one main agent and one helper)")
    if not 1 <= args.helper < args.agents:
        parser.error(f"--helper must be in 1..{args.agents - 1}")
    try:
        task = load_task(args.domain, args.task, args.data)
    except (BenchmarkError, PDDLError, ResourceLimitError) as exc:
        print(f"twostep-prompts: error: {exc}", file=sys.stderr)
        return 2
    earlier = [PLACEHOLDER.format(i) for i in range(1, args.helper)]
    generator = generator_messages(
        task, args.agents, args.helper, earlier, fixed_example=not args.no_fixed_example
    )
    subgoal = args.subgoal or example_subgoal(goal_description(task))
    translator = translator_messages(task, subgoal)
    print(f"# {task.name}, N = {args.agents}: prompts for agent{args.helper}\n")
    print(_show(f"subgoal generator, agent{args.helper}", generator))
    print(_show("translator", translator))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
