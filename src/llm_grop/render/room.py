"""Top-down pictures of a run: the room map and the robot's trajectory, as PNG (paper Fig. 4).

The map is drawn in the room frame (metres, +x right, +y up, equal aspect): the room's
boundary, interior walls, tables (the target highlighted), the chairs sensed at planning
time, where each object started, the path the robot drove (arrows give the direction;
failed legs are dashed red), where it stood to pick and, numbered in order, where it
stood to place. A panel on the right shows the final table setting in the table frame
(see :func:`llm_grop.render.table.draw_table_on`). Like the table picture, only
matplotlib's object API and its Agg canvas are used and the PNG carries no version or
time stamp, so the same run always gives the same bytes.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, FancyArrowPatch, Patch, Polygon, Rectangle
from matplotlib.ticker import MultipleLocator

from llm_grop.errors import BadInput
from llm_grop.render.table import (
    BACKGROUND,
    DPI,
    STYLE,
    TABLE_EDGE,
    draw_table_on,
    kind_colors,
    save_png,
)
from llm_grop.world.arrangement import Arrangement, Placement
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.plan import ExecutedStep, Plan, RunResult
from llm_grop.world.scene import Scene, SceneTable

#: Picture size in inches (1950 x 1200 pixels at the table picture's DPI).
FIGSIZE_IN = (13.0, 8.0)
#: Colours of the map's parts.
ROOM_FACE = "#fbfaf7"
WALL = "#4d4d4d"
TABLE_TAN = "#d2b48c"
TARGET_EDGE = "#e6550d"
CHAIR_FACE = "#9ecae1"
CHAIR_EDGE = "#2b6a99"
PATH_OK = "#1f5fa8"
PATH_FAILED = "#d62728"
START = "#2ca02c"
PLACE = "#6a3d9a"
PICK = "#b8a6d1"
SOURCE = "#8c564b"

# Figure rectangles (left, bottom, width, height, as fractions): the map, the final setting.
_MAP_RECT = (0.045, 0.06, 0.63, 0.83)
_TABLE_RECT = (0.70, 0.48, 0.28, 0.36)
_LEGEND_AT = (0.70, 0.44)
_MARGIN_M = 0.25
_ARROW_SPACING_M = 1.0
_ARROW = "-|>,head_length=0.7,head_width=0.35"
_TITLE_WIDTH_CHARS = 110


def draw_run(result: RunResult, path: str | Path, *, title: str | None = None) -> None:
    """Write a top-down PNG picture of the run ``result`` to ``path``.

    ``title`` defaults to the run's request; a line under it gives the method, task,
    seed, success, execution time and planning time (seconds). The file is replaced
    atomically. Raises :class:`BadInput` if ``path`` does not end in ``.png`` or cannot
    be written.
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise BadInput(f"image {path}: only PNG pictures are made; use a name ending in .png")
    with matplotlib.rc_context(STYLE):
        save_png(_figure(result, title), path)


