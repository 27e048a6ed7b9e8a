"""Pictures of an embodied execution: an animated GIF of the kitchen and a timeline.

The GIF shows the floor plan (walls, furniture, a real scene's unreachable space and
receptacles, the locations' cells), labels placed where they do not overlap, every agent
as a numbered disc with the grid path it is about to walk, doors coloured open or closed,
and a side panel with what each agent holds and does and what lies in which receptacle.
Text is at least ``TEXT_PX`` pixels high. matplotlib draws the floor once; each frame's
agents, routes, doors and text are drawn over a copy of it with PIL (matplotlib's text
is slow); :func:`save_frame` writes one frame as a PNG at print resolution. The timeline is a Gantt-style
chart, agents by environment steps, coloured by primitive (navigate, interact, wait,
backoff); :func:`schedule_timeline` draws the same chart for a symbolic joint schedule.

matplotlib is imported lazily (only these functions need it), on an Agg canvas without
pyplot, so the executor itself stays light.
"""

from __future__ import annotations

import re
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from twostep.embodied.executor import EmbodiedResult, TraceStep
from twostep.embodied.floorplan import Cell, FloorPlan
from twostep.embodied.layouts import display_names
from twostep.embodied.scene import Scene

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


# ----------------------------------------------------------------- the kitchen

CELL_IN = 0.38  # a grid cell, inches (38 px in the GIF)
PANEL_IN = 2.7  # the side panel: agents, what they hold and do; receptacles' contents
TEXT_PX = 11  # the smallest text at the default size (GIF at DPI)
OPEN_COLOR, CLOSED_COLOR, FURNITURE_COLOR = "#a8d5a2", "#b08d63", "#e2d4b7"
UNREACHABLE_COLOR, WALL_COLOR, LOCATION_COLOR = "#cfc9bd", "#3b3b3b", "#dce9f5"


def _pt(px: float, dpi: float = DPI) -> float:
    """Points for a text ``px`` pixels high at ``dpi``."""
    return px * 72 / dpi


@dataclass(frozen=True)
class _Frame:
    """One picture: each agent's cell, what it holds, what it does, where it walks."""

    step: int
    cells: Mapping[str, Cell]
    holding: Mapping[str, tuple[str, ...]]
    doing: Mapping[str, str]
    routes: Mapping[str, tuple[Cell, ...]]
    scene: Scene


def _frames(result: EmbodiedResult) -> list[_Frame]:
    """Per step 0..steps: the agents and the scene after that step. A route is the cells
    the agent will walk through until it arrives where its navigation ends (the trace's
    own future positions: the grid path actually taken)."""
    by_step: dict[int, list[TraceStep]] = {}
    for entry in result.trace:
        by_step.setdefault(entry.step, []).append(entry)
    walks: dict[str, list[tuple[int, Cell, bool]]] = {a: [] for a in result.agents}
    for entry in result.trace:  # (step, cell, arrives) of every move, per agent
        if entry.primitive in ("move", "backoff"):
            arrives = entry.primitive == "backoff" or entry.applied is not None
            walks[entry.agent].append((entry.step, entry.position, arrives))
    cells = dict(result.start_positions)
    holding: dict[str, tuple[str, ...]] = {a: () for a in result.agents}
    doing: dict[str, str] = {a: "" for a in result.agents}
    scene = result.scene
    frames = []
    for step in range(result.steps + 1):
        for entry in by_step.get(step, []):
            cells[entry.agent] = entry.position
            holding[entry.agent] = entry.holding
            verb = PRIMITIVE_LABELS[entry.primitive]
            doing[entry.agent] = f"{verb} {entry.action}" if entry.action else verb
            scene = entry.scene or scene
        routes = {}
        for agent in result.agents:
            route: list[Cell] = []
            for at, cell, arrives in walks[agent]:
                if at <= step:
                    continue
                if route and abs(cell[0] - route[-1][0]) + abs(cell[1] - route[-1][1]) > 1:
                    break  # a pause elsewhere: the next walk is not this one
                route.append(cell)
                if arrives:
                    break
            routes[agent] = tuple(route)
        frames.append(_Frame(step, dict(cells), dict(holding), dict(doing), routes, scene))
    return frames


def _short(text: str, names: Mapping[str, str]) -> str:
    """An action or object list with AlfWorld ids shortened (``fridge1``)."""
    return re.sub(r"[\w|.+-]+", lambda m: names.get(m.group(0), m.group(0)), text)


