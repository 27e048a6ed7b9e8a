"""Logs in the official TwoStep code's format, written by the tests (never the official
files): :func:`block` renders one task's block as that code prints it, with answers and
numbers the tests choose, about twostep's own ``data/`` tasks."""

from __future__ import annotations

from collections.abc import Sequence

SEPARATOR = "-" * 40


def block(
    domain: str,
    task: int,
    answers: Sequence[str],
    *,
    sa_cost: float = 6.0,
    helper_costs: Sequence[float | None] | None = None,
    main_cost: float = 4.0,
    length: float = 5.0,
    run: int = 1000,
    crash_after_answers: bool = False,
    before_answers: Sequence[str] = (),
    translations: Sequence[str] = (),
) -> str:
    """One task's block (ends with the separator line)."""
    agents = len(answers) + 1
    lines = [
        f"[info][singleagent][{domain}] task {task:02d} takes 0.12 sec, found a plan with cost {sa_cost}"
    ]
    lines += list(before_answers)
    lines.append(repr(list(answers)))
    for goal in translations:
        lines += ["old (:goal", goal, ")", f"cleaned (:goal {goal} )"]
    if crash_after_answers:
        lines += [
            "list index out of range",
            "Traceback (most recent call last):",
            "FileNotFoundError: [Errno 2] No such file or directory: 'p01_1_validation.txt'",
            SEPARATOR,
        ]
        return "\n".join(lines) + "\n"
    costs = list(helper_costs) if helper_costs is not None else [2.0] * len(answers)
    for i, cost in enumerate(costs, start=1):
        outcome = "no solution found" if cost is None else f"found a plan with cost {cost}"
        lines += [
            f"[info][subgoal_{i}][{domain}] task {task:02d} takes 0.13 sec, {outcome}",
            "validating",
            "validator time 0.006",
        ]
    lines += [
        f"[info][multiagent main goal][{domain}] task {task:02d} takes 0.12 sec, found a plan with cost {main_cost}",
        f"TASK: {domain} - {run} - {task:02d}",
        f"{length} True",
        f"[results][{domain}][{task:02d}]",
        f"[single_agent][planning time: 0.12][cost: {sa_cost}]",
        f"[multi_agent][planning_time: 2.5][cost: {length}][agents: {agents}][optimization time 0.1]",
        SEPARATOR,
    ]
    return "\n".join(lines) + "\n"
