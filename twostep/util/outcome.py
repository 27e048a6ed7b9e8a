"""The outcome vocabulary: how a planner call, a run, a job, a helper subgoal, an embodied
execution and a report row end, and the sets of statuses the rules ask about.

Every status word of the library, ``flows/`` and the report is a member of one of these
enums or a set derived beside them; code elsewhere compares with a member or a set, never
with a bare string (tests/test_outcome.py checks this). The values are the strings
result.json, trace.json, MLflow's tags and the job store hold, so they never change.

- :class:`PlannerStatus`: a planner call (``twostep.planner.Status``);
- :class:`RunStatus`: a run (result.json ``status``): the deciding planner call's status,
  a method's own failures, and the two the job runner writes for a job that raised;
- :class:`JobStatus`: a job (the ``twostep.status`` tag, the sweep's job records);
- :class:`SubgoalStatus`: a helper subgoal proposal (result.json ``subgoals[].status``);
- :class:`ExchangeStatus`: an exchange of the LLM decomposer (its log record's ``status``);
- :class:`EmbodiedStatus`: an embodied execution (result.json ``embodied_status``);
- :class:`ReportStatus`: a run in the report's run table, and :data:`STATUS_SYNONYMS`, the
  words stored runs use for it.
"""

from __future__ import annotations

from enum import StrEnum


class PlannerStatus(StrEnum):
    """What one planner call says happened (``twostep.planner.Status``).

    "Proven unsolvable" and "search incomplete" are different answers: the first says no
    plan exists; the second only that this (incomplete) search found none."""

    SOLVED = "solved"
    TIMEOUT = "timeout"
    UNSOLVABLE = "unsolvable"  # proven: no plan exists
    INCOMPLETE = "incomplete"  # an incomplete search exhausted its space without a plan
    ERROR = "error"


class JobStatus(StrEnum):
    """How a job ended (the ``twostep.status`` tag, the sweep's job records)."""

    SUCCESS = "success"
    FAILED = "failed"
    TIMEOUT = "timeout"


class RunStatus(StrEnum):
    """How a run ended (result.json ``status``): the deciding planner call's status,
    ``llm_error`` when the decomposer's LLM calls failed, or ``embodied_failed`` when the
    plans were found but did not execute to the goal on the floor plan (``message`` says
    why). A job that raised has ``failed``, or ``resource_limit`` when a resource limit
    of its guard ended it (written by the job runner, ``flows/job.py``)."""

    SOLVED = PlannerStatus.SOLVED.value
    TIMEOUT = PlannerStatus.TIMEOUT.value
    UNSOLVABLE = PlannerStatus.UNSOLVABLE.value
    INCOMPLETE = PlannerStatus.INCOMPLETE.value
    ERROR = PlannerStatus.ERROR.value
    LLM_ERROR = "llm_error"
    EMBODIED_FAILED = "embodied_failed"
    FAILED = JobStatus.FAILED.value  # the job raised
    RESOURCE_LIMIT = "resource_limit"  # a limit of the job's guard ended it (exit 1)


class SubgoalStatus(StrEnum):
    """What became of a helper's subgoal (the ``status`` strings of result.json)."""

    PROPOSED = "proposed"  # from the decomposer, not yet checked by the pipeline
    ACCEPTED = "accepted"  # checked and planned: the helper's plan is in the schedule
    DISCARDED = "discarded"  # unusable: ``reason`` says why
    STOPPED = "stopped"  # the LLM answered "none": no further helper
    UNUSED = "unused"  # planned, but the run fell back to the single-agent plan


class ExchangeStatus(StrEnum):
    """What became of one LLM exchange of the LLM decomposer (its log record's ``status``)."""

    OK = "ok"  # answered and read
    NONE = "none"  # the LLM answered that no further helper helps
    DISCARDED = "discarded"  # unusable: ``reason`` says why


class EmbodiedStatus(StrEnum):
    """How an embodied execution ended; every status but ``success`` is a failed run.

    The values are the strings result.json, trace.json and MLflow hold.
    """

    SUCCESS = "success"
    DEADLOCK = "deadlock"  # nobody can ever make progress: a precondition no one makes true
    BOXED_IN = "boxed_in"  # agents cannot all stand, or a way is blocked and nobody can make way
    UNREACHABLE = "unreachable"  # walls and furniture cut a location off
    NO_CELL = "no_cell"  # a location the floor plan does not place
    BUDGET_EXCEEDED = "budget_exceeded"
    INVALID_PLAN = "invalid_plan"  # an action the task does not know
    GOAL_NOT_REACHED = "goal_not_reached"
    NOT_RUN = "not_run"  # no plan to execute (planning failed)


class ReportStatus(StrEnum):
    """A run's status in the report's run table: how its job ended, or ``running`` (an
    MLflow run that had not finished when the report was made)."""

    SUCCESS = JobStatus.SUCCESS.value
    FAILED = JobStatus.FAILED.value
    TIMEOUT = JobStatus.TIMEOUT.value
    RUNNING = "running"


# ----------------------------------------------------------------- derived sets

#: A time limit was reached (a planner call's, a run's or a job's status): counted apart
#: from failures (``twostep.planner.limits``, the job's ``timeout`` status, the report).
LIMIT_REACHED: frozenset[str] = frozenset({PlannerStatus.TIMEOUT})

#: Run statuses of a job that did not finish its work: never stored, computed again by a
#: re-run (every other finished run is storable, :func:`storable`).
UNFINISHED: frozenset[str] = frozenset(
    {RunStatus.ERROR, RunStatus.LLM_ERROR, RunStatus.FAILED, RunStatus.RESOURCE_LIMIT}
)

#: Job statuses whose MLflow run, once logged completely, is left as it is when the job
#: runs again (a failed job's run is logged again).
SETTLED: frozenset[str] = frozenset({JobStatus.SUCCESS, JobStatus.TIMEOUT})

#: The report's statuses, in the order its counts show them.
REPORT_STATUSES: tuple[str, ...] = tuple(s.value for s in ReportStatus)

#: Words stored runs use for a status (MLflow's, older result files', other tools'), read
#: as the report's status they mean.
STATUS_SYNONYMS: dict[str, ReportStatus] = {
    "success": ReportStatus.SUCCESS,
    "succeeded": ReportStatus.SUCCESS,
    PlannerStatus.SOLVED: ReportStatus.SUCCESS,
    "ok": ReportStatus.SUCCESS,
    "finished": ReportStatus.SUCCESS,
    "failed": ReportStatus.FAILED,
    "failure": ReportStatus.FAILED,
    RunStatus.ERROR: ReportStatus.FAILED,
    RunStatus.UNSOLVABLE: ReportStatus.FAILED,
    "killed": ReportStatus.FAILED,
    "crashed": ReportStatus.FAILED,
    "timeout": ReportStatus.TIMEOUT,
    "timed_out": ReportStatus.TIMEOUT,
    "timed-out": ReportStatus.TIMEOUT,
    "running": ReportStatus.RUNNING,
    "scheduled": ReportStatus.RUNNING,
}


def storable(status: object) -> bool:
    """Whether a finished run with this result.json ``status`` may be stored and reused."""
    return str(status) not in UNFINISHED


def limit_reached(status: object) -> bool:
    """Whether ``status`` (a planner call's, a run's or a job's) says a time limit ended it."""
    return isinstance(status, str) and status in LIMIT_REACHED