class _KitchenFigure:
    """The floor plan drawn once; agents, routes, doors and the panel redrawn per frame."""

    def __init__(self, result: EmbodiedResult, floor_plan: FloorPlan, dpi: float) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.result, self.floor, self.dpi = result, floor_plan, dpi
        width_in = floor_plan.width * CELL_IN
        height_in = max(floor_plan.height * CELL_IN, 3.2)
        self.fig = Figure(figsize=(width_in + PANEL_IN + 0.3, height_in + 0.45), dpi=dpi)
        self.canvas = FigureCanvasAgg(self.fig)
        total_w, total_h = self.fig.get_size_inches()
        self.ax = self.fig.add_axes(
            (0.1 / total_w, 0.1 / total_h, width_in / total_w, (height_in) / total_h)
        )
        self.panel = self.fig.add_axes(
            ((width_in + 0.25) / total_w, 0.1 / total_h, PANEL_IN / total_w, height_in / total_h)
        )
        self.panel.axis("off")
        self.ax.set_xlim(-0.5, floor_plan.width - 0.5)
        self.ax.set_ylim(floor_plan.height - 0.5, -0.5)
        self.ax.set_aspect("equal", adjustable="box")
        self.ax.axis("off")
        names = set(floor_plan.fixtures) | set(floor_plan.furniture)
        for scene in [result.scene, *(t.scene for t in result.trace if t.scene)]:
            names |= set(scene.contents) | {i for v in scene.contents.values() for i in v}
        names |= {h for t in result.trace for h in t.holding} | set(floor_plan.locations)
        self.names = display_names(names)
        self.colors = {a: AGENT_COLORS[i % len(AGENT_COLORS)] for i, a in enumerate(result.agents)}
        self._tiles: dict[tuple[str, int, str, str], tuple[Any, int, int]] = {}
        self._draw_floor()
        self._make_artists()

    # ------------------------------------------------------------ the static floor

    def _anchors(self) -> dict[str, tuple[float, float, float, float]]:
        """Where each receptacle is drawn: (x, y, width, height) in cells."""
        out = {n: (x - 0.5, y - 0.5, float(w), float(h)) for n, (x, y, w, h) in self.floor.furniture.items()}  # fmt: skip
        out.update({n: (x - 0.4, y - 0.4, 0.8, 0.8) for n, (x, y) in self.floor.fixtures.items()})
        return out

    def _draw_floor(self) -> None:
        from matplotlib.colors import ListedColormap
        from matplotlib.patches import Rectangle

        floor, ax = self.floor, self.ax
        wall_cells = {(x + dx, y + dy) for x, y, w, h in floor.walls for dx in range(w) for dy in range(h)}  # fmt: skip
        furniture_cells = {
            (x + dx, y + dy) for x, y, w, h in floor.furniture.values()
            for dx in range(w) for dy in range(h)
        }  # fmt: skip
        grid = [[0] * floor.width for _ in range(floor.height)]
        for x, y in floor.blocked - furniture_cells:
            grid[y][x] = 2 if (x, y) in wall_cells else 1
        for cell in floor.locations.values():
            grid[cell[1]][cell[0]] = 3
        cmap = ListedColormap(["white", UNREACHABLE_COLOR, WALL_COLOR, LOCATION_COLOR])
        ax.imshow(grid, cmap=cmap, vmin=0, vmax=3, interpolation="nearest", zorder=0)
        self.doors: dict[str, Any] = {}
        for name, (left, top, w, h) in self._anchors().items():
            patch = Rectangle(
                (left, top), w, h, facecolor=FURNITURE_COLOR, edgecolor="0.35", zorder=1
            )
            ax.add_patch(patch)
            if self.result.scene.is_open(name) is not None:
                self.doors[name] = patch
        self.labels: list[tuple[str, Any]] = _place_labels(
            ax,
            self.canvas,
            [(self.names.get(n, n), (x + w / 2, y + h / 2)) for n, (x, y, w, h) in self._anchors().items()],
            _pt(TEXT_PX),
        )  # fmt: skip
        if floor.origin is not None:  # a real scene: its name and compass
            ax.text(0, floor.height - 1, f"{floor.name} (north up)", fontsize=_pt(TEXT_PX),
                    va="center", ha="left", color="0.2", zorder=2)  # fmt: skip

    # ------------------------------------------------------------ what moves

    def _make_artists(self) -> None:
        # Doors are drawn per frame (open or closed) in pixel boxes; the static drawing
        # shows them as plain furniture.
        height = self.fig.bbox.height
        self.door_boxes = {}
        for name, patch in self.doors.items():
            box = patch.get_window_extent()
            self.door_boxes[name] = (box.x0, height - box.y1, box.x1, height - box.y0)

    def _pixel(self, cell: Cell) -> tuple[float, float]:
        x, y = self.ax.transData.transform(cell)
        return x, self.fig.bbox.height - y

    def draw(self, image: Any, frame: _Frame) -> None:
        """The frame's shapes on the image: doors, routes, agents (PIL: fast)."""
        from PIL import ImageDraw

        draw = ImageDraw.Draw(image)
        for name, box in self.door_boxes.items():
            color = OPEN_COLOR if frame.scene.is_open(name) else CLOSED_COLOR
            draw.rectangle(box, fill=color, outline="#595959")
        cell_px = self._pixel((1, 0))[0] - self._pixel((0, 0))[0]
        for agent in self.result.agents:
            route = [self._pixel(c) for c in (frame.cells[agent], *frame.routes[agent])]
            if len(route) > 1:
                draw.line(route, fill=_lighter(self.colors[agent]), width=max(2, round(cell_px / 12)),
                          joint="curve")  # fmt: skip
        for agent in self.result.agents:
            x, y = self._pixel(frame.cells[agent])
            r = 0.4 * cell_px
            draw.ellipse(
                (x - r, y - r, x + r, y + r), fill=self.colors[agent], outline="white", width=2
            )

    def _text(
        self,
        image: Any,
        xy: tuple[float, float],
        text: str,
        font: Any,
        fill: str,
        anchor: str = "la",
    ) -> None:
        """``text`` stamped on ``image``: each distinct text is rasterised once per figure
        (most of a frame's text is the same as the last frame's)."""
        from PIL import Image, ImageDraw

        key = (text, id(font), fill, anchor)
        if key not in self._tiles:
            left, top, right, bottom = font.getbbox(text, anchor=anchor)
            tile = Image.new("RGBA", (max(1, right - left), max(1, bottom - top)), (0, 0, 0, 0))
            ImageDraw.Draw(tile).text((-left, -top), text, font=font, fill=fill, anchor=anchor)
            self._tiles[key] = (tile, left, top)
        tile, left, top = self._tiles[key]
        image.paste(tile, (round(xy[0] + left), round(xy[1] + top)), tile)

    def write(self, image: Any, frame: _Frame, final: bool) -> None:
        """The frame's text, drawn on the image with PIL (matplotlib's text is slow)."""
        from PIL import ImageDraw

        draw = ImageDraw.Draw(image)
        height = image.height
        font, bold = _font(TEXT_PX * self.dpi / DPI), _font(TEXT_PX * self.dpi / DPI, bold=True)
        big = _font((TEXT_PX + 3) * self.dpi / DPI, bold=True)
        for text, box in self.labels:
            top = height - box.y1
            draw.rectangle((box.x0, top, box.x1, height - box.y0), fill="#fbfaf6")
            self._text(image, ((box.x0 + box.x1) / 2, (top + height - box.y0) / 2), text, font,
                       "black", "mm")  # fmt: skip
        for index, agent in enumerate(self.result.agents):
            x, y = self.ax.transData.transform(frame.cells[agent])
            self._text(image, (x, height - y), str(index), bold, "white", "mm")
        status = f"  ({self.result.status})" if final else ""
        map_box = self.ax.get_window_extent()
        self._text(image, ((map_box.x0 + map_box.x1) / 2, 4),
                   f"step {frame.step}/{self.result.steps}{status}", big, "black", "ma")  # fmt: skip
        panel = self.panel.get_window_extent()
        x, y = panel.x0, height - panel.y1
        line = font.size * 1.3
        for index, agent in enumerate(self.result.agents):
            held = ", ".join(self.names.get(h, h) for h in frame.holding[agent]) or "nothing"
            doing = textwrap.wrap(_short(frame.doing[agent], self.names) or "-", 40)[:3]
            self._text(image, (x, y), f"{index}  {agent}", bold, self.colors[agent])
            self._text(image, (x + font.size, y + line), f"holds {held}", font, "black")
            for row, text in enumerate(doing, start=2):
                self._text(image, (x + font.size, y + row * line), text, font, "#4d4d4d")
            y += (len(doing) + 2.4) * line
        rows = []
        for receptacle, items in sorted(frame.scene.contents.items()):
            state = frame.scene.is_open(receptacle)
            door = "" if state is None else (" (open)" if state else " (closed)")
            listed = ", ".join(self.names.get(i, i) for i in items)
            rows.append(
                textwrap.shorten(f"{self.names.get(receptacle, receptacle)}{door}: {listed}", 44)
            )
        if rows:
            self._text(image, (x, y), "in the receptacles", bold, "black")
            for text in rows:
                y += line
                self._text(image, (x + font.size, y), text, font, "black")
            y += 1.6 * line
        if self.doors:
            for color, word in ((OPEN_COLOR, "open"), (CLOSED_COLOR, "closed")):
                draw.rectangle(
                    (x, y + 2, x + font.size, y + font.size + 2), fill=color, outline="#595959"
                )
                self._text(image, (x + 1.5 * font.size, y), word, font, "black")
                x += 5 * font.size


