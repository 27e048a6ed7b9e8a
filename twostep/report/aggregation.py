"""Aggregation and normalisation: per-seed means, cell summaries, the min-max scaled panel."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

from twostep.report.model import CELL_COLUMNS, CELL_METRICS, REPORT_METRICS, SERIES_COLUMNS
from twostep.util.outcome import ReportStatus


def sample_std(values: pd.Series) -> float:
    clean = values.dropna()
    return float(clean.std(ddof=1)) if len(clean) >= 2 else float("nan")


def span(values: pd.Series) -> str:
    clean = [int(v) for v in values.dropna()]
    if not clean:
        return ""
    low, high = min(clean), max(clean)
    return str(low) if low == high else f"{low}-{high}"


def per_seed_means(ok: pd.DataFrame) -> pd.DataFrame:
    keys = [*CELL_COLUMNS, "seed"]
    columns = [*keys, *CELL_METRICS, *(f"{m}_n_tasks" for m in CELL_METRICS)]
    if ok.empty:
        return pd.DataFrame(columns=columns)
    grouped = ok.groupby(keys, dropna=False)
    out = grouped[list(CELL_METRICS)].mean()
    for metric in CELL_METRICS:
        out[f"{metric}_n_tasks"] = grouped[metric].count()
    return out.reset_index()[columns]


def cell_counts(identified: pd.DataFrame) -> pd.DataFrame:
    status = identified["status"]
    missing = (status == ReportStatus.SUCCESS) & identified[list(REPORT_METRICS)].isna().any(axis=1)
    frame = identified.assign(
        _success=(status == ReportStatus.SUCCESS).astype(int),
        _failed=(status == ReportStatus.FAILED).astype(int),
        _timeout=(status == ReportStatus.TIMEOUT).astype(int),
        _running=(status == ReportStatus.RUNNING).astype(int),
        _missing=missing.astype(int),
    )
    grouped = frame.groupby(list(CELL_COLUMNS), dropna=False)
    counts = pd.DataFrame(
        {
            "n_runs": grouped.size(),
            "n_success": grouped["_success"].sum(),
            "n_failed": grouped["_failed"].sum(),
            "n_timeout": grouped["_timeout"].sum(),
            "n_running": grouped["_running"].sum(),
            "n_missing_metrics": grouped["_missing"].sum(),
            "n_tasks": grouped["task"].nunique(),
        }
    )
    finished = counts["n_success"] + counts["n_failed"] + counts["n_timeout"]
    counts["success_rate"] = (counts["n_success"] / finished.where(finished > 0)).astype(float)
    return counts.reset_index()


def cell_summary(identified: pd.DataFrame, per_seed: pd.DataFrame) -> pd.DataFrame:
    counts = cell_counts(identified)
    stats = over_seeds(per_seed, list(CELL_COLUMNS))
    spans = (
        per_seed.groupby(list(CELL_COLUMNS), dropna=False)[f"{REPORT_METRICS[0]}_n_tasks"]
        .agg(span)
        .rename("tasks_per_seed")
        .reset_index()
        if len(per_seed)
        else pd.DataFrame(columns=[*CELL_COLUMNS, "tasks_per_seed"])
    )
    stats = stats.merge(spans, on=list(CELL_COLUMNS), how="left")
    summary = counts.merge(stats, on=list(CELL_COLUMNS), how="left")
    for metric in CELL_METRICS:
        summary[f"{metric}_n_seeds"] = summary[f"{metric}_n_seeds"].fillna(0).astype(int)
    summary["tasks_per_seed"] = summary["tasks_per_seed"].fillna("")
    ordered = [
        *CELL_COLUMNS,
        *(f"{m}_{s}" for m in CELL_METRICS for s in ("mean", "std", "n_seeds")),
        "success_rate",
        "n_runs",
        "n_success",
        "n_failed",
        "n_timeout",
        "n_running",
        "n_missing_metrics",
        "n_tasks",
        "tasks_per_seed",
    ]
    return summary[ordered]


def over_seeds(per_seed: pd.DataFrame, keys: list[str]) -> pd.DataFrame:
    """Mean, sample std and count over seeds of per-seed values, per ``keys``."""
    columns = [*keys, *(f"{m}_{s}" for m in CELL_METRICS for s in ("mean", "std", "n_seeds"))]
    if per_seed.empty:
        return pd.DataFrame(columns=columns)
    grouped = per_seed.groupby(keys, dropna=False)
    out = pd.DataFrame(index=grouped.size().index)
    for metric in CELL_METRICS:
        out[f"{metric}_mean"] = grouped[metric].mean()
        out[f"{metric}_std"] = grouped[metric].std(ddof=1)
        out[f"{metric}_n_seeds"] = grouped[metric].count()
    return out.reset_index()[columns]


def per_task_means(identified: pd.DataFrame, ok: pd.DataFrame) -> pd.DataFrame:
    keys = [*CELL_COLUMNS, "task"]
    counts = identified.groupby(keys, dropna=False).agg(
        n_runs=("run_id", "size"),
        n_success=("status", lambda s: int((s == ReportStatus.SUCCESS).sum())),
    )
    if ok.empty:
        per_seed = pd.DataFrame(columns=[*keys, "seed", *CELL_METRICS])
    else:
        per_seed = ok.groupby([*keys, "seed"], dropna=False)[list(CELL_METRICS)].mean()
        per_seed = per_seed.reset_index()
    stats = over_seeds(per_seed, keys)
    out = counts.reset_index().merge(stats, on=keys, how="left")
    return out.sort_values(keys).reset_index(drop=True)


def eligible_cells(identified: pd.DataFrame, summary: pd.DataFrame) -> pd.Series:
    """True for summary cells that cover all their domain's tasks."""
    domain_tasks = identified.groupby("domain")["task"].agg(lambda s: frozenset(s.dropna()))
    cell_tasks = identified.groupby(list(CELL_COLUMNS), dropna=False)["task"].agg(
        lambda s: frozenset(s.dropna())
    )
    flags = [
        cell_tasks.get(tuple(row[c] for c in CELL_COLUMNS), frozenset())
        == domain_tasks.get(row["domain"], frozenset())
        for _, row in summary.iterrows()
    ]
    return pd.Series(flags, index=summary.index, dtype=bool)