def draw_plan(scene: Scene, plan: Plan, arrangement: Arrangement, path: str | Path, *,
              title: str | None = None) -> None:
    """Write a top-down PNG picture of ``plan``, not yet executed, to ``path``: the room,
    the planned paths and standing positions, and the arrangement it realises (drawn as
    :func:`draw_run` draws a run, every leg as planned). ``title`` defaults to the request."""
    steps = tuple(ExecutedStep(s.action, True, s.duration_s, s.object, s.goal, s.path,
                               s.standing, s.pose) for s in plan.steps)
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=FIGSIZE_IN, dpi=DPI, facecolor=BACKGROUND)
        FigureCanvasAgg(fig)
        ax = fig.add_axes(_MAP_RECT)
        handles: list[Patch | Line2D] = []
        _draw_room(ax, scene, handles)
        _draw_sources(ax, scene, arrangement.placements, handles)
        _draw_paths(ax, steps, handles)
        _draw_standing(ax, steps, scene.robot.base_radius_m, handles)
        _draw_start(ax, scene.robot_start, scene.robot.base_radius_m, handles)
        _set_limits(ax, scene, steps)
        inset = fig.add_axes(_TABLE_RECT)
        draw_table_on(inset, arrangement, show_relations=False, compact=True)
        inset.set_title("planned table setting", fontsize=8.5, color="#333333")
        fig.legend(handles=handles, loc="upper left", bbox_to_anchor=_LEGEND_AT, ncol=2,
                   fontsize=8, frameon=False, handlelength=2.2, columnspacing=1.2)
        head = fig.text(0.5, 0.985, _clip(title or arrangement.request or "plan",
                                          _TITLE_WIDTH_CHARS, 2),
                        ha="center", va="top", fontsize=12, fontweight="bold")
        facts = (f"planned: {len(plan.order)} objects  |  expected utility "
                 f"{plan.utility:.1f} s  |  expected duration "
                 f"{plan.expected_duration_s or plan.cost_s:.1f} s  |  scene {scene.name}")
        ax.annotate(facts, xy=(0.5, 0.0), xycoords=head, xytext=(0, -6),
                    textcoords="offset points", ha="center", va="top", fontsize=9,
                    annotation_clip=False, color="#333333")
        save_png(fig, Path(path))


def room_image(scene: Scene, robot: Pose2D, objects: dict[str, tuple[float, float]],
               size: tuple[int, int] = (160, 120)) -> np.ndarray:
    """An RGB image (height x width x 3, uint8) of the room from above: furniture, the
    robot at ``robot`` and each object as a dot at its room-frame ``(x, y)`` (metres)."""
    width, height = size
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(width / 100, height / 100), dpi=100, facecolor=BACKGROUND)
        canvas = FigureCanvasAgg(fig)
        ax = fig.add_axes((0, 0, 1, 1))
        _draw_room(ax, scene, [])
        for t in ax.texts:
            t.set_visible(False)
        _base(ax, robot, scene.robot.base_radius_m, PATH_OK, 0.35, 6)
        for x, y in objects.values():
            ax.add_patch(Circle((x, y), 0.05, facecolor="#1f4e9c", edgecolor="white",
                                linewidth=0.5, zorder=7))
        ax.set_xlim(-0.1, scene.width + 0.1)
        ax.set_ylim(-0.1, scene.depth + 0.1)
        ax.set_axis_off()
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def _figure(result: RunResult, title: str | None) -> Figure:
    fig = Figure(figsize=FIGSIZE_IN, dpi=DPI, facecolor=BACKGROUND)
    FigureCanvasAgg(fig)
    ax = fig.add_axes(_MAP_RECT)
    scene = result.scene
    steps = result.execution.steps
    handles: list[Patch | Line2D] = []
    _draw_room(ax, scene, handles)
    _draw_sources(ax, scene, result.final.placements, handles)
    _draw_paths(ax, steps, handles)
    _draw_standing(ax, steps, scene.robot.base_radius_m, handles)
    _draw_start(ax, scene.robot_start, scene.robot.base_radius_m, handles)
    _set_limits(ax, scene, steps)
    inset = fig.add_axes(_TABLE_RECT)
    draw_table_on(inset, result.final, show_relations=False, compact=True)
    placed = len(result.final.placements)
    unplaced = result.execution.unplaced
    heading = f"final table setting: {placed} placed"
    if unplaced:
        heading += "\n" + _clip(f"not placed: {', '.join(unplaced)}", 45, 2)
    inset.set_title(heading, fontsize=8.5, color="#333333" if not unplaced else PATH_FAILED)
    fig.legend(handles=handles, loc="upper left", bbox_to_anchor=_LEGEND_AT, ncol=2,
               fontsize=8, frameon=False, handlelength=2.2, columnspacing=1.2)
    _draw_title(fig, result, title)
    return fig


def _polygon(box: Box, **style: object) -> Polygon:
    """A patch of ``box``'s footprint (room frame)."""
    return Polygon(box.corners(), closed=True, **style)  # type: ignore[arg-type]


