"""Reading the run logs of the official TwoStep code (``--format twostep-official``).

The official code (its ``helper_script*.py`` run through ``run_experiments.sh``) prints,
per task, a block of lines ended by a line of dashes. What this reader takes from a block:

* ``[info][singleagent][DOMAIN] task NN takes T sec, found a plan with cost C`` (or
  ``..., no solution found``): the domain, the task and the single-agent plan;
* the model's helper subgoals, one Python list literal of N-1 strings on one line, e.g.
  ``['b2 is clear and on the table.']`` (any text the model printed before it, e.g. its
  reasoning about how many agents to use, is skipped);
* ``[info][subgoal_I][DOMAIN] task NN takes T sec, found a plan with cost C``: helper I's
  plan for the model's own translation (``no solution found``: none);
* ``[info][multiagent main goal][...]``: the main agent's plan;
* ``TASK: DOMAIN - RUN - NN`` (the run label) and ``LENGTH True|False`` (the official
  execution length and whether its joint execution validated);
* ``[results][DOMAIN][NN]``, ``[single_agent][planning time: T][cost: C]`` and
  ``[multi_agent][planning_time: T][cost: L][agents: N]...``: the official numbers;
* ``cleaned (:goal ...)``: the model's PDDL translation of a helper's subgoal, printed by
  some versions of the code (one per helper, in order).

Everything else (tracebacks, planner output, progress lines) is skipped. A block whose run
crashed before the answers holds no answers and is counted, not imported; one that
crashed after them is imported with the numbers it has. A line that starts like one of
the lines above but does not parse, answers without a task, two answer lists in one
block, a count of agents that contradicts the answers, or a log that ends inside a block
(truncated) is a :class:`LogFormatError` naming ``file:line``.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from twostep.replay.bundle import Answer, OfficialNumbers

FORMAT = "twostep-official"

_NUMBER = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf|nan"
_PLAN_OUTCOME = rf"takes (?P<time>{_NUMBER}) sec, (?:found a plan with cost (?P<cost>{_NUMBER})|no solution found)"
_INFO = re.compile(
    r"^\[info\]\[(?P<what>singleagent|subgoal_(?P<helper>\d+)|multiagent main goal)\]"
    rf"\[(?P<domain>[^\]]+)\] task (?P<task>\d+) {_PLAN_OUTCOME}\s*$"
)
_TASK = re.compile(r"^TASK: (?P<domain>\S+) - (?P<run>\S+) - (?P<task>\d+)\s*$")
_LENGTH = re.compile(rf"^(?P<length>{_NUMBER}) (?P<valid>True|False)\s*$")
_RESULTS = re.compile(r"^\[results\]\[(?P<domain>[^\]]+)\]\[(?P<task>\d+)\]\s*$")
_SINGLE = re.compile(
    rf"^\[single_agent\]\[planning time: (?P<time>{_NUMBER})\]\[cost: (?P<cost>{_NUMBER})\]\s*$"
)
_MULTI = re.compile(
    rf"^\[multi_agent\]\[planning_time: (?P<time>{_NUMBER})\]\[cost: (?P<cost>{_NUMBER})\]"
    rf"\[agents: (?P<agents>\d+)\](?:\[optimization time (?P<opt>{_NUMBER})\])?\s*$"
)
_CLEANED = re.compile(r"^cleaned (?P<goal>\(.*)$")
_SEPARATOR = re.compile(r"^-{20,}\s*$")
# Lines that announce one of the records above: they must parse.
_ANNOUNCES = ("[info][", "[results][", "[single_agent][", "[multi_agent][", "TASK:")


class LogFormatError(ValueError):
    """A log that is not in the format (``file:line: what``)."""


@dataclass
class LogEntry:
    """One task block's answers and numbers, as read from the log."""

    domain: str
    task: int
    agents: int
    line: int
    answers: tuple[Answer, ...]
    official: OfficialNumbers
    translations: tuple[str | None, ...] = ()
    run_label: str | None = None


