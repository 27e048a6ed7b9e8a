"""TwoStep against MA in planning time, per domain and N: the paper's planning-time claim.

The paper reports that TwoStep plans faster than MA (-50.1 / -60.3 / -64.7 % for
N = 2 / 3 / 4, after min-max normalising across domains). The report's change table
gives that normalised figure across domains; this view answers the question per domain,
in seconds, beside what explains it:

* ``sa_time_s`` / ``ma_time_s`` / ``twostep_time_s``: the report's cell means
  (:attr:`~twostep.report.model.Report.summary`; SA at N = 1, MA and TwoStep at N);
* ``change_pct``: (TwoStep - MA) / MA of those means, in percent (negative = TwoStep
  plans faster), with the paper's figure for that N beside it;
* ``sa_exec`` / ``ma_exec`` / ``twostep_exec``: the execution lengths of the same cells;
* ``ma_at_limit``: share of the cell's successful MA runs whose planner call stopped at its
  time limit (an anytime planner that never proves its plan optimal uses all of it);
* ``twostep_no_helper``: share of the cell's successful TwoStep runs with no accepted
  helper subgoal: they return the SA plan, and its planner time is theirs.

A row ``all`` per N averages each column over the domains that have the three series,
and its ``change_pct`` is the change of those averages (seconds, not normalised).
"""

from __future__ import annotations

import math
from typing import Any

import pandas as pd

from twostep.report.paper import PAPER_CHANGE_PCT
from twostep.util.outcome import ReportStatus

ALL_DOMAINS = "all"

COLUMNS: tuple[str, ...] = (
    "twostep_series",
    "ma_series",
    "domain",
    "agents",
    "sa_time_s",
    "ma_time_s",
    "twostep_time_s",
    "change_pct",
    "paper_change_pct",
    "sa_exec",
    "ma_exec",
    "twostep_exec",
    "ma_at_limit",
    "twostep_no_helper",
)

_AVERAGED: tuple[str, ...] = (
    "sa_time_s",
    "ma_time_s",
    "twostep_time_s",
    "sa_exec",
    "ma_exec",
    "twostep_exec",
    "ma_at_limit",
    "twostep_no_helper",
)


def _pairs(summary: pd.DataFrame, method: str, base_method: str) -> list[tuple[str, str]]:
    """(TwoStep series, baseline series) with the same variant; the only baseline when
    there is one."""
    cells = summary[["series", "method", "variant"]].drop_duplicates()
    targets = cells[cells["method"] == method]
    bases = cells[cells["method"] == base_method]
    pairs: list[tuple[str, str]] = []
    for target in targets.to_dict("records"):
        same = bases[bases["variant"] == target["variant"]]
        chosen = same if len(same) else (bases if len(bases) == 1 else bases.iloc[0:0])
        pairs += [(str(target["series"]), str(s)) for s in chosen["series"]]
    return pairs


def _cell(summary: pd.DataFrame, series: str, domain: str, agents: int) -> dict[str, Any] | None:
    rows = summary[
        (summary["series"] == series)
        & (summary["domain"] == domain)
        & (summary["agents"] == agents)
    ]
    return None if rows.empty else dict(rows.iloc[0])


def _share(runs: pd.DataFrame, series: str, domain: str, agents: int, test: str) -> float:
    """Share of the cell's successful runs for which ``test`` holds (NaN without runs)."""
    ok = runs[
        (runs["series"] == series)
        & (runs["domain"] == domain)
        & (runs["agents"] == agents)
        & (runs["status"] == ReportStatus.SUCCESS)
    ]
    if "counted" in ok:
        ok = ok[ok["counted"]]
    if ok.empty:
        return math.nan
    if test == "at_limit":
        hits = ok["planner_timeouts"].fillna(0) > 0
    else:
        hits = ok["subgoals_accepted"].fillna(0) == 0
    return float(hits.mean())


def _change(value: float, base: float) -> float:
    if math.isnan(value) or math.isnan(base) or base <= 0:
        return math.nan
    return (value - base) / base * 100


def _value(cell: dict[str, Any] | None, column: str) -> float:
    if cell is None or pd.isna(cell[column]):
        return math.nan
    return float(cell[column])


