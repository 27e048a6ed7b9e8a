"""plan-deal on one task, checked: within a time limit (:func:`deal_within`), its schedule
checked by twostep (:func:`our_verdict`) and by the independent validator
(:func:`independent_verdict`), its dealing time and fallback as a row shows them. Used by
``bench/bench_deal_ipc.py`` and ``bench/bench_deal_generated.py``.
"""

from __future__ import annotations

import signal
import traceback
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import FrameType

from checkers import IndependentValidator
from twostep.methods import MethodRequest, RunResult, check_run
from twostep.methods.plan_deal import run_plan_deal
from twostep.tasks.benchmark import BenchmarkTask


class Timeout(Exception):
    pass


@contextmanager
def time_limit(seconds: int) -> Iterator[None]:
    def expire(signum: int, frame: FrameType | None) -> None:
        raise Timeout(f"over {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def independent_verdict(
    validator: IndependentValidator, run: RunResult, preds: Sequence[str]
) -> str:
    """The independent validator's verdict on the schedule, on the original files
    (``checkers``: Fast Downward's grounding with a simulator of its own, and
    unified-planning where its reader accepts the files), and which checkers agreed. One
    validator per task: it reads the files once for all of the task's rows."""
    try:
        verdict = validator.check_schedule(run.agent_order, run.plans, run.schedule, preds)
    except Exception as error:  # no checker could read the task: no verdict
        return f"n/a ({type(error).__name__}: {str(error).splitlines()[0][:60]})"
    readers = verdict.checkers.split(" (", 1)[0]  # the checkers that read the files
    return f"ok ({readers})" if verdict.valid else f"INVALID ({verdict.reason[:80]})"


def our_verdict(task: BenchmarkTask, run: RunResult, preds: Sequence[str]) -> str:
    try:
        check_run(task.problem, run, preds)
    except Exception as error:
        return f"INVALID ({type(error).__name__}: {str(error)[:80]})"
    return "ok"


def deal_seconds(run: RunResult) -> float:
    return float(sum(run.extra.get("deal_seconds", {}).values()))


def fallback_text(run: RunResult, none: str = "-", width: int | None = None) -> str:
    """The fallback's reason, and each distinct error of the deals once (cut to ``width``
    characters); ``none`` when the run did not fall back."""
    fallback = run.fallback
    if not fallback:
        return none
    errors = sorted({str(r["error"])[:width] for r in run.extra.get("deal", []) if "error" in r})
    reason = getattr(fallback, "reason", fallback)
    return str(reason) + (f" [{'; '.join(errors)}]" if errors else "")


def deal_within(request: MethodRequest, seconds: int, width: int) -> RunResult | str:
    """plan-deal on ``request`` within ``seconds``: the run, or what went wrong when it
    raised (the exception, its message cut to ``width`` characters, and where)."""
    try:
        with time_limit(seconds):
            return run_plan_deal(request)
    except Exception as error:
        where = traceback.extract_tb(error.__traceback__)[-1]
        return (f"{type(error).__name__}: {str(error)[:width]} "
                f"({Path(where.filename).name}:{where.lineno})")  # fmt: skip