def normalise(
    summary: pd.DataFrame,
    per_seed: pd.DataFrame,
    eligible: pd.Series,
    length_of: Mapping[str, str] | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Per domain and metric, min-max scaled cell means (and per-seed values).

    ``length_of`` names, per domain, the column that measures its execution length
    (``embodied_length`` for kitchen runs); ``exec_length`` where it is not given. The
    rows keep the metric name ``exec_length`` and say what was read in ``measured_as``.
    """
    norm_rows: list[dict[str, Any]] = []
    seed_rows: list[dict[str, Any]] = []
    for metric in REPORT_METRICS:
        for domain, sub in summary[eligible].groupby("domain"):
            column = metric
            if metric == REPORT_METRICS[0] and length_of is not None:
                column = length_of.get(str(domain), metric)
            sub = sub[sub[f"{column}_mean"].notna()]
            if sub.empty:
                continue
            low = float(sub[f"{column}_mean"].min())
            high = float(sub[f"{column}_mean"].max())
            scale = high - low

            def scaled(value: float, low: float = low, scale: float = scale) -> float:
                return (value - low) / scale if scale > 0 else 0.0

            for _, row in sub.iterrows():
                record = {c: row[c] for c in CELL_COLUMNS}
                norm_rows.append(
                    {
                        **record,
                        "metric": metric,
                        "measured_as": column,
                        "mean": float(row[f"{column}_mean"]),
                        "normalised": scaled(float(row[f"{column}_mean"])),
                        "domain_min": low,
                        "domain_max": high,
                    }
                )
            cells = {tuple(r) for r in sub[list(CELL_COLUMNS)].itertuples(index=False)}
            seeds = per_seed[per_seed["domain"] == domain]
            for _, row in seeds.iterrows():
                if tuple(row[c] for c in CELL_COLUMNS) not in cells:
                    continue
                if pd.isna(row[column]):
                    continue
                seed_rows.append(
                    {
                        **{c: row[c] for c in CELL_COLUMNS},
                        "seed": row["seed"],
                        "metric": metric,
                        "normalised": scaled(float(row[column])),
                    }
                )
    normalised = pd.DataFrame.from_records(
        norm_rows,
        columns=[
            *CELL_COLUMNS,
            "metric",
            "measured_as",
            "mean",
            "normalised",
            "domain_min",
            "domain_max",
        ],
    )
    seed_frame = pd.DataFrame.from_records(
        seed_rows, columns=[*CELL_COLUMNS, "seed", "metric", "normalised"]
    )
    return normalised, seed_frame


def cross_domain_means(normalised: pd.DataFrame, seed_norm: pd.DataFrame) -> pd.DataFrame:
    keys = [*SERIES_COLUMNS, "agents", "metric"]
    rows: list[dict[str, Any]] = []
    for key, sub in normalised.groupby(keys, dropna=False):
        domains = sorted(str(d) for d in sub["domain"])
        row: dict[str, Any] = dict(zip(keys, key, strict=True))
        row["normalised_mean"] = float(sub["normalised"].mean())
        mask = pd.Series(True, index=seed_norm.index)
        for column in keys:
            mask &= seed_norm[column] == row[column]
        seeds = seed_norm[mask]
        per_seed = seeds.groupby("seed").agg(
            value=("normalised", "mean"), n_domains=("domain", "nunique")
        )
        complete = per_seed[per_seed["n_domains"] == len(domains)]["value"]
        row["normalised_std"] = sample_std(complete)
        row["n_seeds"] = len(complete)
        row["n_domains"] = len(domains)
        row["domains"] = ",".join(domains)
        rows.append(row)
    columns = [*keys, "normalised_mean", "normalised_std", "n_seeds", "n_domains", "domains"]
    return pd.DataFrame.from_records(rows, columns=columns)