def _table_patch(table: SceneTable, **style: object) -> Patch:
    """A patch of ``table``'s top (room frame): a circle for a round one."""
    if table.is_round:
        return Circle((table.box.x, table.box.y), table.box.width / 2,
                      **style)  # type: ignore[arg-type]
    return _polygon(table.box, **style)


def _draw_room(ax: Axes, scene: Scene, handles: list[Patch | Line2D]) -> None:
    """The boundary, interior walls, tables and sensed chairs, each named in the legend."""
    ax.add_patch(Rectangle((0.0, 0.0), scene.width, scene.depth, facecolor=ROOM_FACE,
                           edgecolor=WALL, linewidth=3.0, zorder=1))
    handles.append(Patch(facecolor=ROOM_FACE, edgecolor=WALL, linewidth=2.0, label="room"))
    for wall in scene.walls:
        ax.add_patch(_polygon(wall, facecolor=WALL, edgecolor=WALL, linewidth=0.5, zorder=2))
    if scene.walls:
        handles.append(Patch(facecolor=WALL, edgecolor=WALL, label="wall"))
    for table in scene.tables:
        target = table.name == scene.target
        ax.add_patch(_table_patch(table, facecolor=TABLE_TAN,
                                  edgecolor=TARGET_EDGE if target else TABLE_EDGE,
                                  linewidth=2.6 if target else 1.0, zorder=2))
        label = f"{table.name}\n(target)" if target else table.name
        ax.text(table.box.x, table.box.y, label, ha="center", va="center", fontsize=7.5,
                fontweight="bold" if target else "normal", color="#3d2b14", zorder=9,
                bbox={"boxstyle": "round,pad=0.15", "facecolor": "white", "alpha": 0.6,
                      "edgecolor": "none"})
    handles.append(Patch(facecolor=TABLE_TAN, edgecolor=TABLE_EDGE, label="table"))
    handles.append(Patch(facecolor=TABLE_TAN, edgecolor=TARGET_EDGE, linewidth=2.0,
                         label="target table"))
    for chair in scene.chairs:
        ax.add_patch(_polygon(chair.box, facecolor=CHAIR_FACE, edgecolor=CHAIR_EDGE,
                              hatch="////", linewidth=0.9, zorder=3))
    if scene.chairs:
        handles.append(Patch(facecolor=CHAIR_FACE, edgecolor=CHAIR_EDGE, hatch="////",
                             label="chair (sensed)"))


def _draw_sources(ax: Axes, scene: Scene, final: Sequence[Placement],
                  handles: list[Patch | Line2D]) -> None:
    """A small marker where each object started (room frame), in its kind's colour in the
    final-setting panel when it reached the table (else brown)."""
    colors = kind_colors(final)
    color_of = {key: colors[p.kind or p.name] for p in final for key in (p.kind, p.name) if key}
    for s in scene.sources:
        ax.plot([s.x], [s.y], marker="s", markersize=4.5, color=color_of.get(s.object, SOURCE),
                linestyle="none",
                markeredgecolor="white", markeredgewidth=0.4, zorder=6)
    if scene.sources:
        handles.append(Line2D([], [], marker="s", markersize=5, color=SOURCE, linestyle="none",
                              label="object start"))


def _draw_paths(ax: Axes, steps: Sequence[ExecutedStep], handles: list[Patch | Line2D]) -> None:
    """Every navigation leg driven: solid with direction arrows, or dashed red if it failed."""
    ok_seen = failed_seen = False
    for step in steps:
        if step.action != "navigate" or len(step.path) < 2:
            continue
        xs, ys = zip(*step.path, strict=True)
        if step.ok:
            ok_seen = True
            ax.plot(xs, ys, color=PATH_OK, linewidth=1.6, alpha=0.9, zorder=7,
                    solid_capstyle="round", solid_joinstyle="round")
            for tail, head in _arrow_spots(step.path):
                ax.add_patch(FancyArrowPatch(tail, head, arrowstyle=_ARROW, mutation_scale=15,
                                             color=PATH_OK, linewidth=0.0, shrinkA=0,
                                             shrinkB=0, zorder=8))
        else:
            failed_seen = True
            ax.plot(xs, ys, color=PATH_FAILED, linewidth=1.6, linestyle=(0, (4, 2.5)), zorder=7)
            ax.plot([xs[-1]], [ys[-1]], marker="x", markersize=7, markeredgewidth=2.0,
                    color=PATH_FAILED, linestyle="none", zorder=8)
    if ok_seen:
        handles.append(Line2D([], [], color=PATH_OK, linewidth=1.6, marker=">", markersize=5,
                              label="robot path"))
    if failed_seen:
        handles.append(Line2D([], [], color=PATH_FAILED, linewidth=1.6, linestyle=(0, (4, 2.5)),
                              marker="x", markersize=6, label="failed navigation"))


