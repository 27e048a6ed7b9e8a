"""Series: which runs form one line of Fig. 3, and which params split them.

Which params cannot change a run's result, and which a method never reads, is the
config's rule, told with the run table (:class:`twostep.report.runs.RunParams`: the job
identity's rules when ``flows/`` made the table); such params never split a series.
"""

from __future__ import annotations

import pandas as pd

from twostep.report.model import SERIES_COLUMNS
from twostep.report.runs import KEY_COLUMNS, NO_PARAMS, PARAM_PREFIX, RunParams


def _relevance_mask(runs: pd.DataFrame, param: str, params: RunParams) -> pd.Series:
    """Per run, whether its method (and decomposer) reads ``param`` (``params.read_by``)."""
    flags = [
        params.read_by(param, str(method), str(decomposer))
        for method, decomposer in zip(runs["method"], runs["decomposer"], strict=True)
    ]
    return pd.Series(flags, index=runs.index, dtype=bool)


METHOD_ORDER = {"sa": 0, "ma": 1, "twostep": 2}


def series_label(method: str, decomposer: str, variant: str = "") -> str:
    """The legend label of a series: ``SA``, ``MA``, ``TwoStep (goal-split) [p=v]``."""
    base = {"sa": "SA", "ma": "MA"}.get(method)
    if base is None:
        base = f"TwoStep ({decomposer})" if method == "twostep" and decomposer else method
    return f"{base} [{variant}]" if variant else base


def detect_variant_params(
    runs: pd.DataFrame, params: RunParams = NO_PARAMS
) -> tuple[list[str], list[str]]:
    """(params that split series, params that only differ between methods/decomposers).

    A param splits series when it takes more than one value inside one job cell
    (same domain, task, method, decomposer, N, seed). Params that only change with the
    domain (e.g. its agent predicates) are neither; nor are params that cannot change a
    result (``params.identity``), or runs that do not read the param (``params.read_by``).
    """
    identified = runs[runs["counted"]]
    variant: list[str] = []
    between: list[str] = []
    for column in sorted(c for c in identified.columns if str(c).startswith(PARAM_PREFIX)):
        name = column[len(PARAM_PREFIX) :]
        if not params.identity(name):
            continue
        sub = identified[_relevance_mask(identified, name, params)]
        if sub.empty or sub[column].nunique(dropna=False) <= 1:
            continue
        per_cell = sub.groupby(list(KEY_COLUMNS), dropna=False)[column].nunique(dropna=False)
        if bool((per_cell > 1).any()):
            variant.append(name)
            continue
        per_domain = sub.groupby("domain", dropna=False)[column].nunique(dropna=False)
        if bool((per_domain > 1).any()):
            between.append(name)
    return variant, between


def assign_series(
    runs: pd.DataFrame, variant_params: list[str], params: RunParams = NO_PARAMS
) -> tuple[pd.DataFrame, dict[str, dict[str, str]]]:
    """Runs with ``variant`` and ``series`` columns, and each series' variant values."""
    runs = runs.copy()
    values_of: dict[str, dict[str, str]] = {}
    family_params: dict[tuple[str, str], list[str]] = {}
    for (method, decomposer), sub in runs[runs["counted"]].groupby(
        ["method", "decomposer"], dropna=False
    ):
        family_params[(str(method), str(decomposer))] = [
            p
            for p in variant_params
            if params.read_by(p, str(method), str(decomposer))
            and sub[PARAM_PREFIX + p].nunique(dropna=False) > 1
        ]
    variants: list[str] = []
    labels: list[str] = []
    for row in runs.to_dict("records"):
        method, decomposer = str(row["method"]), str(row["decomposer"])
        identified = bool(row["counted"])
        split_by = family_params.get((method, decomposer), []) if identified else []
        values = {p: str(row[PARAM_PREFIX + p]) for p in split_by}
        variant = ", ".join(f"{p}={v}" for p, v in values.items())
        label = series_label(method, decomposer, variant) if identified else ""
        variants.append(variant)
        labels.append(label)
        if identified:
            values_of[label] = values
    runs["variant"] = variants
    runs["series"] = labels
    return runs, values_of


def series_order(runs: pd.DataFrame) -> tuple[str, ...]:
    identified = runs[runs["counted"]]
    keys = identified[list(SERIES_COLUMNS)].drop_duplicates()
    ordered = sorted(
        keys.itertuples(index=False),
        key=lambda r: (METHOD_ORDER.get(str(r.method), 9), str(r.decomposer), str(r.variant)),
    )
    return tuple(str(r.series) for r in ordered)
