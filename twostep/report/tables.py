"""The paper comparisons: TwoStep's % changes against SA / MA, and Table I."""

from __future__ import annotations

import math
from typing import Any

import pandas as pd

from twostep.report.aggregation import sample_std
from twostep.report.model import REPORT_METRICS
from twostep.report.paper import (
    ANNOTATED_TASKS,
    PAPER_CHANGE_PCT,
    PAPER_TABLE1,
    TABLE1_AGENTS,
    TABLE1_DOMAINS,
)
from twostep.util.outcome import ReportStatus


def changes_against_baselines(
    normalised: pd.DataFrame, series_frame: pd.DataFrame, values_of: dict[str, dict[str, str]]
) -> pd.DataFrame:
    """TwoStep against every SA / MA series whose variant values do not contradict it."""
    rows: list[dict[str, Any]] = []
    twostep = series_frame[series_frame["method"] == "twostep"]
    for _, target in twostep.iterrows():
        target_variant = values_of.get(str(target["series"]), {})
        for base_method in ("sa", "ma"):
            bases = series_frame[series_frame["method"] == base_method]
            for _, base in bases.iterrows():
                base_variant = values_of.get(str(base["series"]), {})
                shared = set(target_variant) & set(base_variant)
                if any(target_variant[p] != base_variant[p] for p in shared):
                    continue
                for metric in REPORT_METRICS:
                    t_rows = normalised[
                        (normalised["series"] == target["series"])
                        & (normalised["metric"] == metric)
                    ]
                    for agents in sorted(int(n) for n in t_rows["agents"].unique()):
                        if agents < 2:
                            continue
                        base_n = 1 if base_method == "sa" else agents
                        t = t_rows[t_rows["agents"] == agents].set_index("domain")
                        b = normalised[
                            (normalised["series"] == base["series"])
                            & (normalised["metric"] == metric)
                            & (normalised["agents"] == base_n)
                        ].set_index("domain")
                        rows.append(
                            change_row(t, b, str(target["series"]), str(base["series"]))
                            | {"metric": metric, "agents": agents}
                        )
    columns = [
        "series",
        "baseline",
        "metric",
        "agents",
        "n_domains",
        "domains",
        "twostep_normalised",
        "baseline_normalised",
        "change_pct",
        "change_pct_raw",
        "paper_change_pct",
    ]
    frame = pd.DataFrame.from_records(rows, columns=columns)
    frame["paper_change_pct"] = [
        PAPER_CHANGE_PCT.get(str(m), {}).get(int(n), math.nan)
        for m, n in zip(frame["metric"], frame["agents"], strict=True)
    ]
    return frame


def change_row(t: pd.DataFrame, b: pd.DataFrame, series: str, baseline: str) -> dict[str, Any]:
    common = sorted(set(t.index) & set(b.index))
    row: dict[str, Any] = {
        "series": series,
        "baseline": baseline,
        "n_domains": len(common),
        "domains": ",".join(str(d) for d in common),
    }
    if not common:
        return row | {
            "twostep_normalised": math.nan,
            "baseline_normalised": math.nan,
            "change_pct": math.nan,
            "change_pct_raw": math.nan,
        }
    t_norm = float(t.loc[common, "normalised"].mean())
    b_norm = float(b.loc[common, "normalised"].mean())
    raw = [
        (float(t.loc[d, "mean"]) - float(b.loc[d, "mean"])) / float(b.loc[d, "mean"]) * 100
        for d in common
        if float(b.loc[d, "mean"]) > 0
    ]
    return row | {
        "twostep_normalised": t_norm,
        "baseline_normalised": b_norm,
        # Min-max scaling within a single domain only ranks the series (0 or 1): a change
        # of those is meaningless, so the paper's normalised change needs two domains.
        "change_pct": (
            (t_norm - b_norm) / b_norm * 100 if b_norm > 0 and len(common) > 1 else math.nan
        ),
        "change_pct_raw": sum(raw) / len(raw) if raw else math.nan,
    }


def table_one(identified: pd.DataFrame, series_frame: pd.DataFrame) -> pd.DataFrame:
    rows: list[dict[str, Any]] = []
    in_scope = identified[
        identified["task"].isin(ANNOTATED_TASKS) & identified["domain"].isin(TABLE1_DOMAINS)
    ]
    for _, series in series_frame.iterrows():
        agents = 1 if series["method"] == "sa" else TABLE1_AGENTS
        cells = in_scope[(in_scope["series"] == series["series"]) & (in_scope["agents"] == agents)]
        ok = cells[(cells["status"] == ReportStatus.SUCCESS) & cells["exec_length"].notna()]
        if ok.empty:
            continue
        label = str(series["series"])
        if series["method"] != "twostep":
            label = f"{label} (N={agents}, reference)"
        row: dict[str, Any] = {"series": label, "source": "this report"}
        row["seeded"] = bool(ok["seeded"].any()) if "seeded" in ok else True
        per_domain_seed: dict[str, pd.Series] = {}
        for domain in TABLE1_DOMAINS:
            sub = ok[ok["domain"] == domain]
            per_seed = sub.groupby("seed")["exec_length"].mean()
            per_domain_seed[domain] = per_seed
            row[f"{domain}_mean"] = float(per_seed.mean()) if len(per_seed) else math.nan
            row[f"{domain}_std"] = sample_std(per_seed)
            row[f"{domain}_n_seeds"] = len(per_seed)
            row[f"{domain}_n_tasks"] = int(sub["task"].nunique())
        present = [d for d in TABLE1_DOMAINS if len(per_domain_seed[d])]
        macro_frame = pd.DataFrame({d: per_domain_seed[d] for d in present}).dropna()
        macro = macro_frame.mean(axis=1) if len(macro_frame) else pd.Series(dtype=float)
        row["macro_mean"] = float(macro.mean()) if len(macro) else math.nan
        row["macro_std"] = sample_std(macro)
        row["macro_n_seeds"] = len(macro)
        row["macro_n_domains"] = len(present)
        row["n_failed"] = int(
            cells["status"].isin([ReportStatus.FAILED, ReportStatus.TIMEOUT]).sum()
        )
        rows.append(row)
    for label, values in PAPER_TABLE1:
        paper_row: dict[str, Any] = {"series": label, "source": "paper"}
        for key, (mean, std) in values.items():
            paper_row[f"{key}_mean"] = mean
            paper_row[f"{key}_std"] = math.nan if std is None else std
        paper_row["macro_n_domains"] = len(TABLE1_DOMAINS)
        rows.append(paper_row)
    columns = [
        "series",
        "source",
        *(f"{d}_{s}" for d in TABLE1_DOMAINS for s in ("mean", "std", "n_seeds", "n_tasks")),
        "macro_mean",
        "macro_std",
        "macro_n_seeds",
        "macro_n_domains",
        "n_failed",
        "seeded",
    ]
    return pd.DataFrame.from_records(rows, columns=columns)