def _arrow_spots(path: Sequence[tuple[float, float]]) -> list[tuple[tuple[float, float],
                                                                     tuple[float, float]]]:
    """Short ``(tail, head)`` pieces (room frame, metres) along ``path`` for direction arrows.

    One sits at the path's middle (by length) and further ones every
    ``_ARROW_SPACING_M`` metres either side, so dense and sparse paths look alike.
    """
    seg = [math.dist(a, b) for a, b in zip(path, path[1:], strict=False)]
    total = sum(seg)
    if total < 1e-6:
        return []
    count = max(1, int(total / _ARROW_SPACING_M))
    spots = [total * (k + 0.5) / count for k in range(count)]
    out = []
    for s in spots:
        acc = 0.0
        for (a, b), length in zip(zip(path, path[1:], strict=False), seg, strict=True):
            if length > 1e-9 and acc + length >= s:
                t = (s - acc) / length
                ux, uy = (b[0] - a[0]) / length, (b[1] - a[1]) / length
                mx, my = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
                half = min(0.05, length / 2)
                out.append(((mx - ux * half, my - uy * half), (mx + ux * half, my + uy * half)))
                break
            acc += length
    return out


def _base(ax: Axes, pose: Pose2D, radius: float, color: str, alpha: float, zorder: int) -> None:
    """The robot's round base at ``pose`` (``radius`` metres) with a tick for its heading."""
    ax.add_patch(Circle((pose.x, pose.y), radius, facecolor=color, alpha=alpha, zorder=zorder,
                        edgecolor="none"))
    ax.add_patch(Circle((pose.x, pose.y), radius, facecolor="none", edgecolor=color,
                        linewidth=1.0, zorder=zorder))
    ax.plot([pose.x, pose.x + 1.3 * radius * math.cos(pose.theta)],
            [pose.y, pose.y + 1.3 * radius * math.sin(pose.theta)], color=color, linewidth=1.6,
            solid_capstyle="butt", zorder=zorder)


def _draw_standing(ax: Axes, steps: Sequence[ExecutedStep], radius: float,
                   handles: list[Patch | Line2D]) -> None:
    """Where the base stood for each successful pick (light) and place (numbered 1..n).

    Places made from the same spot share one circle, labelled with all their numbers.
    """
    picks: dict[tuple[float, float], Pose2D] = {}
    places: dict[tuple[float, float], tuple[Pose2D, list[int]]] = {}
    n = 0
    for step in steps:
        if not step.ok or step.standing is None:
            continue
        key = (round(step.standing.x, 3), round(step.standing.y, 3))
        if step.action == "pick":
            picks.setdefault(key, step.standing)
        elif step.action == "place":
            n += 1
            places.setdefault(key, (step.standing, []))[1].append(n)
    for pose in picks.values():
        _base(ax, pose, radius, PICK, 0.25, 4)
    for pose, numbers in places.values():
        _base(ax, pose, radius, PLACE, 0.22, 5)
        ax.text(pose.x, pose.y, ",".join(map(str, numbers)), ha="center", va="center",
                fontsize=8, fontweight="bold", color=PLACE, zorder=11,
                bbox={"boxstyle": "circle,pad=0.15", "facecolor": "white", "alpha": 0.85,
                      "edgecolor": PLACE, "linewidth": 0.8})
    if picks:
        handles.append(Line2D([], [], marker="o", markersize=9, color=PICK, linestyle="none",
                              markerfacecolor=PICK, label="pick stance"))
    if places:
        handles.append(Line2D([], [], marker="o", markersize=9, color=PLACE, linestyle="none",
                              markerfacecolor="white", label="place stance (order)"))


