"""Which runs a mean is made of: one run per job, one distinct run per deterministic task.

A spread is shown only where runs differ, so a report must know which runs are the same:

* **Grid duplicates.** SA plans one agent whatever N says, so a sweep over ``agents=2,3``
  runs each SA job once per N value: the same computation twice (the second from the
  planner cache). They are one run: counted once, per (task, seed), in every count, legend
  and mean (:func:`grid_duplicates`).
* **Deterministic methods.** SA, MA and TwoStep with an offline decomposer give the same
  plans for every seed, and a later seed's planner times are the first seed's, read back
  from the planner cache: their seeds repeat **one distinct run** (per task). The means
  use that run alone, the lowest seed's (its planner calls were the ones measured), with
  n = 1 and no spread; the other seeds are still counted as runs (a timed-out task times
  out in every seed). Runs that differ by seed (the LLM decomposer's answers, the
  embodied executor's start cells: :func:`twostep.methods.result.seed_matters`) are averaged
  over their n seeds, with the sample std (:func:`measured_runs`).
"""

from __future__ import annotations

import pandas as pd

from twostep.methods.result import seed_matters
from twostep.report.model import CELL_COLUMNS
from twostep.report.runs import NO_PARAMS, PARAM_PREFIX, RunParams
from twostep.util.outcome import ReportStatus


def seeded_runs(runs: pd.DataFrame, executor: str | None = None) -> pd.Series:
    """Per run: whether its method's runs differ by seed (False: deterministic); the
    param ``executor`` names each run's executor. A run table without it (an older one)
    says it by its domain: a domain with embodied lengths was executed in the kitchen."""
    column = f"{PARAM_PREFIX}{executor}"
    executors = runs[column] if executor and column in runs else pd.Series("", index=runs.index)
    if "embodied_length" in runs:
        kitchens = set(runs.loc[runs["embodied_length"].notna(), "domain"])
        unknown = executors.fillna("").astype(str) == ""
        executors = executors.where(~(unknown & runs["domain"].isin(kitchens)), "embodied")
    flags = [
        seed_matters(str(method), str(decomposer), str(executor) or None)
        for method, decomposer, executor in zip(
            runs["method"], runs["decomposer"], executors, strict=True
        )
    ]
    return pd.Series(flags, index=runs.index, dtype=bool)


def grid_duplicates(runs: pd.DataFrame) -> pd.Series:
    """True for the SA runs a grid's N repeated: of the runs of one SA cell, task and seed
    launched with different N, all but the one with the lowest N. Only among ``counted``
    runs (``runs`` needs the cell columns: call after the series are assigned)."""
    flags = pd.Series(False, index=runs.index)
    sa = runs[runs["counted"] & (runs["method"] == "sa")]
    if sa.empty:
        return flags
    ordered = sa.assign(_launched=sa["agents_param"].fillna(1)).sort_values("_launched")
    repeated = ordered.duplicated([*CELL_COLUMNS, "task", "seed"], keep="first")
    flags.loc[repeated[repeated].index] = True
    return flags


def measured_runs(identified: pd.DataFrame, params: RunParams = NO_PARAMS) -> pd.DataFrame:
    """The runs means are made of: every run of a seed-dependent series; of a
    deterministic one, per (cell, task) the lowest (successful) seed's run, its ``seed``
    set to the cell's lowest (one distinct run: one value per cell, n = 1). Adds
    ``seeded``."""
    runs = identified.assign(seeded=seeded_runs(identified, params.executor))
    fixed = runs[~runs["seeded"]]
    if fixed.empty:
        return runs
    # a seed that failed where another succeeded (a crash, a timeout under load) says
    # nothing about the method: the lowest successful seed, else the lowest seed
    first = (
        fixed.assign(_failed=fixed["status"] != ReportStatus.SUCCESS)
        .sort_values(["_failed", "seed"])
        .drop_duplicates([*CELL_COLUMNS, "task"], keep="first")
        .drop(columns="_failed")
    )
    lowest = first.groupby(list(CELL_COLUMNS), dropna=False)["seed"].transform("min")
    first = first.assign(seed=lowest.astype(first["seed"].dtype))
    return pd.concat([runs[runs["seeded"]], first]).sort_index()


def distinct_label(n_seeds: object, seeded: object) -> str:
    """How many runs a mean is over: ``1 distinct run`` (deterministic), ``3 seeds``."""
    if not bool(seeded):
        return "1 distinct run"
    try:
        n = int(float(str(n_seeds)))
    except ValueError:
        return ""
    return f"{n} seed{'s' if n != 1 else ''}"
