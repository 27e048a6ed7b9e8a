"""Pictures of an embodied execution: an animated GIF of the kitchen and a timeline.

The GIF shows the floor plan (walls, labelled furniture and locations), every agent with
what it holds, and a dashed line to where it is walking. The timeline is a Gantt-style
chart, agents by environment steps, coloured by primitive (navigate, interact, wait,
backoff); :func:`schedule_timeline` draws the same chart for a symbolic joint schedule.

matplotlib is imported lazily (only these functions need it), on an Agg canvas without
pyplot, so the executor itself stays light.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from twostep.embodied.executor import EmbodiedResult
from twostep.embodied.floorplan import Cell, FloorPlan

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PRIMITIVE_COLORS: Mapping[str, str] = {
    "move": "#4C78A8",
    "interact": "#54A24B",
    "wait": "#F58518",
    "backoff": "#E45756",
}
PRIMITIVE_LABELS: Mapping[str, str] = {
    "move": "navigate",
    "interact": "interact",
    "wait": "wait",
    "backoff": "backoff",
}
AGENT_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2")
DPI = 100


def _timeline(rows: Mapping[str, Sequence[str | None]], title: str) -> Figure:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    agents = list(rows)
    steps = max((len(r) for r in rows.values()), default=0)
    fig = Figure(figsize=(min(5 + steps * 0.06, 17), 1.2 + 0.45 * len(agents)), dpi=DPI)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for y, agent in enumerate(agents):
        start = 0
        row = list(rows[agent])
        for x in range(1, len(row) + 1):  # one bar per run of equal primitives
            if x == len(row) or row[x] != row[start]:
                if row[start] is not None:
                    ax.broken_barh(
                        [(start + 0.5, x - start)],
                        (y - 0.4, 0.8),
                        facecolors=PRIMITIVE_COLORS[row[start] or "move"],
                    )
                start = x
    ax.set_yticks(range(len(agents)), agents)
    ax.set_ylim(len(agents) - 0.5, -0.5)
    ax.set_xlim(0.5, max(steps, 1) + 0.5)
    ax.set_xlabel("environment step")
    ax.set_title(title, fontsize=10)
    used = {p for r in rows.values() for p in r if p is not None}
    handles = [
        Patch(color=PRIMITIVE_COLORS[p], label=PRIMITIVE_LABELS[p])
        for p in PRIMITIVE_COLORS
        if p in used
    ]
    if handles:
        ax.legend(handles=handles, loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=8,
                  frameon=False)  # fmt: skip
    fig.tight_layout()
    return fig


def timeline_rows(result: EmbodiedResult) -> dict[str, list[str | None]]:
    """Per agent, the primitive of every step (None: done, nothing to do)."""
    rows: dict[str, list[str | None]] = {a: [None] * result.steps for a in result.agents}
    for entry in result.trace:
        rows[entry.agent][entry.step - 1] = entry.primitive
    return rows


def timeline_figure(result: EmbodiedResult, title: str | None = None) -> Figure:
    title = title or (
        f"{result.status}: {result.steps} steps, {result.waits} waits, {result.backoffs} backoffs"
    )
    return _timeline(timeline_rows(result), title)


def save_timeline(result: EmbodiedResult, path: str | Path, title: str | None = None) -> Path:
    """The embodied run's Gantt-style timeline as a PNG."""
    path = Path(path)
    timeline_figure(result, title).savefig(path)
    return path


def schedule_timeline(
    schedule: Sequence[Sequence[tuple[str, str]]],
    agents: Sequence[str],
    path: str | Path,
    title: str = "symbolic schedule",
) -> Path:
    """The same chart for a symbolic joint schedule (``RunResult.schedule``): every
    scheduled action is one interact step."""
    rows: dict[str, list[str | None]] = {a: [None] * len(schedule) for a in agents}
    for step, pairs in enumerate(schedule):
        for agent, _ in pairs:
            rows.setdefault(agent, [None] * len(schedule))[step] = "interact"
    path = Path(path)
    _timeline(rows, title).savefig(path)
    return path


# ----------------------------------------------------------------- animation


