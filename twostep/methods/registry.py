"""Which function runs a method: :data:`METHODS`, one line per method, and
:func:`method_for`, the one place that picks by name.

A method is a function from a :class:`~twostep.methods.request.MethodRequest` to a
:class:`~twostep.methods.result.RunResult`. ``sa`` and ``ma`` are the paper's baselines,
``twostep`` the paper's hand-off with a subgoal source (:data:`SUBGOAL_SOURCES`, the
request's decomposer); ``plan-deal``, ``portfolio`` and ``portfolio-lite`` go beyond it.
The library, ``flows/`` and ``bench/`` all ask here.

Adding a method is one module with its run function, one line in :data:`METHODS` and
one config file (``conf/method/<name>.yaml``, its ``name`` and options). Its options are
the run function's keyword parameters (after the request), checked against their
annotations (``bool``, ``int``, ``float``, ``str``, a ``Literal``, or ``Annotated[str,
Literal[...]]`` for a string of a few choices) when the method is picked, so a wrong
option is an error before any work.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Annotated, Any, Literal, Union, get_args, get_origin, get_type_hints

from twostep.methods.request import MethodRequest
from twostep.methods.result import RunResult

Method = Callable[[MethodRequest], RunResult]


@dataclass(frozen=True)
class MethodEntry:
    """Where a method's run function lives (``module:function``, imported when the method
    is picked: a job of another method never loads its algorithms), and whether it reads a
    subgoal source (the ``decomposer``)."""

    run: str
    subgoals: bool = False


METHODS: dict[str, MethodEntry] = {
    "sa": MethodEntry("twostep.methods.single_agent:run_single_agent"),
    "ma": MethodEntry("twostep.methods.multi_agent:run_multi_agent"),
    "twostep": MethodEntry("twostep.methods.twostep:run_twostep", subgoals=True),
    "plan-deal": MethodEntry("twostep.methods.plan_deal:run_plan_deal"),
    "portfolio": MethodEntry("twostep.methods.portfolio:run_full_portfolio"),
    "portfolio-lite": MethodEntry("twostep.methods.portfolio:run_portfolio_lite"),
}
"""Every method by name: its run function and whether it reads a subgoal source."""

SUBGOAL_SOURCES = ("goal-split", "expert", "llm", "plan-split")
"""Decomposers that propose helper subgoals for TwoStep's hand-off (the request's)."""
TWOSTEP_METHODS = ("plan-deal", "portfolio", "portfolio-lite")
"""Methods that the old spelling named as ``twostep``'s decomposer (the method ``twostep``
with the decomposer ``plan-deal``); result.json records them so (``method`` twostep, ``decomposer``
the method's name): :func:`method_for` still answers to that spelling."""
DECOMPOSERS = (*SUBGOAL_SOURCES, *TWOSTEP_METHODS)
"""The names ``decomposer`` takes: the subgoal sources, and the old spelling's methods."""
OLD_OPTIONS = frozenset({"cut", "link_degree", "rebind", "owner_search"})
"""Options the old :func:`method_for` took for every method: dropped for a method whose
run function has no such parameter."""


class UnknownMethod(ValueError):
    """A method or decomposer name that no method answers to, or an option it lacks."""


def reads_subgoals(method: str | None) -> bool:
    """Whether ``method`` reads a subgoal source (``decomposer``); unknown: False."""
    entry = METHODS.get(str(method))
    return entry is not None and entry.subgoals


def method_name(method: str, decomposer: str | None = None) -> str:
    """The method a (method, decomposer) pair names: ``twostep`` with one of
    :data:`TWOSTEP_METHODS` as its decomposer is that method (the old spelling)."""
    if method == "twostep" and decomposer in TWOSTEP_METHODS:
        return str(decomposer)
    return method


def run_function(method: str) -> Callable[..., RunResult]:
    """The run function of ``method`` (imported now)."""
    entry = METHODS.get(method)
    if entry is None:
        raise UnknownMethod(f"unknown method '{method}' (known: {', '.join(METHODS)})")
    module, _, name = entry.run.partition(":")
    function: Callable[..., RunResult] = getattr(importlib.import_module(module), name)
    return function


def method_options(method: str) -> dict[str, Any]:
    """``method``'s options and their defaults (its run function's keyword parameters)."""
    parameters = list(inspect.signature(run_function(method)).parameters.values())[1:]
    return {p.name: p.default for p in parameters if p.default is not inspect.Parameter.empty}


def method_for(method: str, decomposer: str | None = None, **options: Any) -> Method:
    """The function that runs ``method`` (with ``decomposer`` for ``twostep``), its
    ``options`` bound (see the module docstring): e.g. ``method_for("plan-deal",
    cut="free")``. ``method_for("twostep", "plan-deal")`` is ``method_for("plan-deal")``.

    Raises :class:`UnknownMethod` for an unknown method, decomposer or option, and
    :class:`ValueError` for an option's value of the wrong type or choice.
    """
    name = method_name(method, decomposer)
    function = run_function(name)
    if reads_subgoals(name) and decomposer is not None and decomposer not in SUBGOAL_SOURCES:
        raise UnknownMethod(
            f"unknown decomposer '{decomposer}' (known: {', '.join(SUBGOAL_SOURCES)})"
        )
    known = method_options(name)
    unknown = sorted(set(options) - set(known) - OLD_OPTIONS)
    if unknown:
        raise UnknownMethod(
            f"method {name} has no option {', '.join(unknown)} "
            f"(its options: {', '.join(known) or 'none'})"
        )
    given = {key: value for key, value in options.items() if key in known}
    hints = get_type_hints(function, include_extras=True)
    for key, value in given.items():
        problem = _type_problem(value, hints.get(key, Any))
        if problem:
            raise ValueError(f"method {name}: option {key}={value!r} {problem}")
    return partial(function, **given) if given else function


def _type_problem(value: Any, kind: Any) -> str | None:
    """Why ``value`` is not of the annotation ``kind`` (None: it is, or the annotation is
    not one of the simple kinds checked)."""
    if get_origin(kind) is Annotated:  # Annotated[str, Literal[...]]: the Literal's choices
        choices = [c for extra in kind.__metadata__ if get_origin(extra) is Literal
                   for c in get_args(extra)]  # fmt: skip
        kind = get_args(kind)[0] if not choices else Literal[tuple(choices)]
    kinds = get_args(kind) if get_origin(kind) is Union else (kind,)
    choices = []
    for one in kinds:
        if get_origin(one) is Literal:
            choices += get_args(one)
        elif one is bool:
            if isinstance(value, bool):
                return None
        elif one is int or one is float:
            number = int if one is int else int | float
            if isinstance(value, number) and not isinstance(value, bool):
                return None
        elif one is str:
            if isinstance(value, str):
                return None
        else:
            return None  # not a kind checked here
    if choices and value in choices:
        return None
    if choices:
        return f"is not one of {', '.join(map(str, choices))}"
    return f"is not {' or '.join(getattr(k, '__name__', str(k)) for k in kinds)}"
