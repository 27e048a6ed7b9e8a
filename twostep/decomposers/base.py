"""What a decomposer is: the source of helper subgoals in TwoStep.

A decomposer proposes, for N agents, up to N-1 helper subgoals. Each proposal carries the
PDDL goal text (and, for the LLM, the English subgoal and every prompt and answer). The
TwoStep method (:mod:`twostep.methods.twostep`) then checks every proposal against the
task (:mod:`twostep.plans.subgoals`) and plans the accepted ones; a decomposer never plans.

A decomposer that cannot propose at all (its LLM calls failed) raises
:class:`DecomposerError`; the run then fails with the error's status instead of falling
back to the single-agent plan, which is only for subgoals that turned out unusable.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from twostep.plans.subgoals import SubgoalStatus
from twostep.tasks.benchmark import BenchmarkTask


@dataclass
class SubgoalProposal:
    """One helper's subgoal as proposed, before the pipeline checks and plans it.

    ``pddl`` is the goal text (None when no usable PDDL came out); ``status`` is
    ``PROPOSED`` until the pipeline decides, or ``DISCARDED`` (or ``STOPPED``) when the
    decomposer already knows it is unusable (``reason`` then says why).
    """

    helper: int  # 1-based helper index
    pddl: str | None
    english: str | None = None
    status: SubgoalStatus = SubgoalStatus.PROPOSED
    reason: str | None = None
    llm_time_s: float = 0.0
    exchanges: list[dict[str, Any]] = field(default_factory=list)  # prompts and answers

    def to_dict(self) -> dict[str, Any]:
        return {
            "helper": self.helper,
            "english": self.english,
            "pddl": self.pddl,
            "status": SubgoalStatus(self.status).value,
            "reason": self.reason,
            "llm_time_s": round(self.llm_time_s, 6),
            "exchanges": self.exchanges,
        }


Exchange = dict[str, Any]
"""One prompt and its raw answer, as result.json records them."""
LLMStep = Callable[..., tuple[str | None, Exchange]]
"""An LLM call of a decomposer (:func:`twostep.decomposers.llm.generate_subgoal` and
``translate_subgoal``, or a replacement with the same signature and result)."""


@dataclass(frozen=True)
class DecompositionRequest:
    """What a decomposer is asked: helpers for ``agents`` agents on ``task``.

    ``sa_plan`` is the single-agent plan, for decomposers that read it (plan-split); the
    TwoStep method fills it in when :func:`reads_sa_plan` says so. ``generate`` and
    ``translate`` are the LLM calls an LLM decomposer makes (None: its own functions), so
    that a workflow engine can run each call as a task of its own.
    """

    task: BenchmarkTask
    agents: int
    seed: int = 0
    sa_plan: tuple[str, ...] | None = None
    generate: LLMStep | None = None
    translate: LLMStep | None = None


class Decomposer(Protocol):
    """Proposes helper subgoals for a task; at most ``request.agents - 1`` of them.

    A decomposer that reads the single-agent plan says so with ``needs_sa_plan = True``.
    """

    name: str

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]: ...


def reads_sa_plan(decomposer: Decomposer) -> bool:
    """Whether ``decomposer`` reads the SA plan (``needs_sa_plan``; absent: it does not)."""
    return bool(getattr(decomposer, "needs_sa_plan", False))


class DecomposerError(Exception):
    """The decomposer could not propose (e.g. an LLM call failed after its retries).

    ``status`` becomes the run's status; ``proposals`` are those made before the failure
    (recorded in result.json, never planned).
    """

    def __init__(
        self, message: str, status: str, proposals: list[SubgoalProposal] | None = None
    ) -> None:
        super().__init__(message)
        self.status = status
        self.proposals = list(proposals or [])
