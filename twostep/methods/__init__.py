"""The methods, side by side: each takes a :class:`MethodRequest` and returns a
:class:`RunResult` (the result.json shape).

================  ============================================================
module            what it is for
================  ============================================================
``request``       :class:`MethodRequest`: the task, N and the settings every method shares
``steps``         :class:`Steps`: the replaceable step functions (plan, LLM, progress, score)
``result``        :class:`RunResult` and the rules every method follows to fill it in
``single_agent``  SA PDDL: the task solved as is
``multi_agent``   MA PDDL: compiled for N agents, solved once, split and scored
``twostep``       TwoStep: propose -> check -> plan helpers -> progress -> plan main -> score
``plan_deal``     plan-deal: the SA plan dealt to N agents (:mod:`twostep.dealing`)
``portfolio``     several decompositions, the shortest schedule kept
``registry``      ``METHODS`` and :func:`method_for`: picks a method by name
================  ============================================================

    from twostep.methods import MethodRequest, method_for

    request = MethodRequest(task, agents=3, planner=settings, agent_predicates=facts,
                            decomposer=GoalSplitDecomposer(facts))
    run = method_for("twostep", "goal-split")(request)
    deal = method_for("plan-deal", cut="free")(MethodRequest(task, agents=3, planner=settings))

plan-deal and the portfolio load on first use (:func:`method_for`, or their modules), so that
importing the package stays light.
"""

from twostep.methods.multi_agent import run_multi_agent
from twostep.methods.registry import Method, method_for
from twostep.methods.request import MethodRequest
from twostep.methods.result import (
    AgentPlan,
    Fallback,
    FallbackReason,
    MethodName,
    RunResult,
    RunStatus,
    adopt_execution,
    check_run,
)
from twostep.methods.single_agent import run_single_agent
from twostep.methods.steps import DIRECT, Steps
from twostep.methods.twostep import run_twostep

__all__ = [
    "DIRECT",
    "AgentPlan",
    "Fallback",
    "FallbackReason",
    "Method",
    "MethodName",
    "MethodRequest",
    "RunResult",
    "RunStatus",
    "Steps",
    "adopt_execution",
    "check_run",
    "method_for",
    "run_multi_agent",
    "run_single_agent",
    "run_twostep",
]
