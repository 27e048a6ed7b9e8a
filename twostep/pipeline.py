"""The public entry points of the methods, where they were first documented."""

from twostep.methods.twostep import (
    RunResult,
    Steps,
    check_run,
    run_multi_agent,
    run_single_agent,
    run_twostep,
)

__all__ = ["RunResult", "Steps", "check_run", "run_multi_agent", "run_single_agent", "run_twostep"]
