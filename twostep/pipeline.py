"""The methods' public entry points under the name they were first documented with; they
live in :mod:`twostep.methods` (one module per method)."""

from twostep.methods import (
    MethodRequest,
    RunResult,
    Steps,
    check_run,
    method_for,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)

__all__ = [
    "MethodRequest",
    "RunResult",
    "Steps",
    "check_run",
    "method_for",
    "run_multi_agent",
    "run_single_agent",
    "run_twostep",
]
