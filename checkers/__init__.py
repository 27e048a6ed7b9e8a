"""The independent checkers: code that shares nothing with ``twostep`` (imports nothing from
it; tests/test_layout.py checks) and is not part of its wheel.

* :mod:`checkers.trace_check`: embodied traces replayed on its own reading of the floor
  plan and the PDDL; :mod:`checkers.alfworld_engine`: AlfWorld's own engine (TextWorld)
  replaying plans and traces;
* this package: an independent validator, plans and joint schedules checked against the
  ORIGINAL PDDL files.

The validator has two checkers, each reading the files with its own parser:

* **unified-planning** (:mod:`.unified`): its PDDL reader and sequential plan validator,
  where the reader accepts the files (it rejects some valid PDDL: derived predicates,
  ``either`` in predicate declarations, a variable glued to a name such as ``aircraft?a``);
* **the grounded-task simulator** (:mod:`.sas`): Fast Downward's own translator grounds the
  files (:mod:`.fast_downward`, keeping every fact, variable and operator it would
  otherwise prune) and a small simulator written here runs the plan on ``output.sas``:
  conditional effects, costs, axioms by layers with negation by failure, the goal. It reads
  every file Fast Downward reads, so it is the checker of record where unified-planning
  cannot read the files. A step that is not among the translator's operators is invalid:
  with ``--keep-no-ops --keep-unreachable-facts`` it drops only actions no state reachable
  even under the delete relaxation can apply.

A plan is valid when every checker that reads the files says so; when they disagree the
verdict is invalid and the reason names both answers. A joint schedule is valid when
(1) each agent's actions in the schedule are exactly its plan, in order, (2) the simulator
accepts it as parallel steps of the N-agent task in which every agent has its own copy of
the agent-specific facts (every order of a step's actions must run and reach the same
state: :func:`.sas.run_parallel`), and (3) unified-planning accepts the sequentialised
schedule in its own N-agent formulation (:func:`.unified.multi_agent_problem`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import sas, unified
from .fast_downward import TranslateError, Translation, translate

__all__ = ["IndependentValidator", "TranslateError", "Verdict"]


@dataclass(frozen=True)
class Verdict:
    valid: bool
    reason: str = ""
    checkers: str = ""  # which checkers read the files and agreed (or why one could not)
    cost: int | None = None  # the plan's cost by the grounded task (Fast Downward's costs)


class IndependentValidator:
    """The checkers for one task (a domain file and a problem file), each loaded once."""

    def __init__(self, domain: Path, problem: Path, use_unified_planning: bool = True):
        self.domain, self.problem = Path(domain), Path(problem)
        self.use_unified_planning = use_unified_planning
        self._translation: Translation | None = None
        self._translate_error: str | None = None
        self._up: Any = None
        self._up_error: str | None = None if use_unified_planning else "not asked for"
        self._ma_tasks: dict[tuple[tuple[str, ...], int], sas.SASTask | str] = {}
        self._ma_up: dict[tuple[tuple[str, ...], int], Any] = {}

    # -------------------------------------------------------------------- loading

    @property
    def translation(self) -> Translation | None:
        if self._translation is None and self._translate_error is None:
            try:
                self._translation = translate(self.domain, self.problem)
            except TranslateError as error:
                self._translate_error = str(error)
        return self._translation

    @property
    def up_problem(self) -> Any:
        if self._up is None and self._up_error is None:
            try:
                self._up = unified.read_problem(self.domain, self.problem)
            except unified.ReaderRejected as error:
                self._up_error = str(error)
        return self._up

    def _checkers(self) -> str:
        names = []
        if self.translation is not None:
            names.append("grounded-task simulator")
        if self.up_problem is not None:
            names.append("unified-planning")
        text = " + ".join(names) or "none"
        if self._up_error and self.use_unified_planning:
            text += f" (unified-planning rejects the files: {self._up_error})"
        if self._translate_error:
            text += f" (Fast Downward's translator rejects the files: {self._translate_error})"
        return text

    @staticmethod
    def _combine(
        simulator: sas.PlanCheck | None, up: unified.UPCheck | None, checkers: str
    ) -> Verdict:
        if simulator is None and up is None:
            return Verdict(False, "no independent checker reads the files", checkers)
        cost = simulator.cost if simulator is not None else None
        answers = [a for a in (simulator, up) if a is not None]
        if all(a.valid for a in answers):
            return Verdict(True, "", checkers, cost)
        if len(answers) == 2 and answers[0].valid != answers[1].valid:
            assert simulator is not None and up is not None
            said = {True: "valid", False: "invalid"}
            reason = (
                f"the checkers disagree: simulator {said[simulator.valid]} "
                f"{simulator.reason}; unified-planning {said[up.valid]} {up.reason}"
            )
            return Verdict(False, " ".join(reason.split()), checkers, cost)
        failed = next(a for a in answers if not a.valid)
        return Verdict(False, failed.reason, checkers, cost)

    # -------------------------------------------------------------------- plans

    def check_plan(self, plan: Sequence[str]) -> Verdict:
        """Is ``plan`` (``(name arg ...)`` steps) a valid plan of the original task?"""
        translation = self.translation
        simulator = sas.run_plan(translation.task, plan) if translation is not None else None
        up = unified.validate_plan(self.up_problem, plan) if self.up_problem is not None else None
        return self._combine(simulator, up, self._checkers())

    # -------------------------------------------------------------------- schedules

    def check_schedule(
        self,
        agent_order: Sequence[str],
        plans: Mapping[str, Sequence[str]],
        schedule: Sequence[Sequence[Sequence[str]]],
        agent_predicates: Sequence[str],
    ) -> Verdict:
        """Is ``schedule`` (time steps of ``[agent, action]``) a valid joint execution of
        ``plans`` in which each agent of ``agent_order`` keeps its own agent facts?"""
        consistency = schedule_matches_plans(agent_order, plans, schedule)
        if consistency:
            return Verdict(False, consistency, "schedule against plans")
        index = {agent: i for i, agent in enumerate(agent_order)}
        key = (tuple(sorted(p.lower() for p in agent_predicates)), len(agent_order))
        simulator: sas.PlanCheck | None = None
        if self.translation is not None:
            if key not in self._ma_tasks:
                try:
                    self._ma_tasks[key] = sas.multi_agent_task(
                        self.translation.task, key[0], key[1]
                    )
                except ValueError as error:
                    self._ma_tasks[key] = str(error)
            task = self._ma_tasks[key]
            if isinstance(task, str):
                simulator = sas.PlanCheck(False, f"N-agent formulation: {task}")
            else:
                steps = [
                    [sas.agent_operator_name(index[agent], action) for agent, action in step]
                    for step in schedule
                ]
                simulator = sas.run_parallel(task, steps)
        up: unified.UPCheck | None = None
        if self.up_problem is not None:
            if key not in self._ma_up:
                self._ma_up[key] = unified.multi_agent_problem(self.up_problem, key[0], key[1])
            up = unified.validate_schedule(self._ma_up[key], agent_order, schedule)
        return self._combine(simulator, up, self._checkers())


def schedule_matches_plans(
    agent_order: Sequence[str],
    plans: Mapping[str, Sequence[str]],
    schedule: Sequence[Sequence[Sequence[str]]],
) -> str:
    """Why the schedule does not run each agent's plan exactly, in order; "" when it does."""
    done: dict[str, list[str]] = {agent: [] for agent in agent_order}
    for number, step in enumerate(schedule, start=1):
        agents = [agent for agent, _ in step]
        if len(set(agents)) != len(agents):
            return f"time step {number} gives one agent two actions"
        for agent, action in step:
            if agent not in done:
                return f"time step {number} names {agent}, which is not in the agent order"
            done[agent].append(sas.step_name(action))
    for agent in agent_order:
        expected = [sas.step_name(a) for a in plans.get(agent, [])]
        if done[agent] != expected:
            return (
                f"{agent} runs {len(done[agent])} actions in the schedule but its plan has "
                f"{len(expected)}, or they differ"
            )
    return ""
