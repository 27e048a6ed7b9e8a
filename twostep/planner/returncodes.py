"""Fast Downward's exit codes, named as in its ``driver/returncodes.py``, and what each means.

Data only: :mod:`twostep.planner.driver` turns a code (and whether a complete plan file
exists) into a :class:`~twostep.planner.results.Status`.
"""

from __future__ import annotations

SUCCESS = 0
SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY = 1
SEARCH_PLAN_FOUND_AND_OUT_OF_TIME = 2
SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY_AND_TIME = 3

TRANSLATE_UNSOLVABLE = 10
SEARCH_UNSOLVABLE = 11
SEARCH_UNSOLVED_INCOMPLETE = 12
SEARCH_UNSOLVABLE_WITHIN_BOUND = 13

TRANSLATE_OUT_OF_MEMORY = 20
TRANSLATE_OUT_OF_TIME = 21
SEARCH_OUT_OF_MEMORY = 22
SEARCH_OUT_OF_TIME = 23
SEARCH_OUT_OF_MEMORY_AND_TIME = 24

TRANSLATE_CRITICAL_ERROR = 30
TRANSLATE_INPUT_ERROR = 31
SEARCH_CRITICAL_ERROR = 32
SEARCH_INPUT_ERROR = 33
SEARCH_UNSUPPORTED = 34
DRIVER_CRITICAL_ERROR = 35
DRIVER_INPUT_ERROR = 36
DRIVER_UNSUPPORTED = 37

MEANINGS: dict[int, str] = {
    SUCCESS: "success",
    SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY: "plan found, out of memory",
    SEARCH_PLAN_FOUND_AND_OUT_OF_TIME: "plan found, out of time",
    SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY_AND_TIME: "plan found, out of memory and time",
    TRANSLATE_UNSOLVABLE: "translator proved unsolvable",
    SEARCH_UNSOLVABLE: "search proved unsolvable",
    SEARCH_UNSOLVED_INCOMPLETE: "search space exhausted without a plan (incomplete search)",
    SEARCH_UNSOLVABLE_WITHIN_BOUND: "search proved no plan within the cost bound",
    TRANSLATE_OUT_OF_MEMORY: "translator out of memory",
    TRANSLATE_OUT_OF_TIME: "translator out of time",
    SEARCH_OUT_OF_MEMORY: "search out of memory",
    SEARCH_OUT_OF_TIME: "search out of time",
    SEARCH_OUT_OF_MEMORY_AND_TIME: "search out of memory and time",
    TRANSLATE_CRITICAL_ERROR: "translator critical error",
    TRANSLATE_INPUT_ERROR: "translator input error",
    SEARCH_CRITICAL_ERROR: "search critical error",
    SEARCH_INPUT_ERROR: "search input error",
    SEARCH_UNSUPPORTED: "search unsupported",
    DRIVER_CRITICAL_ERROR: "driver critical error",
    DRIVER_INPUT_ERROR: "driver input error",
    DRIVER_UNSUPPORTED: "driver unsupported",
}

#: The search found at least one plan (the plan files say which are complete).
PLAN_FOUND: frozenset[int] = frozenset(
    {
        SUCCESS,
        SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY,
        SEARCH_PLAN_FOUND_AND_OUT_OF_TIME,
        SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY_AND_TIME,
    }
)
#: Proven: no plan exists (we never set a cost bound, so "none within the bound" is
#: "none at all").
PROVEN_UNSOLVABLE: frozenset[int] = frozenset(
    {TRANSLATE_UNSOLVABLE, SEARCH_UNSOLVABLE, SEARCH_UNSOLVABLE_WITHIN_BOUND}
)
#: Not proven: an incomplete search (e.g. with pruning) ran out of states to expand.
INCOMPLETE: frozenset[int] = frozenset({SEARCH_UNSOLVED_INCOMPLETE})
#: A time limit ended the run; any complete plan file written before still counts.
OUT_OF_TIME: frozenset[int] = frozenset(
    {TRANSLATE_OUT_OF_TIME, SEARCH_OUT_OF_TIME, SEARCH_OUT_OF_MEMORY_AND_TIME}
)
#: The memory limit ended the run; any complete plan file written before still counts.
OUT_OF_MEMORY: frozenset[int] = frozenset({TRANSLATE_OUT_OF_MEMORY, SEARCH_OUT_OF_MEMORY})


def is_unrecoverable(code: int) -> bool:
    """Critical, input and unsupported errors (30-39), as Fast Downward's driver says."""
    return 30 <= code < 40


def meaning(code: int) -> str:
    return MEANINGS.get(code, f"unexpected exit code {code}")