def _lighter(color: str, amount: float = 0.45) -> tuple[int, int, int]:
    """``color`` mixed with white (a route under the agents' discs)."""
    rgb = [int(color[i : i + 2], 16) for i in (1, 3, 5)]
    r, g, b = (round(c + (255 - c) * amount) for c in rgb)
    return r, g, b


@lru_cache(maxsize=16)
def _font(px: float, bold: bool = False) -> Any:
    """matplotlib's DejaVu Sans at ``px`` pixels, for PIL."""
    from matplotlib import font_manager
    from PIL import ImageFont

    path = font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans",
                                                             weight="bold" if bold else "normal"))  # fmt: skip
    return ImageFont.truetype(path, round(px))


def _place_labels(
    ax: Any, canvas: Any, labels: Sequence[tuple[str, tuple[float, float]]], size: float
) -> list[tuple[str, Any]]:
    """Where label texts go (their pixel boxes), never on top of each other: each tries
    its anchor, then above, below, left and right of it, keeping the first free place."""
    canvas.draw()
    renderer = canvas.get_renderer()
    boxes: list[Any] = []
    out = []
    offsets = ((0, 0), (0, -0.75), (0, 0.75), (-1.2, 0), (1.2, 0), (0, -1.5), (0, 1.5))
    for text, (x, y) in sorted(labels, key=lambda item: (item[1][1], item[1][0])):
        chosen = None
        for dx, dy in offsets:
            artist = ax.text(x + dx, y + dy, text, fontsize=size, ha="center", va="center")
            box = artist.get_window_extent(renderer).expanded(1.08, 1.2)
            artist.remove()
            if chosen is None:
                chosen = box  # nowhere free: keep it at its anchor
            if not any(box.overlaps(other) for other in boxes):
                chosen = box
                break
        boxes.append(chosen)
        out.append((text, chosen))
    return out


