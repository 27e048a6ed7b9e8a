"""The results page of the rows ``bench/bench_embodied.py`` writes (``make results``:
:mod:`tools.results`).
"""

from __future__ import annotations

import statistics
from typing import Any

from tools import record as bench_record


def page(records: list[dict[str, Any]], figure: Any) -> list[str]:
    """The results page of a ``--json`` record (tools.results): a part per section run."""
    from matplotlib.figure import Figure

    (data,) = records
    rows = data["rows"]
    of = {
        name: [r for r in rows if r["section"] == name]
        for name in ("speed", "check", "render", "real")
    }
    lines: list[str] = []
    if of["speed"]:
        lines += [
            "## Speed",
            "",
            "TwoStep (goal-split) plans for N agents on the four kitchen tasks and a generated "
            f"larger kitchen (s{data.get('size')}: {data.get('size')} objects); the mean over "
            "seeds of one `twostep.embodied.execute` (planning not timed). Ground ms: grounding "
            "the task with its N bodies the first time, timed apart. Goal: a 4-agent, 300-step "
            "execution in under 0.5 s.",
            "",
            *bench_record.table(
                ["task", "N", "plans", "actions", "steps", "waits", "backoffs", "ok", "time ms",
                 "ground ms", "steps/s", "load (1 min)"],
                [[r["task"], r["agents"], r["plans"], r["actions"], f"{r['steps']:.1f}",
                  f"{r['waits']:.1f}", f"{r['backoffs']:.1f}", f"{r['ok']}/{r['repeats']}",
                  f"{r['time_ms']:.2f}", f"{r['ground_ms']:.2f}",
                  f"{r['steps'] / r['time_ms'] * 1000:.0f}", f"{r['load'][0]:.2f}"]
                 for r in of["speed"]],
            ),
            "",
        ]  # fmt: skip
        fig = Figure(figsize=(7.0, 3.4), layout="constrained")
        axes = fig.subplots()
        for k, task in enumerate(dict.fromkeys(r["task"] for r in of["speed"])):
            mine = [r for r in of["speed"] if r["task"] == task]
            axes.plot([r["steps"] for r in mine], [r["time_ms"] for r in mine], marker="o",
                      color=f"C{k}", label=task)  # fmt: skip
            for r in mine:
                axes.annotate(f"N={r['agents']}", (r["steps"], r["time_ms"]), fontsize=7,
                              textcoords="offset points", xytext=(3, 3))  # fmt: skip
        axes.set_xlabel("steps of the execution (mean)")
        axes.set_ylabel("wall ms (mean)")
        axes.set_title("Execution time against its length")
        axes.grid(alpha=0.3)
        axes.legend(fontsize=8)
        lines += [figure(fig, "speed", "Execution time against steps, per task and N"), ""]
    for r in of["check"]:
        lines += [
            "## Trace check",
            "",
            f"MA and TwoStep (goal-split) on the four kitchen tasks, N = 2 and 3, seeds 0-"
            f"{r['seeds'] - 1}: every trace replayed by `checkers.trace_check` (its own reading "
            "of the floor plan and the PDDL).",
            "",
            *bench_record.table(
                ["traces", "failed runs", "commands", "interactions", "out of reach",
                 "violations", "seconds with planning", "load (1 min)"],
                [[r["traces"], r["failed runs"], r["commands"], r["interactions"],
                  r["out of reach"], r["violations"], f"{r['seconds']:.0f}", f"{r['load'][0]:.2f}"]],
            ),
            "",
        ]  # fmt: skip
    if of["render"]:
        lines += ["## Pictures", "", "The GIF and the timeline of task 1, MA, N = 2, seed 0 "
                  "(`write_pictures`); goal: at most 2 s per run.", ""]  # fmt: skip
        lines += bench_record.table(
            ["run", "seconds", "steps", "sizes", "load (1 min)"],
            [[r["run"], f"{r['seconds']:.2f}", r["steps"],
              ", ".join(f"{k} {v} kB" for k, v in r["kb"].items()), f"{r['load'][0]:.2f}"]
             for r in of["render"]],
        )  # fmt: skip
        lines.append("")
    real_rows = [r for r in of["real"] if "skipped" not in r]
    if real_rows:
        first = real_rows[0]
        engine = any(r["engine"] is not None for r in real_rows)
        lines += [
            "## A real AlfWorld problem",
            "",
            f"`{first['problem']}` (AlfWorld's format) with the alfworld wheel's `alfred.pddl`, "
            f"on its scene's layout {first['floor_plan']}, seeds 0-{first['seeds'] - 1}. Check: "
            "the trace check passes with nothing out of reach; engine: AlfWorld's own text "
            "engine accepts the trace"
            + ("" if engine else " (not installed for this run: `make alfworld-engine`)") + ".",
            "",
            *bench_record.table(
                ["method", "N", "actions", "embodied lengths", "mean", "check", "engine"],
                [[r["method"], r["agents"], r["actions"], ", ".join(map(str, r["lengths"])),
                  f"{statistics.mean(r['lengths']):.1f}", f"{r['checked']}/{r['seeds']}",
                  "-" if r["engine"] is None else f"{r['engine']}/{r['seeds']}"] for r in real_rows],
            ),
            "",
        ]  # fmt: skip
    for r in of["real"]:
        if "skipped" in r:
            lines += ["## A real AlfWorld problem", "", f"Skipped: {r['skipped']}.", ""]
    return lines
