"""The figures the TwoStep paper reports, printed beside ours for comparison.

Source: the paper's "Results" section (changes after min-max normalising the per-domain
averages and averaging across domains) and its Table I (execution length on the four
expert-annotated tasks of four domains, N = 2). The paper does not say whether its
percentages are measured against SA or MA; reports print ours against both.
"""

from __future__ import annotations

#: Change of TwoStep against the baseline, in percent, per N (negative = reduction).
PAPER_CHANGE_PCT: dict[str, dict[int, float]] = {
    "planning_time_s": {2: -50.1, 3: -60.3, 4: -64.7},
    "exec_length": {2: -7.7, 3: -7.1, 4: -13.2},
}

#: The tasks the paper's expert annotated with helper subgoals (N = 2).
ANNOTATED_TASKS: tuple[int, ...] = (1, 6, 11, 16)
TABLE1_DOMAINS: tuple[str, ...] = ("blocksworld", "termes", "tyreworld", "grippers")
TABLE1_AGENTS = 2

#: Table I rows: (label, {domain or "macro": (mean, std or None)}).
PAPER_TABLE1: tuple[tuple[str, dict[str, tuple[float, float | None]]], ...] = (
    (
        "paper: TwoStep (LLM, GPT-4o)",
        {
            "blocksworld": (15.5, 0.4),
            "termes": (125.5, 0.8),
            "tyreworld": (88.3, 1.9),
            "grippers": (6.5, 0.0),
            "macro": (58.9, 0.8),
        },
    ),
    (
        "paper: expert subgoals",
        {
            "blocksworld": (16.3, None),
            "termes": (120.0, None),
            "tyreworld": (86.8, None),
            "grippers": (5.3, None),
            "macro": (57.1, None),
        },
    ),
)