def _render(
    result: EmbodiedResult, floor_plan: FloorPlan, steps: Sequence[int], dpi: float
) -> list[Any]:
    """The RGB images (PIL) of the given steps: the floor drawn once by matplotlib, each
    frame's shapes and text drawn over a copy of it."""
    from PIL import Image

    figure = _KitchenFigure(result, floor_plan, dpi)
    frames = _frames(result)
    canvas: Any = figure.canvas
    canvas.draw()
    width, height = canvas.get_width_height()
    rgba = bytes(canvas.buffer_rgba())
    floor = Image.frombuffer("RGBA", (width, height), rgba, "raw", "RGBA", 0, 1).convert("RGB")
    images = []
    for step in steps:
        image = floor.copy()
        figure.draw(image, frames[step])
        figure.write(image, frames[step], final=step == result.steps)
        images.append(image)
    return images


def save_animation(
    result: EmbodiedResult,
    floor_plan: FloorPlan,
    path: str | Path,
    max_frames: int = 120,
    fps: int = 6,
) -> Path:
    """An animated GIF of the run, one frame per step (long runs are downsampled to
    ``max_frames``; the last frame is held a little longer)."""
    from PIL import Image

    count = result.steps + 1
    stride = max(1, -(-count // max_frames))
    shown = list(range(0, count, stride))
    if shown[-1] != count - 1:
        shown.append(count - 1)
    images = _render(result, floor_plan, shown, DPI)
    # one palette for every frame, from a sample of them (a door opens late in the run)
    sample = [
        image.resize((image.width // 2, image.height // 2), Image.Resampling.NEAREST)
        for image in images[:: max(1, len(images) // 6)][:8]
    ]
    mosaic = Image.new("RGB", (sample[0].width, sample[0].height * len(sample)))
    for index, image in enumerate(sample):
        mosaic.paste(image, (0, index * image.height))
    palette = mosaic.quantize(colors=128, method=Image.Quantize.MEDIANCUT)
    frames = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    durations = [round(1000 / fps)] * (len(frames) - 1) + [2000]
    path = Path(path)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=durations, loop=0)
    return path


def save_frame(
    result: EmbodiedResult, floor_plan: FloorPlan, path: str | Path, step: int, dpi: float = 200
) -> Path:
    """One frame of the animation as a PNG (``dpi`` 200: the text stays sharp when the
    picture is printed at a paper's column width)."""
    (image,) = _render(result, floor_plan, [min(step, result.steps)], dpi)
    path = Path(path)
    image.save(path)
    return path