@dataclass
class ParsedLog:
    """What a log holds: its entries, and the blocks that hold no answers."""

    path: Path
    entries: list[LogEntry] = field(default_factory=list)
    blocks: int = 0
    without_answers: list[int] = field(default_factory=list)  # first lines of those blocks

    @property
    def run_labels(self) -> list[str]:
        return list(dict.fromkeys(e.run_label for e in self.entries if e.run_label))


def _float(text: str | None) -> float | None:
    if text is None:
        return None
    value = float(text)
    return None if value != value else value  # nan: nothing known


def _blocks(
    lines: list[str], name: str, allow_truncated: bool = False
) -> Iterator[tuple[int, list[tuple[int, str]]]]:
    """(first line, [(line number, text)]) of every block that ends with a separator; a
    last block without one is an error, or (``allow_truncated``) left out."""
    block: list[tuple[int, str]] = []
    for number, text in enumerate(lines, start=1):
        if _SEPARATOR.match(text):
            if any(t.strip() for _, t in block):
                yield block[0][0], block
            block = []
        else:
            block.append((number, text))
    content = [(n, t) for n, t in block if t.strip()]
    if content and not allow_truncated:
        raise LogFormatError(
            f"{name}:{content[0][0]}: truncated log: the block that starts here has no "
            "end line (a line of dashes) after it; import the blocks before it with "
            "--allow-truncated"
        )


def _answer_list(text: str, where: str) -> list[str] | None:
    """The subgoal list on this line, None if the line is not one; malformed: an error."""
    stripped = text.strip()
    if not (stripped.startswith(("['", '["')) or stripped == "[]"):
        return None
    try:
        value = ast.literal_eval(stripped)
    except (ValueError, SyntaxError):
        raise LogFormatError(
            f"{where}: malformed subgoal list (not a Python list of strings, or cut short)"
        ) from None
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise LogFormatError(f"{where}: malformed subgoal list (not a list of strings)")
    return value