def _draw_start(ax: Axes, start: Pose2D, radius: float, handles: list[Patch | Line2D]) -> None:
    """The robot's start pose: its base, heading and a star."""
    _base(ax, start, radius, START, 0.25, 6)
    ax.plot([start.x], [start.y], marker="*", markersize=11, color=START,
            markeredgecolor="white", markeredgewidth=0.6, linestyle="none", zorder=12)
    handles.append(Line2D([], [], marker="*", markersize=11, color=START, linestyle="none",
                          label="robot start"))


def _set_limits(ax: Axes, scene: Scene, steps: Sequence[ExecutedStep]) -> None:
    """The room plus a margin (and anything drawn outside it), equal aspect, metres."""
    r = scene.robot.base_radius_m
    points = [(0.0, 0.0), (scene.width, scene.depth)]
    for box in (*scene.walls, *(t.box for t in scene.tables), *(c.box for c in scene.chairs)):
        points.extend(box.corners())
    points.extend((s.x, s.y) for s in scene.sources)
    stances = [scene.robot_start, *(s.standing for s in steps if s.standing is not None)]
    for pose in stances:
        points.extend(((pose.x - r, pose.y - r), (pose.x + r, pose.y + r)))
    for step in steps:
        points.extend(step.path)
    xs, ys = zip(*points, strict=True)
    x0, x1 = min(xs) - _MARGIN_M, max(xs) + _MARGIN_M
    y0, y1 = min(ys) - _MARGIN_M, max(ys) + _MARGIN_M
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box", anchor="N")
    span = max(x1 - x0, y1 - y0)
    step_m = next((s for s in (0.25, 0.5, 1.0, 2.0, 5.0, 10.0) if span / s <= 16),
                  10.0 ** math.ceil(math.log10(span / 10)))
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(MultipleLocator(step_m))
    ax.tick_params(labelsize=7, length=2)
    ax.grid(True, color="#e3e3e3", linewidth=0.5, zorder=0)
    ax.set_axisbelow(True)
    ax.set_facecolor(BACKGROUND)
    ax.set_xlabel("x (m)", fontsize=8)
    ax.set_ylabel("y (m)", fontsize=8)


def _clip(text: str, width: int, max_lines: int) -> str:
    """``text`` wrapped to ``width`` characters, at most ``max_lines`` lines (ellipsis)."""
    lines = textwrap.wrap(text, width) or [""]
    if len(lines) > max_lines:
        lines = lines[:max_lines]
        lines[-1] = lines[-1][: width - 1].rstrip() + "\u2026"
    return "\n".join(lines)


def _draw_title(fig: Figure, result: RunResult, title: str | None) -> None:
    """The title (default: the request) and a line of the run's facts under it."""
    heading = title if title is not None else (result.request or "run")
    head = fig.text(0.5, 0.985, _clip(heading, _TITLE_WIDTH_CHARS, 2), ha="center", va="top",
                    fontsize=12, fontweight="bold")
    ex = result.execution
    task = "-" if result.task is None else str(result.task)
    outcome = "success" if result.success else f"failed ({len(ex.unplaced)} not placed)"
    facts = (f"method {result.method}  |  task {task}  |  seed {result.seed}  |  {outcome}  |  "
             f"execution {ex.execution_time_s:.1f} s  |  planning {result.planning_time_s:.2f} s"
             f"  |  failed attempts {ex.failures}  |  scene {result.scene.name}")
    fig.axes[0].annotate(_clip(facts, _TITLE_WIDTH_CHARS + 40, 1), xy=(0.5, 0.0),
                         xycoords=head, xytext=(0, -6), textcoords="offset points",
                         ha="center", va="top", fontsize=9, annotation_clip=False,
                         color=PATH_FAILED if not result.success else "#333333")
