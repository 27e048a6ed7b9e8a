"""What a decomposer is: the source of helper subgoals in TwoStep.

A decomposer proposes, for N agents, up to N-1 helper subgoals. Each proposal carries the
PDDL goal text (and, for the LLM, the English subgoal and every prompt and answer). The
pipeline (:mod:`twostep.pipeline`) then checks every proposal against the task and plans
the accepted ones; a decomposer never plans.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

from twostep.benchmark import BenchmarkTask
from twostep.pddl import Goal, fact_to_pddl


@dataclass
class SubgoalProposal:
    """One helper's subgoal as proposed, before the pipeline checks and plans it.

    ``pddl`` is the goal text (None when no usable PDDL came out); ``status`` is
    ``"proposed"`` until the pipeline decides, or ``"discarded"`` when the decomposer
    already knows it is unusable (``reason`` then says why).
    """

    helper: int  # 1-based helper index
    pddl: str | None
    english: str | None = None
    status: str = "proposed"
    reason: str | None = None
    llm_time_s: float = 0.0
    exchanges: list[dict[str, Any]] = field(default_factory=list)  # prompts and answers

    def to_dict(self) -> dict[str, Any]:
        return {
            "helper": self.helper,
            "english": self.english,
            "pddl": self.pddl,
            "status": self.status,
            "reason": self.reason,
            "llm_time_s": round(self.llm_time_s, 6),
            "exchanges": self.exchanges,
        }


@dataclass(frozen=True)
class DecompositionRequest:
    task: BenchmarkTask
    agents: int
    seed: int = 0
    # The single-agent plan, for decomposers that read it (plan-split); the pipeline fills
    # it in when the decomposer sets ``needs_sa_plan = True``.
    sa_plan: tuple[str, ...] | None = None


class Decomposer(Protocol):
    """Proposes helper subgoals for a task; at most ``request.agents - 1`` of them."""

    name: str

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]: ...


def goal_conflict(goal: Goal, full_goal: Goal) -> str | None:
    """Why ``goal`` cannot be a helper subgoal of ``full_goal`` whatever the state, or None.

    It equals the full goal (nothing left to share), or it asks for the opposite of a
    goal literal (the main agent would have to undo the helper's work).
    """
    if goal.positive == full_goal.positive and goal.negative == full_goal.negative:
        return "equals the full goal"
    for fact in sorted(goal.negative & full_goal.positive):
        return f"contradicts the main goal: (not {fact_to_pddl(fact)}) undoes a goal fact"
    for fact in sorted(goal.positive & full_goal.negative):
        return f"contradicts the main goal: {fact_to_pddl(fact)} is negated in the goal"
    return None
