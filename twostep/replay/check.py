"""The rules translator against the logs: does our reading of each replayed subgoal give a
helper plan of the cost the official code logged for the model's own translation?

For every entry of a bundle, :func:`check_entry` replays what the official code did with
its helpers, with the rules translator (:mod:`twostep.english`) in place of the model's
translation: helper i's English answer is read (:func:`twostep.llm.parsing.
parse_english_subgoal`), translated, and planned from the environment the helpers before
it left (their plans progress it; agent facts are each agent's own), with the planner
settings given (the official runs': anytime LAMA, 100 s). Its plan's length is compared
with the cost the log records for that helper. The official code planned whatever goal
the model wrote, so the translated goal is planned whenever it is a goal of the task
(twostep's own discard rules, e.g. a repeat of an earlier helper's subgoal, are recorded
as ``rule`` but do not stop the comparison); a goal already true costs 0.

Two things of the official code are read as it did them: it logs an empty plan (a goal
that already holds) as "no solution found", so a cost of 0 matches a "no solution" logged
well before its time limit (under 90 % of the check's limit, which is the official runs'
by default); and where a model's answer goes on to another helper's subgoal ("...
\n agent3 subgoal: ..."), the official code translated the whole answer while twostep
reads the helper's own part: such rows say so (``continued``), and so do the later helpers
of that task, which the official code started from the state after both goals
(``after_continued``).

:func:`summarise` gives, per domain: subgoals, how many translate, and of those with a
logged cost how many give that cost. A different cost is kept beside its subgoal.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Collection, Iterable
from dataclasses import asdict, dataclass
from typing import Any

from twostep.english import translate_english
from twostep.llm.parsing import continuation, extract_pddl_goal, parse_english_subgoal
from twostep.pddl import Goal
from twostep.planner import PlannerSettings, PlanResult, plan
from twostep.plans.progression import environment_part, handoff_problem, progress_state
from twostep.plans.simulate import Grounder
from twostep.plans.subgoals import SubgoalError, check_subgoal, parse_subgoal
from twostep.replay.bundle import Answer, Entry
from twostep.tasks.benchmark import BenchmarkTask

# Known causes of a cost other than the log's
CONTINUED = "continued"  # the answer went on to another helper's subgoal (translated whole)
OFFICIAL_LIMIT = "official_limit"  # the official call ran to its limit without a plan
AFTER_CONTINUED = "after_continued"  # an earlier helper's answer went on: another start
WHY = {
    CONTINUED: "the answer goes on to another helper's subgoal, which the official code "
    "translated with it",
    AFTER_CONTINUED: "an earlier helper's answer of the task went on to another subgoal: the "
    "official helper before this one planned both, so this one started from another state",
    OFFICIAL_LIMIT: "the official planner call ran to its time limit without a plan, where "
    "this reading is planned (its own translation, not logged, asked for something else)",
}

# What became of one replayed subgoal
MATCH = "match"  # translated, planned: the logged cost (or no plan, as logged)
DIFFERS = "differs"  # translated, planned: another cost than the log's
UNTRANSLATED = "untranslated"  # the rules could not read it (or no condition in the answer)
NOT_LOGGED = "not_logged"  # translated, but the log has no cost to compare with


@dataclass(frozen=True)
class SubgoalCheck:
    """One replayed subgoal: its reading, its plan's cost and the logged one."""

    run: str
    domain: str
    task: int
    agents: int
    helper: int
    line: int
    answer: str
    condition: str | None
    pddl: str | None
    status: str
    reason: str | None  # why untranslated, or twostep's own rule that would discard it
    logged_cost: float | None
    logged_no_plan: bool
    cost: float | None  # None: no plan found
    planner: str | None  # the planner's status
    seconds: float = 0.0
    continued: bool = False  # the answer went on to another helper's subgoal
    logged_time_s: float | None = None  # the official planner call's time
    why: str | None = None  # a known cause of a different cost (WHY)
    # where the log prints the model's own translation: whether ours is the same goal
    same_as_logged: bool | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class _RowMaker:
    """The fields of a check row that one answer fixes; called with the rest."""

    entry: Entry
    answer: Answer
    logged: float | None
    no_plan: bool
    logged_time: float | None
    start: float

    def __call__(self, **fields: Any) -> SubgoalCheck:
        base: dict[str, Any] = {
            "run": self.entry.run,
            "domain": self.entry.domain,
            "task": self.entry.task,
            "agents": self.entry.agents,
            "helper": self.answer.helper,
            "line": self.answer.line,
            "answer": self.answer.text,
            "condition": None,
            "pddl": None,
            "status": UNTRANSLATED,
            "reason": None,
            "logged_cost": self.logged,
            "logged_no_plan": self.no_plan,
            "cost": None,
            "planner": None,
            "continued": continuation(self.answer.text) is not None,
            "logged_time_s": self.logged_time,
        }
        base.update(fields)
        base["seconds"] = round(time.perf_counter() - self.start, 3)
        return SubgoalCheck(**base)


def _plan_length(result: PlanResult) -> float | None:
    return float(len(result.plan)) if result.solved and result.plan is not None else None


