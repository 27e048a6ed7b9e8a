"""Our planner alias names and the Fast Downward driver arguments each stands for."""

from __future__ import annotations

# Anytime aliases write plan.1, plan.2, ... with improving costs; the last complete one
# is the best.
ALIASES: dict[str, tuple[str, ...]] = {
    "lama": ("--alias", "seq-sat-lama-2011"),  # the paper's setting: anytime LAMA
    "lama-first": ("--alias", "lama-first"),  # first plan of LAMA's first iteration
    "seq-sat-lama-2011": ("--alias", "seq-sat-lama-2011"),
    "seq-opt-lmcut": ("--alias", "seq-opt-lmcut"),  # optimal; used for the example plans
    # optimal for any task Fast Downward grounds (lmcut rejects conditional effects and
    # axioms); blind, so for small tasks only
    "astar-blind": ("--search", "astar(blind())"),
}
ANYTIME_ALIASES = frozenset({"lama", "seq-sat-lama-2011"})