def _frames(result: EmbodiedResult) -> list[dict[str, tuple[Cell, tuple[str, ...], Cell | None]]]:
    """Per step 0..steps: each agent's cell, what it holds, and where it is walking."""
    position = dict(result.start_positions)
    holding: dict[str, tuple[str, ...]] = {a: () for a in result.agents}
    by_step: dict[int, list[Any]] = {}
    for entry in result.trace:
        by_step.setdefault(entry.step, []).append(entry)
    # where each navigation ends: the cell of the move that applies it
    arrivals: dict[str, list[tuple[int, Cell]]] = {a: [] for a in result.agents}
    for entry in result.trace:
        if entry.primitive == "move" and entry.applied is not None:
            arrivals[entry.agent].append((entry.step, entry.position))
    frames = []
    for step in range(result.steps + 1):
        for entry in by_step.get(step, []):
            position[entry.agent] = entry.position
            holding[entry.agent] = entry.holding
        frame = {}
        for agent in result.agents:
            target = next((cell for s, cell in arrivals[agent] if s > step), None)
            frame[agent] = (position[agent], holding[agent], target)
        frames.append(frame)
    return frames


def save_animation(
    result: EmbodiedResult,
    floor_plan: FloorPlan,
    path: str | Path,
    max_frames: int = 120,
    fps: int = 6,
) -> Path:
    """An animated GIF of the run (long runs are downsampled to ``max_frames``)."""
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    frames = _frames(result)
    stride = max(1, -(-len(frames) // max_frames))
    shown = list(range(0, len(frames), stride))
    if shown[-1] != len(frames) - 1:
        shown.append(len(frames) - 1)
    scale = 0.42
    fig = Figure(figsize=(floor_plan.width * scale + 0.4, floor_plan.height * scale + 0.6), dpi=72)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.02, 0.02, 0.96, 0.9))
    ax.set_xlim(-0.5, floor_plan.width - 0.5)
    ax.set_ylim(floor_plan.height - 0.5, -0.5)
    ax.set_aspect("equal")
    ax.axis("off")
    for x, y, w, h in floor_plan.walls:
        ax.add_patch(Rectangle((x - 0.5, y - 0.5), w, h, color="0.25"))
    for name, (x, y, w, h) in floor_plan.furniture.items():
        ax.add_patch(Rectangle((x - 0.5, y - 0.5), w, h, facecolor="#d9c7a7", edgecolor="0.4"))
        ax.text(x - 0.5 + w / 2, y - 0.5 + h / 2, name, ha="center", va="center", fontsize=5)
    for x, y in floor_plan.locations.values():
        ax.add_patch(Rectangle((x - 0.5, y - 0.5), 1, 1, facecolor="#eef3f8", edgecolor="none"))
    colors = {a: AGENT_COLORS[i % len(AGENT_COLORS)] for i, a in enumerate(result.agents)}
    dots = {a: ax.plot([], [], "o", color=colors[a], markersize=9)[0] for a in result.agents}
    lines = {a: ax.plot([], [], "--", color=colors[a], linewidth=1)[0] for a in result.agents}
    labels = {a: ax.text(0, 0, "", fontsize=6, color=colors[a]) for a in result.agents}
    title = ax.set_title("", fontsize=8)

    def draw(index: int) -> list[Any]:
        step = shown[index]
        for agent, (cell, held, target) in frames[step].items():
            dots[agent].set_data([cell[0]], [cell[1]])
            if target is not None:
                lines[agent].set_data([cell[0], target[0]], [cell[1], target[1]])
            else:
                lines[agent].set_data([], [])
            labels[agent].set_position((cell[0] + 0.35, cell[1] - 0.3))
            labels[agent].set_text(agent + (f" [{', '.join(held)}]" if held else ""))
        title.set_text(f"step {step}/{result.steps}  ({result.status})")
        return [*dots.values(), *lines.values(), *labels.values(), title]

    animation = FuncAnimation(fig, draw, frames=len(shown), blit=False)
    path = Path(path)
    animation.save(str(path), writer=PillowWriter(fps=fps))
    return path
