"""The methods bench's tables, figure and results pages, from its rows: per data root,
domain and N each method's mean execution length, exec length / SA length and planning
time (:func:`summarise`), the macro against the targets (:func:`report`), plan-deal's
dealing time (:func:`deal_report`), the figure (:func:`plot_methods`), the results pages
(``page_*``, ``make results``) and the README's headline table (:func:`headline`).
"""

from __future__ import annotations

import statistics
from collections import defaultdict
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from evaluation.methods import (
    DECOMPOSERS,
    LEGACY,
    METHODS,
    REPO,
    TARGETS,
    Row,
    offline_default,
    row_data,
    row_key,
    stored_sa_plan,
)
from twostep.dealing import PHASES as DEALER_PHASES
from twostep.dealing.cleanup import clean_plan
from twostep.generators import DOMAINS as BENCHMARK_DOMAINS
from twostep.pddl import parse_problem
from twostep.plans.simulate import PlanError
from twostep.tasks.benchmark import (
    BenchmarkError,
    domain_file,
    load_task,
    task_path,
)

# ---------------------------------------------------------------------------- the tables


def mean(values: Iterable[float]) -> float:
    values = list(values)
    return statistics.fmean(values) if values else float("nan")


def exec_ratio(row: Mapping[str, Any]) -> float | None:
    """Execution length / SA length of a valid row (None when either is missing)."""
    ok = row["valid"] and row["sa_length"] and row["exec_length"] is not None
    return row["exec_length"] / row["sa_length"] if ok else None


def single_agent_rows(rows: Iterable[Row], methods: Sequence[str]) -> list[Row]:
    """The N = 1 row of every method: with one agent each method is the SA plan."""
    return [
        {**r, "method": m, "n1_is_sa": True} for r in rows if r["method"] == "sa" for m in methods
    ]


