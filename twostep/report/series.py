"""Series: which runs form one line of Fig. 3, and which config params split them.

Which config params are not part of a job's identity, and which a method never reads, is
decided by :mod:`twostep.jobs.identity` (the one owner, shared with the job store and sweeps);
:func:`is_bookkeeping_param` and :func:`param_applies` are the report's names for it.
"""

from __future__ import annotations

import pandas as pd

from twostep.jobs.identity import is_identity_key, is_relevant
from twostep.report.model import SERIES_COLUMNS
from twostep.report.runs import KEY_COLUMNS, PARAM_PREFIX


def is_bookkeeping_param(name: str) -> bool:
    """True for params that never split series: not part of a job's identity."""
    return not is_identity_key(name)


def param_applies(param: str, method: str, decomposer: str) -> bool:
    """Whether runs of ``method`` (and ``decomposer``) read ``param`` at all."""
    return is_relevant(param, method, decomposer)


def _relevance_mask(runs: pd.DataFrame, param: str) -> pd.Series:
    """Per run, whether its method (and decomposer) reads ``param``: see :func:`param_applies`."""
    flags = [
        param_applies(param, str(method), str(decomposer))
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


def detect_variant_params(runs: pd.DataFrame) -> tuple[list[str], list[str]]:
    """(params that split series, params that only differ between methods/decomposers).

    A param splits series when it takes more than one value inside one job cell
    (same domain, task, method, decomposer, N, seed). Params that only change with the
    domain (e.g. its agent predicates) are neither.
    """
    identified = runs[runs["counted"]]
    variant: list[str] = []
    between: list[str] = []
    for column in sorted(c for c in identified.columns if str(c).startswith(PARAM_PREFIX)):
        name = column[len(PARAM_PREFIX) :]
        if is_bookkeeping_param(name):
            continue
        sub = identified[_relevance_mask(identified, name)]
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
    runs: pd.DataFrame, variant_params: list[str]
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
            if param_applies(p, str(method), str(decomposer))
            and sub[PARAM_PREFIX + p].nunique(dropna=False) > 1
        ]
    variants: list[str] = []
    labels: list[str] = []
    for row in runs.to_dict("records"):
        method, decomposer = str(row["method"]), str(row["decomposer"])
        identified = bool(row["counted"])
        params = family_params.get((method, decomposer), []) if identified else []
        values = {p: str(row[PARAM_PREFIX + p]) for p in params}
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
