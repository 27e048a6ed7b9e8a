"""The paper's Table I and Fig. 3 from replayed answers (the replay sweep's runs).

Three rows per domain and N, all on the same model answers:

* ``official``: the official TwoStep code's own execution length, read from the bundle
  (its logs: anytime LAMA, its single-agent plan ``sa_cost``);
* ``twostep``: twostep's TwoStep on the replayed answers (the ``llm`` subgoal source, the job's
  seed is the bundle's run);
* ``plan-deal``: twostep's plan-deal on the same task and N.

Each cell is averaged over the tasks that every row covers at that domain and N, in every
run (``tasks``; ``own tasks`` is how many each row has on its own: the official code
crashed on some, a twostep job may fail). Where a row holds several runs (several logs of
that N, or seeds), the cell is the mean of the per-run means and ``std`` their sample
standard deviation, as the paper reports its 3 runs; one run: no spread, ``runs`` says 1.
``length / SA`` divides the mean length by the mean single-agent plan length of the same
tasks, each row by its own SA plan (the official one by the official code's, twostep's by
twostep's), and the macro row averages that ratio over the domains.

Pure analysis (pandas): reading the runs and writing files happen elsewhere
(:mod:`twostep.report.replay_plots`, ``flows/report_cli.py``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import pandas as pd

from twostep.replay import Bundle
from twostep.replay.bundle import same_model
from twostep.util.outcome import ReportStatus

SOURCES = ("official", "twostep", "plan-deal")
LABELS: Mapping[str, str] = {
    "official": "official TwoStep (its logs)",
    "twostep": "TwoStep in twostep (same answers)",
    "plan-deal": "plan-deal (twostep)",
}
VALUE_COLUMNS = ("domain", "agents", "source", "run", "task", "exec_length", "sa_length")


@dataclass(frozen=True)
class ReplayTables:
    """The values each row averages, Table I, and the macro row."""

    values: pd.DataFrame  # VALUE_COLUMNS
    table: pd.DataFrame  # one row per domain, N, source
    macro: pd.DataFrame  # per N and source: mean of the domains' length / SA
    model: str

    @property
    def empty(self) -> bool:
        return bool(self.table.empty)


def official_values(bundle: Bundle, model: str) -> pd.DataFrame:
    """The official code's length and SA cost of every task the bundle's logs finished."""
    rows: list[dict[str, Any]] = []
    for entry in bundle.entries:
        run = bundle.run(entry.run)
        if not same_model(model, run.model) or entry.official.exec_length is None:
            continue
        index = [r.id for r in bundle.runs_for(entry.domain, entry.agents, model)].index(run.id)
        rows.append(
            {
                "domain": entry.domain,
                "agents": entry.agents,
                "source": "official",
                "run": index,
                "task": entry.task,
                "exec_length": float(entry.official.exec_length),
                "sa_length": entry.official.sa_cost,
            }
        )
    return pd.DataFrame.from_records(rows, columns=list(VALUE_COLUMNS))


def twostep_values(runs: pd.DataFrame) -> pd.DataFrame:
    """twostep's TwoStep (the ``llm`` subgoal source) and plan-deal runs that succeeded, counted
    once (a run superseded by a later run of the same job is left out)."""
    if runs.empty:
        return pd.DataFrame(columns=list(VALUE_COLUMNS))
    counted = runs[runs["counted"]] if "counted" in runs else runs
    ok = counted[(counted["status"] == ReportStatus.SUCCESS) & (counted["method"] == "twostep")]
    ok = ok[ok["decomposer"].isin(["llm", "plan-deal"]) & ok["exec_length"].notna()]
    frame = pd.DataFrame(
        {
            "domain": ok["domain"].astype(str),
            "agents": ok["agents"].astype(int),
            "source": ok["decomposer"].map({"llm": "twostep", "plan-deal": "plan-deal"}),
            "run": ok["seed"].astype(int),
            "task": ok["task"].astype(int),
            "exec_length": ok["exec_length"].astype(float),
            "sa_length": ok["sa_length"].astype(float) if "sa_length" in ok else math.nan,
        }
    )
    return frame.reset_index(drop=True)


def _std(values: list[float]) -> float:
    if len(values) < 2:
        return math.nan
    mean = sum(values) / len(values)
    return math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1))


def replay_tables(runs: pd.DataFrame, bundle: Bundle, model: str) -> ReplayTables:
    """Table I of a replay (see the module docstring) from the run table of its sweep."""
    values = pd.concat([official_values(bundle, model), twostep_values(runs)], ignore_index=True)
    rows: list[dict[str, Any]] = []
    for (domain, agents), cell in values.groupby(["domain", "agents"], sort=True):
        if not cell["source"].isin(["twostep", "plan-deal"]).any():
            continue  # a cell of the logs the sweep did not run
        covered: set[int] | None = None
        own: dict[str, int] = {}
        for source in SOURCES:  # a row the sweep did not run leaves the others their tasks
            part = cell[cell["source"] == source]
            own[source] = part["task"].nunique()
            for _, per_run in part.groupby("run"):
                tasks = set(per_run["task"].astype(int))
                covered = tasks if covered is None else covered & tasks
        common = covered or set()
        for source in SOURCES:
            part = cell[(cell["source"] == source) & cell["task"].isin(common)]
            means = [float(r["exec_length"].mean()) for _, r in part.groupby("run")]
            sas = [float(r["sa_length"].mean()) for _, r in part.groupby("run")]
            mean = sum(means) / len(means) if means else math.nan
            sa = sum(sas) / len(sas) if sas else math.nan
            rows.append(
                {
                    "domain": domain,
                    "agents": int(agents),
                    "source": source,
                    "row": LABELS[source],
                    "tasks": len(common),
                    "own_tasks": own[source],
                    "runs": len(means),
                    "exec_length": mean,
                    "std": _std(means),
                    "sa_length": sa,
                    "length_over_sa": mean / sa if sa and not math.isnan(sa) else math.nan,
                }
            )
    table = pd.DataFrame.from_records(rows)
    macro_rows: list[dict[str, Any]] = []
    if not table.empty:
        # the domains where every row has a value at that N: the rows compare on the same ones
        full = table.groupby(["domain", "agents"])["length_over_sa"].transform(
            lambda ratios: ratios.notna().all()
        )
        complete = table[full.astype(bool)]
        order = {source: i for i, source in enumerate(SOURCES)}
        groups = sorted(
            complete.groupby(["agents", "source"]), key=lambda g: (g[0][0], order[g[0][1]])
        )
        for (agents, source), part in groups:
            ratios = part["length_over_sa"].dropna()
            macro_rows.append(
                {
                    "agents": int(agents),
                    "source": source,
                    "row": LABELS[str(source)],
                    "domains": len(ratios),
                    "length_over_sa": float(ratios.mean()) if len(ratios) else math.nan,
                }
            )
    return ReplayTables(values, table, pd.DataFrame.from_records(macro_rows), model)


def _number(value: float, digits: int = 1) -> str:
    return "-" if value is None or math.isnan(value) else f"{value:.{digits}f}"


def table_markdown(tables: ReplayTables) -> str:
    """Table I as Markdown: one block of three rows per domain and N."""
    lines = [
        "| domain | N | row | tasks | own tasks | runs | exec length | its SA | length / SA |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|",
    ]
    for row in tables.table.to_dict("records"):
        length = _number(row["exec_length"])
        if not math.isnan(row["std"]):
            length += f" ± {_number(row['std'])}"
        lines.append(
            f"| {row['domain']} | {row['agents']} | {row['row']} | {row['tasks']} | "
            f"{row['own_tasks']} | {row['runs']} | {length} | {_number(row['sa_length'])} | "
            f"{_number(row['length_over_sa'], 2)} |"
        )
    if not tables.macro.empty:
        lines += ["", "| N | row | domains | length / SA (macro) |", "|---:|---|---:|---:|"]
        for row in tables.macro.to_dict("records"):
            lines.append(
                f"| {row['agents']} | {row['row']} | {row['domains']} | "
                f"{_number(row['length_over_sa'], 2)} |"
            )
    return "\n".join(lines) + "\n"


def coverage_markdown(check: Mapping[str, Any]) -> str:
    """The translation check (``twostep-data check-answers``) as Markdown, with its
    planner settings and examples of what failed or differed."""
    if any("differs_known" not in row for row in check.get("summary", [])):
        return "Written by an earlier twostep-data: run `twostep-data check-answers` again.\n"
    lines = [
        f"Planner of the check: {check.get('planner', {}).get('text', '?')}.",
        "",
        "| domain | subgoals | translated | logged cost given | another cost: the answer "
        "goes on | after such an answer | the official call at its limit | other | given, of "
        "the comparable |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in check.get("summary", []):
        match = (
            f"{row['match']}/{row['compared']} ({row['match_pct']} %)" if row["compared"] else "-"
        )
        lines.append(
            f"| {row['domain']} | {row['subgoals']} | {row['translated']} "
            f"({row['translated_pct']} %) | {match} | {row['differs_continued']} | "
            f"{row['differs_after_continued']} | {row['differs_official_limit']} | "
            f"{row['differs_other']} | {row['match']}/{row['compared'] - row['differs_known']} "
            f"({row['match_pct_comparable']} %) |"
        )
    subgoals = check.get("subgoals", [])
    failed = [s for s in subgoals if s["status"] == "untranslated"]
    differs = [s for s in subgoals if s["status"] == "differs"]
    groups: list[tuple[str, list[dict[str, Any]]]] = [("Not translated", failed)]
    for why, title in (
        ("continued", "Another cost than logged: the answer goes on to another helper"),
        ("after_continued", "Another cost than logged: after an answer that goes on"),
        ("official_limit", "Another cost than logged: the official call ran to its limit"),
        (None, "Another cost than logged, no known cause"),
    ):
        groups.append((title, [s for s in differs if s.get("why") == why]))
    for title, items in groups:
        if not items:
            continue
        lines += ["", f"{title} ({len(items)}), examples:", ""]
        seen: set[str] = set()
        for item in items:
            said = item.get("condition") or item["answer"]
            if said in seen or len(seen) >= 4:
                continue
            seen.add(said)
            where = (
                f"{item['domain']} p{item['task']:02d} N={item['agents']} helper {item['helper']}"
            )
            if item["status"] == "untranslated":
                lines.append(f'- {where}: "{said}": {item["reason"]}')
                continue
            cost = "no plan" if item["cost"] is None else f"{item['cost']:g}"
            logged = "no plan" if item["logged_no_plan"] else f"{item['logged_cost']:g}"
            if item.get("logged_time_s") is not None:
                logged += f" in {item['logged_time_s']:g} s"
            note = f" ({item['reason']})" if item.get("reason") else ""
            answer = " ".join(str(item["answer"]).split())
            shown = f'"{said}"' if not item.get("continued") else f'"{answer}"'
            lines.append(f"- {where}: {shown} -> `{item['pddl']}`: {cost}, logged {logged}{note}")
    return "\n".join(lines) + "\n"


def compact_markdown(tables: ReplayTables) -> str:
    """Table I in one line per domain and row: ``length (tasks)`` per N, ``± std`` where
    runs differ; then each row's length / SA averaged over the domains."""
    table = tables.table
    if table.empty:
        return ""
    ns = sorted(int(n) for n in table["agents"].unique())
    head = "| domain | row | " + " | ".join(f"N = {n}" for n in ns) + " |"
    lines = [head, "|---|---|" + "---:|" * len(ns)]
    for domain in sorted(table["domain"].unique()):
        for source in SOURCES:
            cells = []
            for n in ns:
                found = table[
                    (table["domain"] == domain)
                    & (table["agents"] == n)
                    & (table["source"] == source)
                ]
                if found.empty or not found.iloc[0]["runs"]:
                    cells.append("-")
                    continue
                row = found.iloc[0]
                spread = "" if math.isnan(row["std"]) else f" ± {_number(row['std'])}"
                cells.append(f"{_number(row['exec_length'])}{spread} ({row['tasks']})")
            lines.append(f"| {domain} | {LABELS[source]} | " + " | ".join(cells) + " |")
    for source in SOURCES:
        cells = []
        for n in ns:
            found = tables.macro[(tables.macro["agents"] == n) & (tables.macro["source"] == source)]
            if found.empty:
                cells.append("-")
            else:
                row = found.iloc[0]
                cells.append(f"{_number(row['length_over_sa'], 2)} ({row['domains']} dom.)")
        lines.append(f"| length / own SA | {LABELS[source]} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
