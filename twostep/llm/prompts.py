"""The two prompts of TwoStep, rendered from the templates in ``twostep/prompts/``.

* Subgoal generator (:func:`generator_messages`): a system text (agent0 is the main agent,
  helpers get small independent parallel subgoals, release what they hold, "none" when
  no helper helps); the user text holds a fixed cross-domain example (a barman task with
  its single-agent plan, a second task and two helper subgoals), then the current
  domain's description, its example task with its single-agent plan, the current task,
  the subgoals already given to earlier helpers, and the request for the next one.
* Translator (:func:`translator_messages`): a system text (answer with the PDDL goal
  only); the user text holds the task's objects and initial state in PDDL, the task's
  own English goal with its PDDL goal as the example, and the English subgoal.

Templates use :class:`string.Template` (``$name``); rendering fails on a missing value,
so no placeholder is ever left unfilled.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from importlib import resources
from string import Template

from twostep.pddl import Goal, Problem, fact_to_pddl
from twostep.tasks.benchmark import BenchmarkTask

Message = dict[str, str]

TEMPLATES = (
    "generator_system",
    "generator_example",
    "generator_task",
    "translator_system",
    "translator_user",
)
_GOAL_INTRO = re.compile(r"^.*\byour goal\b", re.IGNORECASE | re.MULTILINE)


def template(name: str) -> Template:
    """The template ``twostep/prompts/<name>.txt``."""
    text = resources.files("twostep").joinpath("prompts", f"{name}.txt").read_text()
    return Template(text)


def _render(name: str, **values: object) -> str:
    return template(name).substitute({k: str(v) for k, v in values.items()}).strip()


def helper_names(agents: int) -> str:
    names = [f"agent{i}" for i in range(1, agents)]
    return ", ".join(names) if names else "none"


def domain_description(task: BenchmarkTask) -> str:
    """The domain's English description, or its action signatures when there is none."""
    if task.domain_nl.strip():
        return task.domain_nl.strip()
    domain = task.problem.domain
    actions = "\n".join(
        f"{a.name}({', '.join(f'{v} - {t}' for v, t in a.parameters)})"
        for a in domain.actions.values()
    )
    return f"The domain '{domain.name}' has these actions:\n{actions}"


def task_description(task: BenchmarkTask) -> str:
    """The task in English, or its PDDL when the ``.nl`` file is missing."""
    if task.task_nl.strip():
        return task.task_nl.strip()
    return problem_state_pddl(task.problem) + "\n" + goal_block(task.problem.goal)


def goal_description(task: BenchmarkTask) -> str:
    """The goal part of the task's English text (from "Your goal ..." on)."""
    text = task.task_nl.strip()
    match = _GOAL_INTRO.search(text)
    if match:
        return text[match.start() :].strip()
    return text or "Reach the goal below."


def example_plan_text(task: BenchmarkTask) -> str:
    steps = [step.strip().strip("()").strip() for step in task.example_plan]
    return "\n".join(steps) if steps else "(no example plan is available)"


def _natural(name: str) -> tuple[tuple[int, int | str], ...]:
    """Sort key that puts ``b2`` before ``b10``."""
    return tuple((0, int(p)) if p.isdigit() else (1, p) for p in re.split(r"(\d+)", name) if p)


def problem_state_pddl(problem: Problem) -> str:
    """The problem's objects and initial state in PDDL, without its goal."""
    by_type: dict[str, list[str]] = {}
    for name, type_name in sorted(problem.objects.items(), key=lambda item: _natural(item[0])):
        by_type.setdefault(type_name if problem.domain.typed else "", []).append(name)
    listing = " ".join(
        " ".join(names) + (f" - {type_name}" if type_name else "")
        for type_name, names in by_type.items()
    )
    lines = [f"(define (problem {problem.name})", f"  (:domain {problem.domain.name})"]
    lines.append(f"  (:objects {listing})")
    lines.append("  (:init")
    basic = (f for f in problem.init if not problem.domain.is_derived(f))  # not initial facts
    init = sorted(basic, key=lambda fact: tuple(_natural(term) for term in fact))
    lines += [f"    {fact_to_pddl(f)}" for f in init]
    lines.append("  )")
    return "\n".join(lines) + "\n)"


def goal_block(goal: Goal) -> str:
    """``goal`` as a ``(:goal (and ...))`` block, one literal per line (a goal formula that
    its literals do not spell out: as written)."""
    if not goal.is_conjunction:
        return f"(:goal\n  {goal.to_pddl()})"
    literals = [fact_to_pddl(f) for f in sorted(goal.positive)]
    literals += [f"(not {fact_to_pddl(f)})" for f in sorted(goal.negative)]
    body = "\n".join(f"    {lit}" for lit in literals)
    return f"(:goal\n  (and\n{body}))"


def earlier_text(earlier: Sequence[str], helper: int) -> str:
    if not earlier:
        return f"none yet: {('agent' + str(helper))} is the first helper."
    return "\n".join(f"agent{i}: {text}" for i, text in enumerate(earlier, start=1))


def generator_messages(
    task: BenchmarkTask,
    agents: int,
    helper: int,
    earlier: Sequence[str] = (),
    *,
    fixed_example: bool = True,
) -> list[Message]:
    """The generator prompt asking for the subgoal of helper ``helper`` (1-based).

    ``earlier`` holds the English subgoals of helpers 1..helper-1, in order.
    """
    if not 1 <= helper < agents:
        raise ValueError(f"helper must be in 1..{agents - 1} for {agents} agents, got {helper}")
    names = helper_names(agents)
    parts = [_render("generator_example")] if fixed_example else []
    parts.append(
        _render(
            "generator_task",
            domain_description=domain_description(task),
            example_task=task.example_nl.strip() or task.example_pddl.strip() or "(none)",
            example_plan=example_plan_text(task),
            task=task_description(task),
            agents=agents,
            n_helpers=agents - 1,
            helper_names=names,
            earlier=earlier_text(earlier, helper),
            helper=f"agent{helper}",
        )
    )
    return [
        {"role": "system", "content": _render("generator_system", helper_names=names)},
        {"role": "user", "content": "\n\n".join(parts)},
    ]


def translator_messages(task: BenchmarkTask, english: str) -> list[Message]:
    """The translator prompt for the English subgoal ``english``."""
    user = _render(
        "translator_user",
        problem_pddl=problem_state_pddl(task.problem),
        example_goal_nl=goal_description(task),
        example_goal_pddl=goal_block(task.problem.goal),
        subgoal=english.strip(),
    )
    return [
        {"role": "system", "content": _render("translator_system")},
        {"role": "user", "content": user},
    ]
