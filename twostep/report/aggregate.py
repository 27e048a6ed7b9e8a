"""From the run table to the paper's numbers: every table a report shows, as DataFrames.

:func:`build_report` is the entry point. How the numbers are made:

* **Series.** A line in Fig. 3 is a *series*: SA, MA, or TwoStep with one decomposer
  ("TwoStep (goal-split)"). When runs of one job cell (domain, task, method, decomposer,
  N, seed) differ in a config value (two planner time limits, two LLM models), that
  param is a *variant param*: the series are split by it ("... [planner.time_limit_s=10]")
  and the report says so. ``llm.*`` params only count for TwoStep with the ``llm``
  decomposer, ``decomposer.*`` only for TwoStep.
* **Means.** Only successful runs with the metric recorded enter a mean. For each
  (domain, series, N, seed) the metric is averaged over tasks; the table shows the mean
  and the sample standard deviation (ddof = 1) of those per-seed averages over seeds, as
  the paper does for its 3 runs. One seed: no std ("1 seed").
* **Counts.** Failed, timed-out and still-running runs are counted in every cell.
* **Normalised panel.** Per domain and metric, the per-domain averages of every series
  and N are min-max scaled to [0, 1], then averaged across domains (the paper's
  rightmost column of Fig. 3). A cell that covers fewer of the domain's tasks than the
  others (e.g. expert subgoals, 4 tasks) is left out of the scaling, with a note.
* **Changes.** TwoStep against SA (N = 1) and MA (same N), in percent of the baseline's
  normalised cross-domain average, over the domains both have (as the paper computes
  its -50.1 % ...); also the mean over domains of the raw per-domain changes.
* **Table I.** Execution length on tasks 1, 6, 11, 16 of four domains at N = 2, per
  domain mean +- std over seeds of the 4-task average, and the macro average.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from twostep.report.paper import (
    ANNOTATED_TASKS,
    PAPER_CHANGE_PCT,
    PAPER_TABLE1,
    TABLE1_AGENTS,
    TABLE1_DOMAINS,
)
from twostep.report.runs import (
    KEY_COLUMNS,
    PARAM_PREFIX,
    ReportInputError,
    normalise_runs,
)

#: The two metrics of Fig. 3, with axis labels.
REPORT_METRICS: tuple[str, ...] = ("exec_length", "planning_time_s")
METRIC_LABELS: dict[str, str] = {
    "exec_length": "Execution length (steps)",
    "planning_time_s": "Planning time (s)",
}
METRIC_NAMES: dict[str, str] = {
    "exec_length": "execution length",
    "planning_time_s": "planning time",
}

#: Bookkeeping params that never make results different: where outputs, stores and
#: caches live, how jobs are orchestrated and tracked, how LLM calls are retried.
IGNORED_PARAMS: frozenset[str] = frozenset(
    {"llm.cache_dir", "llm.max_retries", "llm.backoff_s", "llm.api_key_env"}
)
IGNORED_PARAM_PREFIXES: tuple[str, ...] = ("output.", "orchestration.", "mlflow.", "hydra.")


def is_bookkeeping_param(name: str) -> bool:
    """True for params that never split series (see :data:`IGNORED_PARAMS`)."""
    return name in IGNORED_PARAMS or name.startswith(IGNORED_PARAM_PREFIXES)


SERIES_COLUMNS: tuple[str, ...] = ("series", "method", "decomposer", "variant")
CELL_COLUMNS: tuple[str, ...] = ("domain", *SERIES_COLUMNS, "agents")
_METHOD_ORDER = {"sa": 0, "ma": 1, "twostep": 2}


@dataclass(frozen=True)
class Report:
    """Every table of a report. Build with :func:`build_report`; write with
    :func:`twostep.report.render.write_report`.

    ``runs``: the canonical run table plus ``series``, ``variant`` and ``identified``.
    ``per_seed``: one row per (domain, series, N, seed): task averages.
    ``per_task``: one row per (domain, series, N, task): mean/std over seeds.
    ``summary``: one row per (domain, series, N): counts, mean/std over seeds.
    ``normalised``: per (domain, series, N, metric) the min-max scaled mean.
    ``cross_domain``: per (series, N, metric) the normalised mean across domains.
    ``changes``: TwoStep vs SA/MA per N and metric, beside the paper's figures.
    ``table1``: expert vs decomposers on the annotated tasks (paper's rows included).
    """

    runs: pd.DataFrame
    per_seed: pd.DataFrame
    per_task: pd.DataFrame
    summary: pd.DataFrame
    normalised: pd.DataFrame
    cross_domain: pd.DataFrame
    changes: pd.DataFrame
    table1: pd.DataFrame
    counts: dict[str, int]
    series: tuple[str, ...]
    variant_params: tuple[str, ...]
    notes: tuple[str, ...] = field(default=())

    @property
    def domains(self) -> tuple[str, ...]:
        return tuple(sorted(str(d) for d in self.summary["domain"].unique()))

    @property
    def agent_counts(self) -> tuple[int, ...]:
        return tuple(sorted(int(n) for n in self.summary["agents"].unique()))

    @property
    def has_results(self) -> bool:
        """True when at least one cell has a mean (some run succeeded with metrics)."""
        return bool(self.summary[[f"{m}_mean" for m in REPORT_METRICS]].notna().any().any())


# ------------------------------------------------------------------ series


def series_label(method: str, decomposer: str, variant: str = "") -> str:
    """The legend label of a series: ``SA``, ``MA``, ``TwoStep (goal-split) [p=v]``."""
    base = {"sa": "SA", "ma": "MA"}.get(method)
    if base is None:
        base = f"TwoStep ({decomposer})" if method == "twostep" and decomposer else method
    return f"{base} [{variant}]" if variant else base


def _param_relevant(param: str, method: str, decomposer: str) -> bool:
    if param.startswith("decomposer."):
        return method == "twostep"
    if param.startswith("llm."):
        return method == "twostep" and decomposer == "llm"
    return True


def _relevance_mask(runs: pd.DataFrame, param: str) -> pd.Series:
    if param.startswith("decomposer."):
        return runs["method"] == "twostep"
    if param.startswith("llm."):
        return (runs["method"] == "twostep") & (runs["decomposer"] == "llm")
    return pd.Series(True, index=runs.index)


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


def _assign_series(
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
            if _param_relevant(p, str(method), str(decomposer))
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


def _series_order(runs: pd.DataFrame) -> tuple[str, ...]:
    identified = runs[runs["counted"]]
    keys = identified[list(SERIES_COLUMNS)].drop_duplicates()
    ordered = sorted(
        keys.itertuples(index=False),
        key=lambda r: (_METHOD_ORDER.get(str(r.method), 9), str(r.decomposer), str(r.variant)),
    )
    return tuple(str(r.series) for r in ordered)


# ------------------------------------------------------------------ aggregation


def _std(values: pd.Series) -> float:
    clean = values.dropna()
    return float(clean.std(ddof=1)) if len(clean) >= 2 else float("nan")


def _span(values: pd.Series) -> str:
    clean = [int(v) for v in values.dropna()]
    if not clean:
        return ""
    low, high = min(clean), max(clean)
    return str(low) if low == high else f"{low}-{high}"


def _per_seed(ok: pd.DataFrame) -> pd.DataFrame:
    keys = [*CELL_COLUMNS, "seed"]
    columns = [*keys, *REPORT_METRICS, *(f"{m}_n_tasks" for m in REPORT_METRICS)]
    if ok.empty:
        return pd.DataFrame(columns=columns)
    grouped = ok.groupby(keys, dropna=False)
    out = grouped[list(REPORT_METRICS)].mean()
    for metric in REPORT_METRICS:
        out[f"{metric}_n_tasks"] = grouped[metric].count()
    return out.reset_index()[columns]


def _cell_counts(identified: pd.DataFrame) -> pd.DataFrame:
    status = identified["status"]
    missing = (status == "success") & identified[list(REPORT_METRICS)].isna().any(axis=1)
    frame = identified.assign(
        _success=(status == "success").astype(int),
        _failed=(status == "failed").astype(int),
        _timeout=(status == "timeout").astype(int),
        _running=(status == "running").astype(int),
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


def _summary(identified: pd.DataFrame, per_seed: pd.DataFrame) -> pd.DataFrame:
    counts = _cell_counts(identified)
    stats = _over_seeds(per_seed, list(CELL_COLUMNS))
    spans = (
        per_seed.groupby(list(CELL_COLUMNS), dropna=False)[f"{REPORT_METRICS[0]}_n_tasks"]
        .agg(_span)
        .rename("tasks_per_seed")
        .reset_index()
        if len(per_seed)
        else pd.DataFrame(columns=[*CELL_COLUMNS, "tasks_per_seed"])
    )
    stats = stats.merge(spans, on=list(CELL_COLUMNS), how="left")
    summary = counts.merge(stats, on=list(CELL_COLUMNS), how="left")
    for metric in REPORT_METRICS:
        summary[f"{metric}_n_seeds"] = summary[f"{metric}_n_seeds"].fillna(0).astype(int)
    summary["tasks_per_seed"] = summary["tasks_per_seed"].fillna("")
    ordered = [
        *CELL_COLUMNS,
        *(f"{m}_{s}" for m in REPORT_METRICS for s in ("mean", "std", "n_seeds")),
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


def _over_seeds(per_seed: pd.DataFrame, keys: list[str]) -> pd.DataFrame:
    """Mean, sample std and count over seeds of per-seed values, per ``keys``."""
    columns = [*keys, *(f"{m}_{s}" for m in REPORT_METRICS for s in ("mean", "std", "n_seeds"))]
    if per_seed.empty:
        return pd.DataFrame(columns=columns)
    grouped = per_seed.groupby(keys, dropna=False)
    out = pd.DataFrame(index=grouped.size().index)
    for metric in REPORT_METRICS:
        out[f"{metric}_mean"] = grouped[metric].mean()
        out[f"{metric}_std"] = grouped[metric].std(ddof=1)
        out[f"{metric}_n_seeds"] = grouped[metric].count()
    return out.reset_index()[columns]


def _per_task(identified: pd.DataFrame, ok: pd.DataFrame) -> pd.DataFrame:
    keys = [*CELL_COLUMNS, "task"]
    counts = identified.groupby(keys, dropna=False).agg(
        n_runs=("run_id", "size"),
        n_success=("status", lambda s: int((s == "success").sum())),
    )
    if ok.empty:
        per_seed = pd.DataFrame(columns=[*keys, "seed", *REPORT_METRICS])
    else:
        per_seed = ok.groupby([*keys, "seed"], dropna=False)[list(REPORT_METRICS)].mean()
        per_seed = per_seed.reset_index()
    stats = _over_seeds(per_seed, keys)
    out = counts.reset_index().merge(stats, on=keys, how="left")
    return out.sort_values(keys).reset_index(drop=True)


def _eligible_cells(identified: pd.DataFrame, summary: pd.DataFrame) -> pd.Series:
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


def _normalise(
    summary: pd.DataFrame, per_seed: pd.DataFrame, eligible: pd.Series
) -> tuple[pd.DataFrame, pd.DataFrame]:
    norm_rows: list[dict[str, Any]] = []
    seed_rows: list[dict[str, Any]] = []
    for metric in REPORT_METRICS:
        usable = summary[eligible & summary[f"{metric}_mean"].notna()]
        for domain, sub in usable.groupby("domain"):
            low = float(sub[f"{metric}_mean"].min())
            high = float(sub[f"{metric}_mean"].max())
            scale = high - low

            def scaled(value: float, low: float = low, scale: float = scale) -> float:
                return (value - low) / scale if scale > 0 else 0.0

            for _, row in sub.iterrows():
                record = {c: row[c] for c in CELL_COLUMNS}
                norm_rows.append(
                    {
                        **record,
                        "metric": metric,
                        "mean": float(row[f"{metric}_mean"]),
                        "normalised": scaled(float(row[f"{metric}_mean"])),
                        "domain_min": low,
                        "domain_max": high,
                    }
                )
            cells = {tuple(r) for r in sub[list(CELL_COLUMNS)].itertuples(index=False)}
            seeds = per_seed[per_seed["domain"] == domain]
            for _, row in seeds.iterrows():
                if tuple(row[c] for c in CELL_COLUMNS) not in cells:
                    continue
                if pd.isna(row[metric]):
                    continue
                seed_rows.append(
                    {
                        **{c: row[c] for c in CELL_COLUMNS},
                        "seed": row["seed"],
                        "metric": metric,
                        "normalised": scaled(float(row[metric])),
                    }
                )
    normalised = pd.DataFrame.from_records(
        norm_rows,
        columns=[*CELL_COLUMNS, "metric", "mean", "normalised", "domain_min", "domain_max"],
    )
    seed_frame = pd.DataFrame.from_records(
        seed_rows, columns=[*CELL_COLUMNS, "seed", "metric", "normalised"]
    )
    return normalised, seed_frame


def _cross_domain(normalised: pd.DataFrame, seed_norm: pd.DataFrame) -> pd.DataFrame:
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
        row["normalised_std"] = _std(complete)
        row["n_seeds"] = len(complete)
        row["n_domains"] = len(domains)
        row["domains"] = ",".join(domains)
        rows.append(row)
    columns = [*keys, "normalised_mean", "normalised_std", "n_seeds", "n_domains", "domains"]
    return pd.DataFrame.from_records(rows, columns=columns)


def _changes(
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
                            _change_row(t, b, str(target["series"]), str(base["series"]))
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


def _change_row(t: pd.DataFrame, b: pd.DataFrame, series: str, baseline: str) -> dict[str, Any]:
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
        "change_pct": (t_norm - b_norm) / b_norm * 100 if b_norm > 0 else math.nan,
        "change_pct_raw": sum(raw) / len(raw) if raw else math.nan,
    }


def _table1(identified: pd.DataFrame, series_frame: pd.DataFrame) -> pd.DataFrame:
    rows: list[dict[str, Any]] = []
    in_scope = identified[
        identified["task"].isin(ANNOTATED_TASKS) & identified["domain"].isin(TABLE1_DOMAINS)
    ]
    for _, series in series_frame.iterrows():
        agents = 1 if series["method"] == "sa" else TABLE1_AGENTS
        cells = in_scope[(in_scope["series"] == series["series"]) & (in_scope["agents"] == agents)]
        ok = cells[(cells["status"] == "success") & cells["exec_length"].notna()]
        if ok.empty:
            continue
        label = str(series["series"])
        if series["method"] != "twostep":
            label = f"{label} (N={agents}, reference)"
        row: dict[str, Any] = {"series": label, "source": "this report"}
        per_domain_seed: dict[str, pd.Series] = {}
        for domain in TABLE1_DOMAINS:
            sub = ok[ok["domain"] == domain]
            per_seed = sub.groupby("seed")["exec_length"].mean()
            per_domain_seed[domain] = per_seed
            row[f"{domain}_mean"] = float(per_seed.mean()) if len(per_seed) else math.nan
            row[f"{domain}_std"] = _std(per_seed)
            row[f"{domain}_n_seeds"] = len(per_seed)
            row[f"{domain}_n_tasks"] = int(sub["task"].nunique())
        present = [d for d in TABLE1_DOMAINS if len(per_domain_seed[d])]
        macro_frame = pd.DataFrame({d: per_domain_seed[d] for d in present}).dropna()
        macro = macro_frame.mean(axis=1) if len(macro_frame) else pd.Series(dtype=float)
        row["macro_mean"] = float(macro.mean()) if len(macro) else math.nan
        row["macro_std"] = _std(macro)
        row["macro_n_seeds"] = len(macro)
        row["macro_n_domains"] = len(present)
        row["n_failed"] = int(cells["status"].isin(["failed", "timeout"]).sum())
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
    ]
    return pd.DataFrame.from_records(rows, columns=columns)


# ------------------------------------------------------------------ notes


def _notes(
    runs: pd.DataFrame,
    summary: pd.DataFrame,
    per_seed: pd.DataFrame,
    eligible: pd.Series,
    cross: pd.DataFrame,
    variant_params: list[str],
    between: list[str],
) -> list[str]:
    notes: list[str] = []
    identified = runs[runs["counted"]]
    if variant_params:
        described = []
        for param in variant_params:
            values = sorted(set(identified[PARAM_PREFIX + param]))
            described.append(f"{param} ({', '.join(values)})")
        notes.append(
            "Runs differ in config beyond domain/task/method/N/seed/decomposer; series are "
            "split by: " + "; ".join(described) + "."
        )
    if between:
        notes.append(
            "These params differ between methods or decomposers (not used for grouping): "
            + ", ".join(between)
            + "."
        )
    superseded = int(runs["superseded"].sum())
    if superseded:
        notes.append(
            f"{superseded} older run(s) of jobs that were run again (same twostep.job_key) "
            "are superseded by the latest run and left out (runs.csv, column 'superseded')."
        )
    unidentified = int((~runs["placed"] & ~runs["superseded"]).sum())
    if unidentified:
        notes.append(
            f"{unidentified} run(s) lack domain, task, method, N or seed and could not be "
            "placed in any table; they are listed under the failed runs."
        )
    running = int((identified["status"] == "running").sum())
    if running:
        notes.append(
            f"{running} run(s) had not finished when the report was made (still running, "
            "or interrupted before logging a status): counted, not averaged."
        )
    missing = int(summary["n_missing_metrics"].sum())
    if missing:
        notes.append(
            f"{missing} successful run(s) lack exec_length or planning_time_s; "
            "they are counted but left out of the means of the missing metric."
        )
    sa_moved = identified[(identified["method"] == "sa") & (identified["agents_param"] > 1)]
    if len(sa_moved):
        notes.append(
            f"{len(sa_moved)} SA run(s) were launched with N > 1; SA ignores N, so they "
            "count as N = 1 (repeated runs of one task and seed are averaged)."
        )
    ok = identified[identified["status"] == "success"]
    repeats = ok.groupby([*CELL_COLUMNS, "task", "seed"], dropna=False).size()
    repeats = repeats[repeats > 1]
    if len(repeats):
        notes.append(
            f"{len(repeats)} (cell, task, seed) combination(s) have more than one successful "
            "run; their values are averaged before averaging over tasks."
        )
    has_mean = summary[f"{REPORT_METRICS[0]}_mean"].notna()
    single = summary[has_mean & (summary[f"{REPORT_METRICS[0]}_n_seeds"] == 1)]
    if len(single):
        notes.append(
            f"{len(single)} of {int(has_mean.sum())} cells have results from 1 seed only: "
            "no std, shown as 'mean (1 seed)'."
        )
    uneven = summary[summary["tasks_per_seed"].str.contains("-", regex=False)]
    if len(uneven):
        notes.append(
            f"{len(uneven)} cell(s) average a different number of tasks per seed "
            "(failed runs leave their task out): see the 'tasks/seed' column."
        )
    excluded = summary[~eligible & has_mean]
    if len(excluded):
        parts = [
            f"{row.domain} {row.series} N={row.agents} ({row.n_tasks} tasks)"
            for row in excluded.itertuples(index=False)
        ]
        notes.append(
            "Left out of the min-max normalised averages and the changes because they cover "
            "fewer tasks than the rest of their domain: " + "; ".join(parts) + "."
        )
    if len(cross) and cross["n_domains"].nunique() > 1:
        notes.append(
            "Normalised cross-domain points average different numbers of domains "
            f"({_span(cross['n_domains'])}); changes use only the domains both sides have."
        )
    return notes


def _superseded(table: pd.DataFrame) -> pd.Series:
    """True for older runs of a job that was run again (same ``job_key``).

    Re-running a sweep into the same experiment logs the same job again; the report
    counts each job once: its latest finished run (or its latest run if none finished).
    """
    flags = pd.Series(False, index=table.index)
    keyed = table[table["job_key"] != ""]
    if keyed.empty:
        return flags
    order = keyed.assign(
        _finished=(keyed["status"] != "running").astype(int),
        _start=keyed["start_time"].fillna(-1.0),
    ).sort_values(["job_key", "_finished", "_start"])
    latest = order.groupby("job_key").tail(1).index
    flags.loc[keyed.index.difference(latest)] = True
    return flags


# ------------------------------------------------------------------ entry point


def build_report(runs: pd.DataFrame) -> Report:
    """All of a report's tables from a run table (see :mod:`twostep.report.runs`).

    Raises :class:`ReportInputError` when there is no run at all.
    """
    if runs is None or len(runs) == 0:
        raise ReportInputError("no runs to report")
    table = normalise_runs(runs)
    table["placed"] = table[["domain", "task", "method", "agents", "seed"]].notna().all(
        axis=1
    ) & table["method"].isin(["sa", "ma", "twostep"])
    table["superseded"] = _superseded(table)
    table["counted"] = table["placed"] & ~table["superseded"]
    variant_params, between = detect_variant_params(table)
    table, values_of = _assign_series(table, variant_params)
    identified = table[table["counted"]]
    ok = identified[identified["status"] == "success"]

    per_seed = _per_seed(ok)
    summary = _summary(identified, per_seed)
    order = _series_order(table)
    rank = {name: i for i, name in enumerate(order)}
    summary = (
        summary.assign(_rank=summary["series"].map(rank))
        .sort_values(["domain", "_rank", "agents"])
        .drop(columns="_rank")
        .reset_index(drop=True)
    )
    per_task = _per_task(identified, ok)
    eligible = _eligible_cells(identified, summary)
    normalised, seed_norm = _normalise(summary, per_seed, eligible)
    cross = _cross_domain(normalised, seed_norm)
    series_frame = identified[list(SERIES_COLUMNS)].drop_duplicates()
    series_frame = series_frame.assign(_rank=series_frame["series"].map(rank)).sort_values("_rank")
    changes = _changes(normalised, series_frame, values_of)
    table1 = _table1(identified, series_frame)

    current = table[~table["superseded"]]
    status = current["status"]
    counts = {
        "runs": len(current),
        "success": int((status == "success").sum()),
        "failed": int((status == "failed").sum()),
        "timeout": int((status == "timeout").sum()),
        "running": int((status == "running").sum()),
        "unidentified": int((~current["placed"]).sum()),
        "missing_metrics": int(summary["n_missing_metrics"].sum()),
        "superseded": int(table["superseded"].sum()),
    }
    notes = _notes(table, summary, per_seed, eligible, cross, variant_params, between)
    return Report(
        runs=table,
        per_seed=per_seed,
        per_task=per_task,
        summary=summary,
        normalised=normalised,
        cross_domain=cross,
        changes=changes,
        table1=table1,
        counts=counts,
        series=order,
        variant_params=tuple(variant_params),
        notes=tuple(notes),
    )