def check_entry(
    entry: Entry,
    task: BenchmarkTask,
    agent_predicates: Collection[str],
    settings: PlannerSettings,
    planner: Callable[[Any, PlannerSettings], PlanResult] = plan,
) -> list[SubgoalCheck]:
    """Every helper of ``entry`` on ``task`` (see the module docstring)."""
    problem = task.problem
    environment = environment_part(problem.init, agent_predicates)
    goals: dict[int, Goal] = {}
    checks: list[SubgoalCheck] = []
    official = entry.official
    went_on = False  # an earlier answer of this task went on to another helper's subgoal
    for answer in entry.answers:
        start = time.perf_counter()
        helper = answer.helper
        logged = (
            official.helper_costs[helper - 1] if helper - 1 < len(official.helper_costs) else None
        )
        no_plan = helper in official.helper_no_plan
        times = official.helper_times_s
        logged_time = times[helper - 1] if helper - 1 < len(times) else None
        # an empty plan is logged as "no solution found", in about no time
        empty_logged = (
            no_plan and logged_time is not None and logged_time < 0.9 * settings.search_time_limit_s
        )

        row = _RowMaker(entry, answer, logged, no_plan, logged_time, start)
        after_continued, went_on = went_on, went_on or continuation(answer.text) is not None

        try:
            parsed = parse_english_subgoal(answer.text, helper, problem)
        except SubgoalError as error:
            checks.append(row(reason=f"no condition in the answer: {error}"))
            continue
        if parsed.kind != "subgoal" or parsed.text is None:
            checks.append(row(reason="the answer is 'none'"))
            continue
        translation = translate_english(problem, parsed.text, task.domain_name)
        if translation.pddl is None:
            checks.append(row(condition=parsed.text, reason=translation.reason))
            continue
        try:
            goal = parse_subgoal(translation.pddl, problem)
        except SubgoalError as error:
            checks.append(row(condition=parsed.text, pddl=translation.pddl, reason=str(error)))
            continue
        helper_problem = handoff_problem(problem, environment, goal, agent_predicates)
        rule: str | None = None
        try:
            check_subgoal(translation.pddl, problem, start=helper_problem.init, earlier=goals)
        except SubgoalError as error:
            rule = str(error)
        result = planner(helper_problem, settings)
        cost = _plan_length(result)
        if cost is not None and result.plan is not None:
            grounded = Grounder(helper_problem).ground_plan(result.plan)
            environment = progress_state(helper_problem.init, grounded, agent_predicates)
            goals[helper] = goal
        if logged is None and not no_plan:
            status = NOT_LOGGED
        elif (
            (cost is None and no_plan)
            or (cost == 0 and empty_logged)
            or (cost is not None and cost == logged)
        ):
            status = MATCH
        else:
            status = DIFFERS
        why = None
        if status == DIFFERS and continuation(answer.text) is not None:
            why = CONTINUED
        elif status == DIFFERS and no_plan and not empty_logged and cost is not None:
            why = OFFICIAL_LIMIT
        elif status == DIFFERS and after_continued:
            why = AFTER_CONTINUED
        checks.append(
            row(
                condition=parsed.text,
                pddl=translation.pddl,
                status=status,
                reason=rule,
                cost=cost,
                planner=result.status.value,
                why=why,
                same_as_logged=_same_goal(entry, helper, goal, problem),
            )
        )
    return checks


def _same_goal(entry: Entry, helper: int, goal: Goal, problem: Any) -> bool | None:
    """Whether ``goal`` is the goal of the model's own translation the log printed for
    this helper (None: the log prints none, or not a goal of the task)."""
    if helper > len(entry.translations) or entry.translations[helper - 1] is None:
        return None
    text = extract_pddl_goal(str(entry.translations[helper - 1]))
    try:
        logged = parse_subgoal(text, problem) if text else None
    except SubgoalError:
        return False
    if logged is None:
        return False
    return (logged.positive, logged.negative) == (goal.positive, goal.negative)


def summarise(checks: Iterable[SubgoalCheck]) -> list[dict[str, Any]]:
    """Per domain (and all): subgoals, translated (count, %), with a logged cost, giving
    it (count, % of the translated ones with a logged cost), differing (and why, where a
    cause is known: :data:`WHY`; ``differs_known``, ``differs_other``);
    ``match_pct_comparable`` leaves the known ones out."""
    rows: dict[str, dict[str, Any]] = {}
    for check in checks:
        for key in (check.domain, "all"):
            row = rows.setdefault(
                key,
                {
                    "domain": key, "subgoals": 0, "translated": 0, "compared": 0, "match": 0,
                    "differs": 0, "differs_continued": 0, "differs_official_limit": 0,
                    "differs_after_continued": 0, "with_logged_translation": 0,
                    "same_as_logged": 0,
                },
            )  # fmt: skip
            row["subgoals"] += 1
            if check.same_as_logged is not None:
                row["with_logged_translation"] += 1
                row["same_as_logged"] += int(check.same_as_logged)
            if check.status != UNTRANSLATED:
                row["translated"] += 1
            if check.status in (MATCH, DIFFERS):
                row["compared"] += 1
                row[check.status] += 1
                if check.why is not None:
                    row[f"differs_{check.why}"] += 1
    out = []
    for key in sorted(rows, key=lambda k: (k == "all", k)):
        row = rows[key]
        row["translated_pct"] = (
            round(100 * row["translated"] / row["subgoals"], 1) if row["subgoals"] else None
        )
        row["match_pct"] = (
            round(100 * row["match"] / row["compared"], 1) if row["compared"] else None
        )
        row["differs_known"] = sum(row[f"differs_{why}"] for why in WHY)
        row["differs_other"] = row["differs"] - row["differs_known"]
        comparable = row["compared"] - row["differs_known"]
        row["match_pct_comparable"] = (
            round(100 * row["match"] / comparable, 1) if comparable else None
        )
        out.append(row)
    return out


def settings_text(settings: PlannerSettings, version: str) -> str:
    return (
        f"Fast Downward ({version}), alias {settings.alias}, search time limit "
        f"{settings.search_time_limit_s:g} s per helper plan"
    )
