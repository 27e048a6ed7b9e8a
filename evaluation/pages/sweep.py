"""The results page of the rows ``bench/bench_sweep.py`` writes (``make results``:
:mod:`tools.results`), and the targets the bench prints its runs against.
"""

from __future__ import annotations

from typing import Any

from tools import record as bench_record


def targets(rows: list[dict[str, Any]]) -> list[str]:
    """Issue 38's targets against this run's rows, each ``met`` or ``MISSED`` (or ``not
    run``), with the load it was measured at: on a shared machine a miss may be the load's."""

    def small(variant: str, jobs: int, launcher: str = "all") -> dict[str, Any] | None:
        return next(
            (r for r in rows if r.get("grid") == "small" and r["variant"] == variant
             and r["jobs"] == jobs and r["launcher"] == launcher),
            None,
        )  # fmt: skip

    def verdict(ok: bool) -> str:
        return "met   " if ok else "MISSED"

    def at(row: dict[str, Any]) -> str:
        return f"(load {row['load_before'][0]:.1f}/{row['load_after'][0]:.1f})"

    lines = []
    for variant, limit in (("on", 0.3), ("off", 0.1)):
        row = small(variant, 100)
        what = f"100 jobs, Prefect and MLflow {variant}: median overhead <= {limit} s"
        if row is None:
            lines.append(f"not run {what}")
            continue
        value = row["overhead_median_s"]
        lines.append(
            f"{verdict(value <= limit)} {what}: {value:.2f} s (end to end per job "
            f"{row['end_to_end_per_job_s']:.2f} s) {at(row)}"
        )
    for variant in ("on", "off"):
        a, b = small(variant, 20), small(variant, 400)
        what = f"no growth 20 -> 400 jobs ({variant})"
        if a is None or b is None:
            lines.append(f"not run {what}")
            continue
        ratio = b["overhead_median_s"] / max(a["overhead_median_s"], 1e-9)
        flat = ratio <= 1.25 or b["overhead_median_s"] - a["overhead_median_s"] <= 0.03
        lines.append(
            f"{verdict(flat)} {what}: median {a['overhead_median_s']:.2f} -> "
            f"{b['overhead_median_s']:.2f} s, trend over the 400 {b['trend_s_per_100_jobs']:+.3f} s"
            f" per 100 jobs {at(a)} {at(b)}"
        )
    servers = [r for r in rows if r.get("kind") == "prefect_server"]
    if servers:
        worst = max(r["fresh_s"] for r in servers)
        lines.append(
            f"{verdict(worst <= 10)} a fresh Prefect server ready <= 10 s: {worst:.1f} s (the "
            f"slowest of {len(servers)}; load {servers[0]['load_before'][0]:.1f})"
        )
    else:
        lines.append("not run a fresh Prefect server ready <= 10 s")
    for grid_name, title in (("planner", "planner-dominated jobs"), ("small", "small jobs")):
        one = next((r for r in rows if r.get("grid") == grid_name and r["launcher"] == "w1"), None)
        two = next((r for r in rows if r.get("grid") == grid_name and r["launcher"] == "w2"), None)
        if one is None or two is None:
            lines.append(f"not run 1 -> 2 workers on {title}")
            continue
        speedup = one["wall_s"] / two["wall_s"]
        near = speedup >= 1.7 if grid_name == "planner" else speedup > 1.0
        goal = "near 2x" if grid_name == "planner" else "faster"
        lines.append(
            f"{verdict(near)} 1 -> 2 workers on {title} ({goal}): x{speedup:.2f} "
            f"{at(one)} {at(two)}"
        )
    return lines


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of a ``--json`` record (tools.results): the sweeps' figures, the
    Prefect server's start, the workers' scaling, the targets."""
    (data,) = records
    rows = data["rows"]
    sweeps = [r for r in rows if "jobs" in r and r.get("grid") == "small"]
    lines = [
        "## Per job beyond planning",
        "",
        "Each sweep through the `twostep` command in a fresh output root (small SA and "
        "plan-deal TwoStep jobs on blocksworld and grippers, so that orchestration "
        "dominates). Overhead: the time a job held its worker minus its planner time "
        "(median and p90 over the jobs but each worker's first); end to end: (wall - "
        "planner / workers) / jobs; trend: the overhead's change over the sweep. The load "
        "average (1 min) before and after each sweep says what the figures are worth on "
        "this shared machine (2 cores).",
        "",
    ]
    lines += bench_record.table(
        ["jobs", "Prefect", "MLflow", "launcher", "workers", "wall s", "planner s",
         "overhead median s", "p90 s", "end to end s", "trend s/100 jobs", "jobs/min", "load"],
        [[r["jobs"], "on" if r["prefect"] else "off", "on" if r["mlflow"] else "off",
          r["launcher"], r["workers"], f"{r['wall_s']:.1f}", f"{r['planner_total_s']:.1f}",
          f"**{r['overhead_median_s']:.2f}**", f"{r['overhead_p90_s']:.2f}",
          f"{r['end_to_end_per_job_s']:.2f}", f"{r['trend_s_per_100_jobs']:+.3f}",
          f"{r['jobs_per_minute']:.0f}",
          f"{r['load_before'][0]:.1f} / {r['load_after'][0]:.1f}"] for r in sweeps],
    )  # fmt: skip
    if sweeps:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(8, 4))
        ax = fig.subplots()
        for r in sweeps:
            series = [p for p in r.get("series", []) if not p.get("first")]
            label = (f"{r['jobs']} jobs, Prefect/MLflow {'on' if r['prefect'] else 'off'}, "
                     f"{r['launcher']}")  # fmt: skip
            ax.plot([p["num"] for p in series], [p["overhead_s"] for p in series], ".",
                    markersize=3, label=label)  # fmt: skip
        ax.set_xlabel("job number in the sweep")
        ax.set_ylabel("overhead per job (s): held its worker - planner")
        ax.set_yscale("log")
        ax.legend(fontsize=7)
        fig.tight_layout()
        lines += ["", figure(fig, "overhead", "each job's overhead over the sweep, by sweep")]
    servers = [r for r in rows if r.get("kind") == "prefect_server"]
    if servers:
        lines += ["", "## A sweep's Prefect server: start to a healthy API", ""]
        lines += bench_record.table(
            ["fresh database s", "warm s", "load"],
            [[f"{r['fresh_s']:.1f}", f"{r['warm_s']:.1f}", f"{r['load_before'][0]:.1f}"]
             for r in servers],
        )  # fmt: skip
    scaling = [r for r in rows if r.get("launcher") in ("w1", "w2", "dask2")]
    if scaling:
        lines += ["", "## Workers", "", "Prefect and MLflow on; `w1`, `w2`: "
                  "`hydra.launcher.n_jobs=1`, `2`; `dask2`: a local Dask cluster of 2 worker "
                  "processes.", ""]  # fmt: skip
        lines += bench_record.table(
            ["jobs", "launcher", "workers", "wall s", "planner s", "jobs/min", "load"],
            [[f"{r['jobs']} ({r['grid']})", r["launcher"], r["workers"], f"{r['wall_s']:.1f}",
              f"{r['planner_total_s']:.1f}", f"{r['jobs_per_minute']:.1f}",
              f"{r['load_before'][0]:.1f} / {r['load_after'][0]:.1f}"] for r in scaling],
        )  # fmt: skip
    lines += ["", "## Targets (issue 38)", ""]
    lines += [f"- {line}" for line in targets(rows)]
    return lines


def page_grid(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of the paper-grid rows (``--paper-grid``): what the paper's grid
    costs here, and what the same work costs on more cores."""
    rows = [r for data in records for r in data["rows"] if r.get("grid") == "paper"]
    lines = [
        "## The paper's grid, one domain at a time",
        "",
        "`twostep -m experiment=paper` on one domain: 20 tasks x N = 1..4 x SA, MA and "
        "TwoStep x 3 seeds = 720 jobs, offline (`planner=lama-first decomposer=plan-deal` "
        "in place of anytime LAMA with 1000 s and GPT-4o subgoals), Prefect and MLflow on, "
        "the default launcher (every core). The figures are the sweep's own timing line "
        "(its summary): Fast Downward's wall time summed over the jobs' planner calls (the "
        "planner cache answers SA's repeats over N and the seeds), and the workers' time "
        "beyond it.",
        "",
    ]
    lines += bench_record.table(
        ["domain", "jobs", "workers", "wall min", "Fast Downward min", "beyond it s/job",
         "share of the workers' time", "jobs/min", "load"],
        [[next((o.split("=", 1)[1] for o in r["command"].split() if o.startswith("domain=")), "?"),
          r["timing"]["jobs"], r["timing"]["workers"], f"{r['timing']['wall_s'] / 60:.1f}",
          f"{r['timing']['planner_s'] / 60:.1f}", f"{r['timing']['beyond_per_job_s']:.2f}",
          f"{100 * r['timing']['overhead_share']:.0f} %", f"{r['jobs_per_minute']:.0f}",
          f"{r['load_before'][0]:.1f} / {r['load_after'][0]:.1f}"] for r in rows],
    )  # fmt: skip
    if rows:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(7, 1.2 + 0.5 * len(rows)))
        ax = fig.subplots()
        names = [f"{r['timing']['jobs']} jobs, load {r['load_before'][0]:.0f}" for r in rows]
        planner = [r["timing"]["planner_s"] / 60 for r in rows]
        beyond = [(r["timing"]["wall_s"] * r["timing"]["workers"] - r["timing"]["planner_s"]
                   - r["timing"]["llm_s"]) / 60 for r in rows]  # fmt: skip
        ax.barh(names, planner, label="Fast Downward")
        ax.barh(names, beyond, left=planner, label="beyond it (orchestration, waits)")
        ax.set_xlabel("the workers' time (min)")
        ax.legend(fontsize=7, loc="lower right")
        fig.tight_layout()
        lines += ["", figure(fig, "grid", "the workers' time in the paper's grid: Fast "
                                          "Downward and the rest")]  # fmt: skip
        total = sum(r["timing"]["wall_s"] * r["timing"]["workers"] for r in rows)
        jobs = sum(r["timing"]["jobs"] for r in rows)
        lines += [
            "",
            f"The same work on more cores (arithmetic on the measured worker time, "
            f"{total / 60:.0f} min for {jobs} jobs; planner calls and jobs are independent, "
            "so it divides by the workers until the longest job or the Prefect server "
            "bounds it):",
            "",
        ]
        lines += bench_record.table(
            ["workers", "wall min, about"],
            [[k, f"{total / k / 60:.1f}"] for k in (2, 8, 32)],
        )  # fmt: skip
        lines += ["", "Commands:", ""] + [f"    {r['command']}" for r in rows]
    return lines
