"""What a report holds: the metrics of Fig. 3, the columns of a cell, the :class:`Report`."""

from __future__ import annotations

from dataclasses import dataclass, field

import pandas as pd

from twostep.report.runs import RunParams

#: The two metrics of Fig. 3, with axis labels: the normalised panel and the changes.
REPORT_METRICS: tuple[str, ...] = ("exec_length", "planning_time_s")
#: Metrics averaged per cell: Fig. 3's two, and the embodied length of kitchen runs (the
#: length a kitchen domain's figures draw, as Table II does).
CELL_METRICS: tuple[str, ...] = (*REPORT_METRICS, "embodied_length")
METRIC_LABELS: dict[str, str] = {
    "exec_length": "Execution length (steps)",
    "planning_time_s": "Planning time (s)",
    "embodied_length": "Embodied length (steps)",
}
METRIC_NAMES: dict[str, str] = {
    "exec_length": "execution length",
    "planning_time_s": "planning time",
    "embodied_length": "embodied length",
}

SERIES_COLUMNS: tuple[str, ...] = ("series", "method", "decomposer", "variant")
CELL_COLUMNS: tuple[str, ...] = ("domain", *SERIES_COLUMNS, "agents")


@dataclass(frozen=True)
class Report:
    """Every table of a report. Build with :func:`twostep.report.build.build_report`; write
    with :func:`twostep.report.render.write_report`.

    ``runs``: the canonical run table plus ``series``, ``variant`` and ``identified``.
    ``per_seed``: one row per (domain, series, N, seed): task averages.
    ``per_task``: one row per (domain, series, N, task): mean/std over seeds.
    ``summary``: one row per (domain, series, N): counts, mean/std over seeds of every
    successful run.
    ``compared``: the same cells, averaged over the tasks every series of the domain solved
    (:mod:`twostep.report.compared`): what the figures, the normalised panel and the
    changes use, with the runs each cell lost.
    ``coverage``: per domain, the tasks compared, those left out and why.
    ``normalised``: per (domain, series, N, metric) the min-max scaled mean.
    ``cross_domain``: per (series, N, metric) the normalised mean across domains.
    ``changes``: TwoStep vs SA/MA per N and metric, beside the paper's figures.
    ``table1``: expert vs decomposers on the annotated tasks (paper's rows included).
    ``table2``: embodied length and planning time on the kitchen tasks (paper's rows
    included; empty without kitchen runs): :mod:`twostep.report.table2`.
    ``params``: what the run table's ``param.*`` columns stand for.
    """

    runs: pd.DataFrame
    per_seed: pd.DataFrame
    per_task: pd.DataFrame
    summary: pd.DataFrame
    compared: pd.DataFrame
    coverage: pd.DataFrame
    normalised: pd.DataFrame
    cross_domain: pd.DataFrame
    changes: pd.DataFrame
    table1: pd.DataFrame
    counts: dict[str, int]
    series: tuple[str, ...]
    variant_params: tuple[str, ...]
    notes: tuple[str, ...] = field(default=())
    table2: pd.DataFrame = field(default_factory=pd.DataFrame)  # the paper's Table II (kitchen)
    params: RunParams = field(default_factory=RunParams)

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

    def length_metric(self, domain: str) -> str:
        """The length a domain's figures draw: embodied length for kitchen runs."""
        rows = self.coverage[self.coverage["domain"] == domain]
        return str(rows["length_metric"].iloc[0]) if len(rows) else REPORT_METRICS[0]