@dataclass
class _Block:
    """What one block says, filled line by line."""

    name: str
    domain: str | None = None
    task: int | None = None
    answers_line: int | None = None
    answers: list[str] | None = None
    sa_cost: float | None = None
    sa_time: float | None = None
    helper_costs: dict[int, float | None] = field(default_factory=dict)
    main_cost: float | None = None
    exec_length: float | None = None
    valid: bool | None = None
    planning_time: float | None = None
    agents: int | None = None
    agents_line: int | None = None
    run_label: str | None = None
    translations: list[str] = field(default_factory=list)
    no_plan: list[int] = field(default_factory=list)
    helper_times: dict[int, float | None] = field(default_factory=dict)

    def task_is(self, domain: str, task: int, where: str) -> None:
        """Every line of a block names the same task; the first one sets it."""
        if self.domain is None:
            self.domain, self.task = domain, task
        elif (self.domain, self.task) != (domain, task):
            raise LogFormatError(
                f"{where}: names {domain} task {task:02d} inside the block of "
                f"{self.domain} task {self.task:02d} (a missing end line?)"
            )

    def read(self, number: int, text: str) -> None:
        where = f"{self.name}:{number}"
        line = text.rstrip("\n")
        listed = _answer_list(line, where)
        if listed is not None:
            if self.answers is not None:
                raise LogFormatError(
                    f"{where}: a second subgoal list in one block (the first at line "
                    f"{self.answers_line}; a missing end line?)"
                )
            if self.domain is None:
                raise LogFormatError(
                    f"{where}: subgoals without a task (no '[info][singleagent][DOMAIN] "
                    "task NN' line before them in the block)"
                )
            self.answers, self.answers_line = listed, number
            return
        if match := _INFO.match(line):
            self.task_is(match["domain"], int(match["task"]), where)
            cost = _float(match["cost"])
            if match["what"] == "singleagent":
                self.sa_cost, self.sa_time = cost, _float(match["time"])
            elif match["helper"] is not None:
                self.helper_costs[int(match["helper"])] = cost
                self.helper_times[int(match["helper"])] = _float(match["time"])
                if cost is None:
                    self.no_plan.append(int(match["helper"]))
            else:
                self.main_cost = cost
        elif match := _TASK.match(line):
            self.task_is(match["domain"], int(match["task"]), where)
            self.run_label = match["run"]
        elif match := _RESULTS.match(line):
            self.task_is(match["domain"], int(match["task"]), where)
        elif match := _SINGLE.match(line):
            self.sa_time, self.sa_cost = _float(match["time"]), _float(match["cost"])
        elif match := _MULTI.match(line):
            self.planning_time = _float(match["time"])
            self.exec_length = _float(match["cost"])
            self.agents, self.agents_line = int(match["agents"]), number
        elif match := _LENGTH.match(line):
            self.valid = match["valid"] == "True"
        elif match := _CLEANED.match(line):
            self.translations.append(match["goal"].strip())
        elif line.startswith(_ANNOUNCES):
            raise LogFormatError(f"{where}: malformed line '{line[:80]}'")

    def entry(self) -> LogEntry | None:
        if self.answers is None or self.domain is None or self.task is None:
            return None
        assert self.answers_line is not None
        agents = len(self.answers) + 1
        if self.agents is not None and self.agents != agents:
            raise LogFormatError(
                f"{self.name}:{self.agents_line}: agents: {self.agents} does not match the "
                f"{len(self.answers)} subgoal(s) at line {self.answers_line} (N-1 expected)"
            )
        answers = tuple(
            Answer(i, text, self.answers_line) for i, text in enumerate(self.answers, start=1)
        )
        helpers = len(self.answers)
        official = OfficialNumbers(
            sa_cost=self.sa_cost,
            sa_time_s=self.sa_time,
            helper_costs=tuple(self.helper_costs.get(i) for i in range(1, helpers + 1))
            if self.helper_costs
            else (),
            helper_no_plan=tuple(sorted(set(self.no_plan))),
            helper_times_s=tuple(self.helper_times.get(i) for i in range(1, helpers + 1))
            if self.helper_times
            else (),
            main_cost=self.main_cost,
            exec_length=self.exec_length,
            planning_time_s=self.planning_time,
            valid=self.valid,
        )
        translations: tuple[str | None, ...] = ()
        if len(self.translations) == helpers:
            translations = tuple(self.translations)
        return LogEntry(
            domain=self.domain,
            task=self.task,
            agents=agents,
            line=self.answers_line,
            answers=answers,
            official=official,
            translations=translations,
            run_label=self.run_label,
        )


def parse_log(path: Path, text: str, allow_truncated: bool = False) -> ParsedLog:
    """Every task block of a log in the official format (``text``: the file's content,
    ``path``: its name in messages). Raises :class:`LogFormatError` naming ``file:line``;
    ``allow_truncated`` leaves out a last block the log ends inside instead. A block whose
    answer list is empty (the model chose one agent) has nothing to replay: it is counted
    with the blocks without answers."""
    name = str(path)
    parsed = ParsedLog(path=Path(path))
    seen: dict[tuple[str, int, int, str | None], int] = {}
    for first, lines in _blocks(text.splitlines(), name, allow_truncated):
        parsed.blocks += 1
        block = _Block(name)
        for number, line in lines:
            block.read(number, line)
        entry = block.entry()
        if entry is None or not entry.answers:
            parsed.without_answers.append(first)
            continue
        key = (entry.domain, entry.task, entry.agents, entry.run_label)
        if key in seen:
            raise LogFormatError(
                f"{name}:{entry.line}: {entry.domain} task {entry.task:02d} with "
                f"{entry.agents} agents appears twice in one run (first at line {seen[key]})"
            )
        seen[key] = entry.line
        parsed.entries.append(entry)
    return parsed