def lower_bound(row: Mapping[str, Any]) -> int | None:
    """The bound every schedule of the row's plans has: at most N actions per time step,
    so ⌈actions of all its agents / N⌉ (None for rows written before the count)."""
    total = row.get("total_actions")
    return None if total is None else -(-int(total) // int(row["agents"]))


def cleaned_ratio(row: Mapping[str, Any]) -> float | None:
    """Execution length / the cleaned SA plan's length (plan-deal's step 0, one agent)."""
    ok = row["valid"] and row.get("cleaned") and row["exec_length"] is not None
    return row["exec_length"] / row["cleaned"] if ok else None


def with_cleaned(rows: Iterable[Row]) -> list[Row]:
    """The rows, each with the cleaned SA plan's length of its task (``cleaned``): where a
    plan-deal row of the task recorded it (the same SA plan, so the same for every N), else
    the task's stored SA plan cleaned now (a run whose winner is not plan-deal's own deal,
    such as the portfolio's, records none)."""
    rows = list(rows)
    known = {(r.get("data"), r["domain"], r["task"]): r["cleaned_sa_length"]
             for r in rows if r.get("cleaned_sa_length") is not None}  # fmt: skip
    for r in rows:
        key = (r.get("data"), r["domain"], r["task"])
        if r["method"] == "sa" and key not in known and r.get("valid"):
            known[key] = cleaned_length(r)
    return [{**r, "cleaned": known.get((r.get("data"), r["domain"], r["task"]))} for r in rows]


def cleaned_length(sa_row: Row) -> int | None:
    """The length of a stored SA row's plan after plan-deal's action elimination (step 0 of
    :mod:`twostep.dealing`); None without the plan or the task's files, or for a plan that
    does not apply to its task."""
    plan = stored_sa_plan(sa_row)
    if plan is None or plan.plan is None:
        return None
    try:
        task = load_task(sa_row["domain"], sa_row["task"], REPO / row_data(sa_row))
        return len(clean_plan(task.problem, plan.plan))
    except (BenchmarkError, PlanError):
        return None


@dataclass(frozen=True)
class Cell:
    """One method at one (domain, N): means over that domain's tasks."""

    length: float  # mean execution length of the valid rows
    ratio: float  # mean of the per-task exec/SA of the valid rows
    bound: float  # mean of the per-task ⌈actions of all agents / N⌉ (:func:`lower_bound`)
    ratio_cleaned: float  # mean of the per-task exec / cleaned SA length
    time_s: float  # mean planning time
    tasks: int
    failed: int  # rows without a valid schedule (planner timeout, no plan, invalid schedule)
    longer_than_sa: int  # valid rows whose schedule is longer than the SA plan
    inexact: int  # valid rows scored at the scorer's node budget (length: an upper bound)


def cell(rows: Sequence[Row]) -> Cell:
    valid = [r for r in rows if r["valid"] and r["exec_length"] is not None]
    times = [r["planning_time_s"] for r in rows if r["planning_time_s"] is not None]
    return Cell(
        length=mean(r["exec_length"] for r in valid),
        ratio=mean(x for x in map(exec_ratio, valid) if x is not None),
        bound=mean(x for x in map(lower_bound, valid) if x is not None),
        ratio_cleaned=mean(x for x in map(cleaned_ratio, valid) if x is not None),
        time_s=mean(times),
        tasks=len(rows),
        failed=len(rows) - len(valid),
        longer_than_sa=sum(
            bool(r["sa_length"]) and r["exec_length"] > r["sa_length"] for r in valid
        ),
        inexact=sum(r.get("exact") is False for r in valid),
    )


def summarise(
    rows: Iterable[Row], methods: Sequence[str], ns: Sequence[int]
) -> dict[tuple[str, int, str], Cell]:
    """``(domain, N, method)`` -> :class:`Cell`, over ``sa`` and ``methods`` (N = 1: the SA
    rows), and ``(domain, 1, "sa-cleaned")``: the SA plan after plan-deal's action
    elimination, one agent (where plan-deal rows recorded it). Only tasks whose SA row is
    present count, so every cell covers the same tasks."""
    rows = with_cleaned(rows)
    sa = [r for r in rows if r["method"] == "sa"]
    have_sa = {(r["domain"], r["task"]) for r in sa}
    by: dict[tuple[str, int, str], list[Row]] = defaultdict(list)
    for r in [*single_agent_rows(sa, methods), *rows]:
        if (r["domain"], r["task"]) in have_sa and (r["method"] in methods or r["method"] == "sa"):
            by[(r["domain"], int(r["agents"]), r["method"])].append(r)
    for r in sa:
        if r["valid"] and r["cleaned"] is not None:  # 0: the goal holds at the start
            by[(r["domain"], 1, "sa-cleaned")].append(
                {**r, "exec_length": r["cleaned"], "total_actions": r["cleaned"]}
            )
    domains = sorted({r["domain"] for r in sa})
    table = {}
    for domain in domains:
        for n in ns:
            for m in ["sa", *methods]:
                group = by[(domain, 1, "sa")] if m == "sa" else by[(domain, n, m)]
                if group:
                    table[(domain, n, m)] = cell(group)
        if by[(domain, 1, "sa-cleaned")]:
            table[(domain, 1, "sa-cleaned")] = cell(by[(domain, 1, "sa-cleaned")])
    return table


def macro_ratio(
    table: Mapping[tuple[str, int, str], Cell], method: str, n: int, cleaned: bool = False
) -> float:
    """Mean over the domains of the per-domain mean exec/SA (``cleaned``: exec / the
    cleaned SA plan); nan if a domain lacks it."""
    ratios = [c.ratio_cleaned if cleaned else c.ratio
              for (d, k, m), c in table.items() if k == n and m == method]  # fmt: skip
    return statistics.fmean(ratios) if ratios else float("nan")


def no_longer_than_ma(
    table: Mapping[tuple[str, int, str], Cell], method: str, n: int
) -> tuple[list[str], int]:
    """The domains where ``method``'s mean exec/SA is at most MA's at N (or where MA solved
    no task and ``method`` did), and how many domains have both."""
    domains = sorted({d for (d, k, m) in table if k == n and m == method})
    both = [d for d in domains if (d, n, "ma") in table]

    def wins(domain: str) -> bool:
        mine, ma = table[(domain, n, method)].ratio, table[(domain, n, "ma")].ratio
        return mine <= ma + 1e-9 or (ma != ma and mine == mine)

    return [d for d in both if wins(d)], len(both)


def _f(x: float, digits: int) -> str:
    return "" if x != x else f"{x:.{digits}f}"


def macro_time(table: Mapping[tuple[str, int, str], Cell], method: str, n: int) -> float:
    """Mean over the domains of the per-domain mean planning time."""
    times = [c.time_s for (d, k, m), c in table.items() if k == n and m == method]
    return statistics.fmean(times) if times else float("nan")


def overview(table: Mapping[tuple[str, int, str], Cell], methods: Sequence[str], ns: Sequence[int],
             star: Mapping[str, str]) -> list[str]:  # fmt: skip
    """Method x N rows, domains across: mean exec/SA, its macro mean, the macro exec / the
    cleaned SA plan, the macro planning time and its ratio to MA's (the compact form of the
    per-domain table, as issue 11 shows it). N = 1 also shows ``sa (cleaned)``."""
    domains = sorted({d for d, _, _ in table})
    head = ["method", "N", *domains, "macro", "macro / cleaned SA", "planning time s", "time / MA"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for n in ns:
        shown = ["sa", "sa-cleaned"] if n == 1 else methods
        for m in [m for m in shown if any((d, n, m) in table for d in domains)]:
            ratios = [_f(table[(d, n, m)].ratio, 3) if (d, n, m) in table else "" for d in domains]
            ma_time = macro_time(table, "ma", n) if n > 1 else float("nan")
            ratio = macro_time(table, m, n) / ma_time if m != "ma" else float("nan")
            name = "sa (cleaned)" if m == "sa-cleaned" else star.get(m, m)
            cells = [name, str(n), *ratios, _f(macro_ratio(table, m, n), 3)]
            cells.append(_f(macro_ratio(table, m, n, cleaned=True), 3))
            lines.append(
                "| " + " | ".join([*cells, _f(macro_time(table, m, n), 2), _f(ratio, 3)]) + " |"
            )
    return lines


def _length(cell: Cell | None, tasks: int) -> str:
    """Mean length, then the mean lower bound ⌈actions / N⌉ in brackets."""
    if cell is None:
        return ""
    bound = "" if cell.bound != cell.bound else f" [{cell.bound:.1f}]"
    return _f(cell.length, 1) + bound + ("" if cell.tasks == tasks else f" ({cell.tasks} tasks)")


def _time_ratio(cell: Cell | None, ma: Cell | None) -> str:
    return _f(cell.time_s / ma.time_s, 3) if cell and ma and ma.time_s else ""


def report(
    rows: Iterable[Row],
    methods: Sequence[str],
    ns: Sequence[int],
    targets: Mapping[int, float] | None = None,
    default: str | None = None,
    plot: Path | None = None,
    floors: bool = True,
) -> str:
    """The per-domain side-by-side table, then the macro exec/SA per N (``targets``: the
    goals of the offline ``default`` decomposer) and the domains no longer than MA
    (``plot``: :func:`plot_methods` of the same table to that PNG; ``floors``: tyreworld's
    one-jack floor from the task files, :func:`one_jack_floor`)."""
    table = summarise(rows, methods, ns)
    if plot is not None:
        plot_methods(table, methods, ns, targets, default, plot)
    domains = sorted({d for d, _, _ in table})
    ts = [m for m in methods if m != "ma"]
    has_ma = "ma" in methods
    star = {m: f"{m}*" if m == default else m for m in methods}
    lines = ["exec length / SA length, mean over each domain's tasks (N = 1: the SA plan):", ""]
    lines += [*overview(table, methods, ns, star), ""]
    head = ["domain", "N", "tasks", "SA len", "SA (cleaned) len"]
    head += [f"{star[m]} len" for m in methods]
    head += [f"{star[m]}/SA" for m in methods]
    head += ["SA time s", *(f"{star[m]} time s" for m in methods)]
    head += [f"{star[m]}/MA time" for m in ts] if has_ma else []
    head += ["longer than SA", "inexact", "failed"]
    lines += ["Per domain and N, side by side (means over the domain's tasks):", ""]
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for domain in domains:
        sa = table[(domain, 1, "sa")]
        for n in ns:
            got = {m: table.get((domain, n, m)) for m in methods}
            cleaned = table.get((domain, 1, "sa-cleaned"))
            cells = [domain, str(n), str(sa.tasks), _f(sa.length, 1)]
            cells.append(_f(cleaned.length, 1) if cleaned else "")
            # a method run on fewer tasks than SA says on how many
            cells += [_length(c, sa.tasks) for c in got.values()]
            cells += [_f(c.ratio, 3) if c else "" for c in got.values()]
            cells += [_f(sa.time_s, 2)] + [_f(c.time_s, 2) if c else "" for c in got.values()]
            if has_ma:
                cells += [_time_ratio(got[m], got["ma"]) for m in ts]
            longer = sum(c.longer_than_sa for m, c in got.items() if c and m != "ma")
            # at N = 1 every method is the one SA row: count its failures once
            present = [c for c in got.values() if c]
            inexact = sum(c.inexact for c in present)
            failed = sa.failed if n == 1 else sum(c.failed for c in present)
            cells += [str(longer), str(inexact), str(failed)]
            lines.append("| " + " | ".join(cells) + " |")
    lines += [
        "",
        "N = 1: every method is the SA plan (shown as such, not run). SA (cleaned): the SA "
        "plan after plan-deal's action elimination, one agent. [x]: the mean lower bound "
        "⌈actions of all agents' plans / N⌉ (at most N actions per time step). Lengths and "
        "ratios are over the valid rows; failed: no valid schedule (planner timeout, no "
        "plan, invalid schedule), its planning time still counts; inexact: scored at the "
        "scorer's node budget (the length is an upper bound). A blank macro: some domain "
        "has no solved task.",
    ]
    if default in methods:
        lines += [f"* the offline default decomposer (conf/config.yaml): {default}"]
    lines += ["", "Macro exec/SA (mean over domains of the per-task mean; / cleaned: exec / "
              "the cleaned SA plan):", ""]  # fmt: skip
    head = ["N", "target", *(star[m] for m in methods), *(f"{star[m]} / cleaned" for m in ts)]
    head += [f"{star[m]}: domains <= MA" for m in ts] if has_ma else []
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for n in ns:
        target = (targets or {}).get(n)
        cells = [str(n), "" if target is None else f"{target:.2f}"]
        cells += [_f(macro_ratio(table, m, n), 3) for m in methods]
        cells += [_f(macro_ratio(table, m, n, cleaned=True), 3) for m in ts]
        if has_ma:
            for m in ts:
                wins, total = no_longer_than_ma(table, m, n)
                cells.append(f"{len(wins)}/{total}")
        lines.append("| " + " | ".join(cells) + " |")
    if has_ma and ts:
        lines += ["", "Domains where each method is no longer than MA (mean exec/SA):", ""]
        for n in ns:
            if n == 1:
                continue
            parts = [f"{m}: {', '.join(no_longer_than_ma(table, m, n)[0]) or '-'}" for m in ts]
            lines.append(f"- N = {n}: " + "; ".join(parts))
    if default in methods and default is not None:
        lines += ["", *deal_report(rows, ns, default, floors)]
    return "\n".join(lines)


DEAL_LIMIT_S = 5.0  # issue 18: dealing time on any task
PHASES = (*DEALER_PHASES, "rebinding", "scoring")  # plan-deal's own, beside the dealer's


def tyreworld_floor(data: str, task: int) -> int | None:
    """The fewest steps any schedule of a tyreworld task takes, for any N: 6 per hub + 6.

    One jack: each hub's jack-up, undo, remove-wheel, put-on-wheel, do-up and jack-down
    follow one another, and the next hub's jack-up waits for (have jack), which only
    jack-down gives back; three steps come before the first jack-up (open the boot, fetch the
    wrench, loosen the nut) and three after the last jack-down (tighten, put the wrench
    away, close the boot). tests/test_plan_deal.py derives it and checks that the deal
    reaches it. ``None`` when the task's files are not there."""
    try:  # the problem's objects are all it needs: read, not grounded (ms, not a second)
        root = REPO / data
        domain_text = domain_file("tyreworld", root).read_text()
        problem = parse_problem(domain_text, task_path("tyreworld", task, root).read_text())
    except (BenchmarkError, OSError):
        return None
    hubs = sum(1 for kind in problem.all_objects.values() if kind == "hub")
    return 6 * hubs + 6


def one_jack_floor(rows: Sequence[Row], dealt: Sequence[Row]) -> list[str]:
    """How far the tyreworld deals are from :func:`tyreworld_floor` (no lines without them)."""
    sa = {(row_data(r), r["task"]): r for r in rows
          if r["method"] == "sa" and r["domain"] == "tyreworld" and r["valid"]}  # fmt: skip
    floors = {key: floor for key in sa if (floor := tyreworld_floor(*key)) is not None}
    known = [r for r in dealt if r["domain"] == "tyreworld" and r["valid"]
             and (row_data(r), r["task"]) in floors]  # fmt: skip
    if not known:
        return []
    at = sum(r["exec_length"] == floors[(row_data(r), r["task"])] for r in known)
    ratio = mean(f / sa[k]["exec_length"] for k, f in floors.items())
    return [f"- tyreworld's one-jack floor (6 per hub + 6 steps, for any N): reached in {at} "
            f"of {len(known)} runs; floor / SA, mean over tasks: {ratio:.3f} (no N lowers it)"]  # fmt: skip


def deal_report(
    rows: Iterable[Row], ns: Sequence[int], method: str, floors: bool = True
) -> list[str]:
    """For plan-deal (rows that record ``deal_seconds``): the runs that fell back to the SA
    plan and why, the runs that dealt to fewer agents, the monotonicity check (never longer
    with N agents than with N-1) and the dealing time per domain against SA's planner time."""
    rows = list(rows)
    dealt = [r for r in rows if r["method"] == method and r.get("deal_seconds") is not None]
    if not dealt:
        return []
    sa = {(r["domain"], r["task"]): r for r in rows if r["method"] == "sa"}
    lines = [f"{method} in detail (issue 18):", ""]
    fell = sorted((r for r in dealt if r.get("fallback")),
                  key=lambda r: (r["domain"], r["task"], r["agents"]))  # fmt: skip
    reasons: dict[str, int] = defaultdict(int)
    for r in fell:
        reasons[str(r.get("fallback_reason") or r["fallback"])] += 1
    lines.append(f"- runs whose outcome is one agent's plan (fallback): {len(fell)} of "
                 f"{len(dealt)}" + "".join(f"; {k}: {v}" for k, v in sorted(reasons.items())))  # fmt: skip
    lines += [f"  - {r['domain']} p{r['task']:02d} N={r['agents']}: {str(r['fallback'])[:100]}"
              for r in fell]  # fmt: skip
    fewer = [r for r in dealt if r.get("agents_used") and 1 < r["agents_used"] < r["agents"]]
    lines.append(f"- runs dealt to fewer agents than N (an agent idle): {len(fewer)}")
    lengths = {(r["domain"], r["task"], r["agents"]): r["exec_length"]
               for r in dealt if r["valid"]}  # fmt: skip
    for (domain, task), r in sa.items():
        if r["valid"]:
            lengths[(domain, task, 1)] = r["exec_length"]
    worse = [(d, t, n, lengths[(d, t, n)], lengths[(d, t, n - 1)])
             for (d, t, n) in sorted(lengths) if (d, t, n - 1) in lengths
             and lengths[(d, t, n)] > lengths[(d, t, n - 1)]]  # fmt: skip
    pairs = sum((d, t, n - 1) in lengths for (d, t, n) in lengths)
    lines.append(f"- monotonicity (N = 1: the SA plan): {len(worse)} violations in {pairs} "
                 "pairs (N, N-1)" + "".join(f"; {d} p{t:02d} N={n}: {a} > {b}"
                                            for d, t, n, a, b in worse))  # fmt: skip
    lines += one_jack_floor(rows, dealt) if floors else []
    lines += ["", "Dealing time (everything after the SA plan: phases of the dealing, and "
              "scoring), CPU seconds; SA: its planner time (Fast Downward's, CPU time too):",
              ""]  # fmt: skip
    head = ["domain", "N", "SA median", "dealing median", "<= SA", "dealing max",
            f"<= {DEAL_LIMIT_S:g}", *PHASES]  # fmt: skip
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for domain in sorted({r["domain"] for r in dealt}):
        sa_time = statistics.median(
            r["planning_time_s"] for (d, _), r in sa.items() if d == domain and r["valid"]
        )
        for n in ns:
            group = [r for r in dealt if r["domain"] == domain and r["agents"] == n]
            if not group:
                continue
            spent = [sum(r["deal_seconds"].values()) for r in group]
            median, most = statistics.median(spent), max(spent)
            phases = [statistics.median(r["deal_seconds"].get(p, 0.0) for r in group)
                      for p in PHASES]  # fmt: skip
            cells = [domain, str(n), f"{sa_time:.3f}", f"{median:.3f}",
                     "yes" if median <= sa_time else "no", f"{most:.2f}",
                     "yes" if most <= DEAL_LIMIT_S else "no", *(f"{x:.3f}" for x in phases)]  # fmt: skip
            lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Phases: medians over the domain's tasks; walks are the walking searches of "
              "dealing and replay, counted apart from them."]  # fmt: skip
    return lines


def report_all(
    rows: Sequence[Row],
    methods: Sequence[str],
    ns: Sequence[int],
    default: str | None,
    plot: Path | None = None,
    outside: bool = True,
) -> str:
    """One :func:`report` per data root (the issue's targets apply to the 100 tasks only);
    ``plot``: :func:`plot_methods` of the 100 tasks' rows to that PNG; ``outside``: read
    the task files of data roots outside the repository too (tyreworld's floor), which a
    results page does not (it is made from the committed rows and the repository alone)."""
    out = []
    for label in sorted({row_data(r) for r in rows}):
        part = [r for r in rows if row_data(r) == label]
        tasks = sorted({(r["domain"], r["task"]) for r in part if r["method"] == "sa"})
        counts: dict[str, int] = defaultdict(int)
        for d, _ in tasks:
            counts[d] += 1
        out.append(f"## data root {label}: {len(tasks)} tasks ("
                   + ", ".join(f"{d} {k}" for d, k in sorted(counts.items())) + ")\n")  # fmt: skip
        targets = TARGETS if label == LEGACY["data"] else None
        present = [m for m in methods if any(r["method"] == m for r in part)]
        drawn = plot if label == LEGACY["data"] else None
        floors = outside or not Path(label).is_absolute()
        out.append(report(part, present, ns, targets, default, drawn, floors) + "\n")
        if drawn is not None:
            out.append(f"(plot: {drawn})\n")
    return "\n".join(out)


def plot_methods(
    table: Mapping[tuple[str, int, str], Cell],
    methods: Sequence[str],
    ns: Sequence[int],
    targets: Mapping[int, float] | None,
    default: str | None,
    path: Path | None,
) -> Any:
    """Two panels to ``path`` (PNG; None: not saved; the figure is returned): the macro exec/SA of each method against N, with the
    targets; and the same macro against the macro planning time (one point per method and
    N, SA's planning time as a line), where the trade-off between the methods shows."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    shown = [m for m in methods if any((d, n, m) in table for (d, n, _) in table if n > 1)]
    colours = {m: f"C{k}" for k, m in enumerate(shown)}
    figure = Figure(figsize=(10.0, 4.0), layout="constrained")
    FigureCanvasAgg(figure)
    by_n, by_time = figure.subplots(1, 2)
    sa_time = macro_time(table, "sa", 1)
    for m in shown:
        name = f"{m}*" if m == default else m
        points = [(n, macro_ratio(table, m, n), macro_time(table, m, n)) for n in ns if n > 1]
        points = [(1, 1.0, sa_time), *[p for p in points if p[1] == p[1]]]
        style = {"color": colours[m], "marker": "o", "linewidth": 2.5 if m == default else 1.2}
        by_n.plot([p[0] for p in points], [p[1] for p in points], label=name, **style)
        by_time.plot([p[2] for p in points[1:]], [p[1] for p in points[1:]], **style)
        for n, ratio, seconds in points[1:]:
            by_time.annotate(f"N={n}", (seconds, ratio), textcoords="offset points",
                             xytext=(4, 3), fontsize=7, color=colours[m])  # fmt: skip
    if targets:
        xs = sorted(targets)
        by_n.scatter(xs, [targets[n] for n in xs], marker="_", s=400, color="black", zorder=5,
                     label="target (offline default)")  # fmt: skip
    by_n.set_xticks(list(ns))
    by_n.set_xlabel("agents N")
    by_n.set_ylabel("macro exec length / SA length")
    by_n.set_title("Quality against N (N = 1: the SA plan)")
    by_n.grid(alpha=0.3)
    by_n.legend(fontsize=8)
    by_time.axvline(sa_time, color="grey", linestyle="--", linewidth=1)
    by_time.text(sa_time, 0.5, " SA planning time", transform=by_time.get_xaxis_transform(),
                 rotation=90, fontsize=7, color="grey", va="center")  # fmt: skip
    by_time.set_xscale("log")
    by_time.set_xlabel("macro planning time s (SA plan included; log scale)")
    by_time.set_ylabel("macro exec length / SA length")
    by_time.set_title("Quality against planning time (N = 2, 3, 4)")
    by_time.grid(alpha=0.3, which="both")
    if path is not None:
        figure.savefig(path, dpi=120)
    return figure


# ---------------------------------------------------------------------------- pages

Figure = Callable[[Any, str, str], str]  # tools.results: (figure, name, alt) -> Markdown


def _rows_of_records(records: Sequence[Mapping[str, Any]]) -> list[Row]:
    """One row per key: a later record's row replaces an earlier one's (as ``--report``)."""
    return list({row_key(r): r for rec in records for r in rec["rows"]}.values())


def _ns(rows: Iterable[Row]) -> list[int]:
    return sorted({int(r["agents"]) for r in rows} | {1})


def _page(rows: list[Row], figure: Figure, name: str, level: int = 2) -> list[str]:
    """The report of ``rows`` (:func:`report_all`, one section per data root, headings at
    ``level``), with the figure of the 100 tasks' macro against N and time
    (:func:`plot_methods`)."""
    default = offline_default()
    ns = _ns(rows)
    heading = "#" * level
    report_lines = [
        f"{heading} Data root {line.removeprefix('## data root ')}"
        if line.startswith("## data root ") else line
        for line in report_all(rows, METHODS, ns, default, outside=False).splitlines()
    ]  # fmt: skip
    lines: list[str] = []
    # the 100 tasks with the targets, else the rows' one data root
    roots = sorted({row_data(r) for r in rows})
    drawn_root = (
        LEGACY["data"] if LEGACY["data"] in roots else (roots[0] if len(roots) == 1 else None)
    )
    if drawn_root is not None:
        part = [r for r in rows if row_data(r) == drawn_root]
        present = [m for m in METHODS if any(r["method"] == m for r in part)]
        table = summarise(part, present, ns)
        targets = TARGETS if drawn_root == LEGACY["data"] else None
        drawn = plot_methods(table, present, ns, targets, default, None)
        alt = "Macro exec/SA of each method against N with the targets, and against planning time"
        lines += [f"{heading} Figure", "", figure(drawn, name, alt), "",
                  f"Data root {drawn_root}. Left: the macro exec/SA (the mean over domains of the "
                  "per-task exec length / SA length) against N"
                  + (", with the targets of the offline default" if targets else "")
                  + ". Right: the same against the macro planning time (log scale; dashed: the SA "
                  "plan's own).", ""]  # fmt: skip
    return lines + report_lines


def page_plan_deal(records: Sequence[Mapping[str, Any]], figure: Figure) -> list[str]:
    """The plan-deal page: every data root of the rows (the 100 tasks, stress, large)."""
    return _page(_rows_of_records(records), figure, "macro")


def page_methods(records: Sequence[Mapping[str, Any]], figure: Figure) -> list[str]:
    """A page of several methods' rows side by side (later files' rows replace earlier
    ones', as ``--report`` takes them): the 100 tasks' where the rows have them (the
    other data roots of those files are the plan-deal page's), else every root's."""
    rows = _rows_of_records(records)
    legacy = [r for r in rows if row_data(r) == LEGACY["data"]]
    return _page(legacy or rows, figure, "macro")


def headline(records: Sequence[Mapping[str, Any]]) -> list[str]:
    """The README's headline table: each method's macro exec length / SA length on the 100
    tasks at N = 2..4 (the mean over the five domains of the per-task ratio, as the methods
    page's overview) and its macro planning time at the largest N, the offline default
    starred."""
    rows = [r for r in _rows_of_records(records) if row_data(r) == LEGACY["data"]]
    ns = [n for n in _ns(rows) if n > 1]
    present = [m for m in METHODS if any(r["method"] == m for r in rows)]
    table = summarise(rows, present, ns)
    default = offline_default()
    head = ["method", *(f"exec / SA, N = {n}" for n in ns), f"planning time s, N = {ns[-1]}"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines.append("| " + " | ".join(["sa", *("1.000" for _ in ns),
                                    _f(macro_time(table, "sa", ns[-1]), 2)]) + " |")  # fmt: skip
    for m in present:
        name = f"twostep ({m})" if m in DECOMPOSERS else m
        name += " *" if m == default else ""
        cells = [_f(macro_ratio(table, m, n), 3) for n in ns]
        lines.append("| " + " | ".join([name, *cells, _f(macro_time(table, m, ns[-1]), 2)]) + " |")
    return lines


def page_heldout(records: Sequence[Mapping[str, Any]], figure: Figure) -> list[str]:
    """The held-out page: the paper's five domains, then the others apart (with their own
    macro: the paper reports only the five)."""
    rows = _rows_of_records(records)
    ours = [r for r in rows if r["domain"] in BENCHMARK_DOMAINS]
    others = [r for r in rows if r["domain"] not in BENCHMARK_DOMAINS]
    if not others:
        return _page(ours, figure, "macro")
    domains = ", ".join(sorted({r["domain"] for r in others}))
    lines = ["## The paper's five domains", "", *_page(ours, figure, "macro", 3), ""]
    lines += [f"## Other domains ({domains})", "", *_page(others, figure, "others", 3)]
    return lines
