"""Which function runs a method: :func:`method_for`, the one place that picks by name.

A method is a function from a :class:`~twostep.methods.request.MethodRequest` to a
:class:`~twostep.methods.result.RunResult`. ``sa`` and ``ma`` are the paper's baselines;
``twostep`` is the paper's hand-off with a subgoal source (:data:`SUBGOAL_SOURCES`, the
request's decomposer), or one of the methods that go beyond it, chosen by the same
``decomposer`` name (:data:`TWOSTEP_METHODS`: plan-deal, the portfolio and its lite form). The library,
``flows/`` and ``bench/`` all ask here.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

from twostep.methods.multi_agent import run_multi_agent
from twostep.methods.request import MethodRequest
from twostep.methods.result import MethodName, RunResult
from twostep.methods.single_agent import run_single_agent
from twostep.methods.twostep import run_twostep

Method = Callable[[MethodRequest], RunResult]

SUBGOAL_SOURCES = ("goal-split", "expert", "llm", "plan-split")
"""Decomposers that propose helper subgoals for TwoStep's hand-off (the request's)."""
TWOSTEP_METHODS = ("plan-deal", "portfolio", "portfolio-lite")
"""``decomposer`` names that are methods of their own (no subgoal source needed)."""
DECOMPOSERS = (*SUBGOAL_SOURCES, *TWOSTEP_METHODS)
METHODS = tuple(MethodName)


class UnknownMethod(ValueError):
    """A method or decomposer name that no method answers to."""


def method_for(
    method: str,
    decomposer: str | None = None,
    *,
    cut: str = "best",
    link_degree: int = 2,
    rebind: bool = True,
    owner_search: bool = True,
) -> Method:
    """The function that runs ``method`` (with ``decomposer`` for ``twostep``).

    ``cut`` is plan-deal's (``free``, ``holding`` or ``best``) and ``rebind`` whether
    plan-deal deals the rebound plan too (:mod:`twostep.dealing.rebind`; the portfolios'
    plan-deal as well), ``owner_search`` whether it searches the owners of its shortest
    deals (:mod:`twostep.dealing.improve`; the same), ``link_degree`` the portfolio's for its goal-split members; the other methods have no options. plan-deal
    and the portfolio are imported here, when asked for: a job of another method never
    loads their algorithms.
    """
    if method == MethodName.SA:
        return run_single_agent
    if method == MethodName.MA:
        return run_multi_agent
    if method != MethodName.TWOSTEP:
        raise UnknownMethod(f"unknown method '{method}' (known: {', '.join(METHODS)})")
    if decomposer == "plan-deal":
        from twostep.methods.plan_deal import check_cut, run_plan_deal

        check_cut(cut)  # a ValueError now, not at the first run
        return partial(run_plan_deal, cut=cut, rebind=rebind, owner_search=owner_search)
    if decomposer == "portfolio":
        from twostep.methods.portfolio import Portfolio, run_portfolio

        return partial(
            run_portfolio,
            portfolio=Portfolio(link_degree, rebind=rebind, owner_search=owner_search),
        )
    if decomposer == "portfolio-lite":
        from twostep.methods.portfolio import Portfolio, run_portfolio

        return partial(run_portfolio, portfolio=Portfolio.lite(link_degree, rebind, owner_search))
    if decomposer is None or decomposer in SUBGOAL_SOURCES:
        return run_twostep
    raise UnknownMethod(f"unknown decomposer '{decomposer}' (known: {', '.join(DECOMPOSERS)})")