def planning_time_view(summary: pd.DataFrame, runs: pd.DataFrame) -> pd.DataFrame:
    """The view described in the module docstring, from a report's summary and runs.

    ``summary`` has the columns of :attr:`~twostep.report.model.Report.summary`; ``runs``
    the run table with ``series`` (:attr:`~twostep.report.model.Report.runs`). Empty
    when the report has no TwoStep series with N >= 2 and no MA series to pair it with.
    """
    rows: list[dict[str, Any]] = []
    sa_series = summary[summary["method"] == "sa"]["series"].drop_duplicates().tolist()
    sa = str(sa_series[0]) if len(sa_series) == 1 else None
    for twostep, ma in _pairs(summary, "twostep", "ma"):
        agent_counts = sorted(
            int(n) for n in summary[summary["series"] == twostep]["agents"].unique() if n >= 2
        )
        for agents in agent_counts:
            per_domain: list[dict[str, Any]] = []
            for domain in sorted(str(d) for d in summary["domain"].unique()):
                t = _cell(summary, twostep, domain, agents)
                m = _cell(summary, ma, domain, agents)
                if t is None or m is None:
                    continue
                s = _cell(summary, sa, domain, 1) if sa is not None else None
                row = {
                    "sa_time_s": _value(s, "planning_time_s_mean"),
                    "ma_time_s": _value(m, "planning_time_s_mean"),
                    "twostep_time_s": _value(t, "planning_time_s_mean"),
                    "sa_exec": _value(s, "exec_length_mean"),
                    "ma_exec": _value(m, "exec_length_mean"),
                    "twostep_exec": _value(t, "exec_length_mean"),
                    "ma_at_limit": _share(runs, ma, domain, agents, "at_limit"),
                    "twostep_no_helper": _share(runs, twostep, domain, agents, "no_helper"),
                }
                per_domain.append({"domain": domain, **row})
            if not per_domain:
                continue
            complete = [r for r in per_domain if not any(math.isnan(r[k]) for k in _AVERAGED[:3])]
            overall: dict[str, Any] = {"domain": ALL_DOMAINS}
            for column in _AVERAGED:
                values = [r[column] for r in complete if not math.isnan(r[column])]
                overall[column] = sum(values) / len(values) if values else math.nan
            for row in [*per_domain, overall]:
                rows.append(
                    {
                        "twostep_series": twostep,
                        "ma_series": ma,
                        "agents": agents,
                        **row,
                        "change_pct": _change(row["twostep_time_s"], row["ma_time_s"]),
                        "paper_change_pct": PAPER_CHANGE_PCT["planning_time_s"].get(
                            agents, math.nan
                        ),
                    }
                )
    return pd.DataFrame.from_records(rows, columns=list(COLUMNS))


def _number(value: object, digits: int) -> str:
    if value is None or pd.isna(value):  # type: ignore[call-overload]
        return "n/a"
    return f"{float(str(value)):.{digits}f}"


def _pct(value: object) -> str:
    if value is None or pd.isna(value):  # type: ignore[call-overload]
        return "n/a"
    return f"{float(str(value)):+.1f} %"


def _share_text(value: object) -> str:
    if value is None or pd.isna(value):  # type: ignore[call-overload]
        return "n/a"
    return f"{float(str(value)) * 100:.0f} %"


def view_rows(view: pd.DataFrame) -> tuple[list[str], list[list[str]]]:
    """Headers and formatted rows of :func:`planning_time_view` for a Markdown table."""
    headers = [
        "N",
        "domain",
        "SA time (s)",
        "MA time (s)",
        "TwoStep time (s)",
        "TwoStep vs MA",
        "paper",
        "SA / MA / TwoStep exec",
        "MA at limit",
        "TwoStep no helper",
    ]
    several = view["twostep_series"].nunique() > 1 or view["ma_series"].nunique() > 1
    if several:
        headers = ["TwoStep series", "MA series", *headers]
    rows: list[list[str]] = []
    for row in view.to_dict("records"):
        cells = [
            str(row["agents"]),
            f"**{row['domain']}**" if row["domain"] == ALL_DOMAINS else str(row["domain"]),
            _number(row["sa_time_s"], 2),
            _number(row["ma_time_s"], 2),
            _number(row["twostep_time_s"], 2),
            _pct(row["change_pct"]),
            _pct(row["paper_change_pct"]) if row["domain"] == ALL_DOMAINS else "",
            " / ".join(_number(row[k], 1) for k in ("sa_exec", "ma_exec", "twostep_exec")),
            _share_text(row["ma_at_limit"]),
            _share_text(row["twostep_no_helper"]),
        ]
        rows.append(
            [str(row["twostep_series"]), str(row["ma_series"]), *cells] if several else cells
        )
    return headers, rows
