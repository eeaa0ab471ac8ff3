"""Top-down pictures of arrangements: the table and its objects to scale, as PNG.

The picture is drawn in the contract's table frame: +x to the right, +y up, so
the diner (at the table's -y edge) is at the bottom. Axes are in centimetres.
Only matplotlib's object API and its Agg canvas are used (no pyplot state), and
the PNG carries no version or time stamp, so the same arrangement always gives
the same bytes.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from pathlib import Path

import matplotlib
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Patch, Rectangle, Wedge
from matplotlib.text import Text
from matplotlib.ticker import FuncFormatter, MultipleLocator
from matplotlib.transforms import offset_copy

from llm_grop.errors import BadInput
from llm_grop.figures import BACKGROUND, DPI, STYLE, save_png
from llm_grop.render.labels import separate
from llm_grop.world.arrangement import Arrangement, Placement
from llm_grop.world.kind_colors import TABLE_TOP, kind_color
from llm_grop.world.relation import CENTER, STACKING
from llm_grop.world.seat import Seat

#: Picture size in inches (1200 x 1050 pixels at :data:`DPI` dots per inch).
FIGSIZE_IN = (8.0, 7.0)
#: A picture for a phone's screen, inches: shown about 360 pixels wide, its labels stay
#: near 10 pixels high.
PHONE_SIZE_IN = (3.6, 3.9)
#: Colours of the table top and its edge (the page's is :data:`BACKGROUND`).
TABLE_FACE = TABLE_TOP
TABLE_EDGE = "#8a6d45"
RELATION_COLOR = "#333333"
_LABEL_BOX = {"boxstyle": "round,pad=0.15", "facecolor": "white", "alpha": 0.75,
              "edgecolor": "none"}

# Rectangle of the figure (left, bottom, width, height, as fractions) the axes may fill;
# the space above holds the title.
_AXES_RECT = (0.09, 0.065, 0.87, 0.78)
_MARGIN_M = 0.05
_DINER_SPACE_M = 0.16
_TITLE_WIDTH_CHARS = 80


def kind_colors(placements: Sequence[Placement]) -> dict[str, str]:
    """The colour of each kind among ``placements`` (:func:`kind_color`)."""
    return {k: kind_color(k) for k in sorted({p.kind or p.name for p in placements})}


def draw_arrangement(arrangement: Arrangement, path: str | Path, *, title: str | None = None,
                     show_relations: bool = False,
                     size_in: tuple[float, float] = FIGSIZE_IN) -> None:
    """Write a top-down PNG picture of ``arrangement`` to ``path``.

    ``title`` defaults to the arrangement's request; the requested objects are
    listed under it. ``show_relations`` adds an arrow from each relation's subject
    to its reference, labelled with the relation. ``size_in`` is the picture's size in
    inches at :data:`DPI`; the lettering keeps its size, so a smaller picture
    (:data:`PHONE_SIZE_IN`) has larger labels relative to it, for a phone's screen. The
    file is replaced atomically. Raises :class:`BadInput` if ``path`` does not end in
    ``.png`` or cannot be written.
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise BadInput(f"image {path}: only PNG pictures are made; use a name ending in .png")
    with matplotlib.rc_context(STYLE):
        save_png(_figure(arrangement, title, show_relations, size_in), path)


def _figure(arrangement: Arrangement, title: str | None, show_relations: bool,
            size_in: tuple[float, float] = FIGSIZE_IN) -> Figure:
    fig = Figure(figsize=size_in, dpi=DPI, facecolor=BACKGROUND)
    FigureCanvasAgg(fig)
    # The margins for tick labels and the title stay as many inches in a smaller picture.
    w, h = size_in
    left, bottom, width, height = _AXES_RECT
    fw, fh = FIGSIZE_IN
    ax = fig.add_axes((left * fw / w, bottom * fh / h, 1 - (1 - width) * fw / w,
                       1 - (1 - height) * fh / h))
    draw_table_on(ax, arrangement, show_relations=show_relations)
    _draw_title(fig, arrangement, title, round(_TITLE_WIDTH_CHARS * w / fw))
    return fig


def draw_table_on(ax: Axes, arrangement: Arrangement, *, show_relations: bool = True,
                  compact: bool = False) -> None:
    """Draw ``arrangement`` top-down onto ``ax``, in its table frame (data units: metres).

    The table top (a rectangle or a circle), the diner at its -y edge and every object
    are drawn to scale with equal aspect; tick labels read in centimetres.
    ``show_relations`` adds an arrow from each relation's subject to its reference.
    ``compact`` draws smaller labels and no axis labels or tick labels (and never a
    legend), for an inset or a small panel. The figure's title is left to the caller.
    """
    ax.set_facecolor(BACKGROUND)
    table = arrangement.table
    w, d = table.width, table.depth
    top = {"facecolor": TABLE_FACE, "edgecolor": TABLE_EDGE,
           "linewidth": 1.2 if compact else 2.0, "zorder": 1}
    ax.add_patch(Circle((0.0, 0.0), w / 2, **top) if table.is_round
                 else Rectangle((-w / 2, -d / 2), w, d, **top))
    for k, seat in enumerate(table.seats):
        _draw_diner(ax, seat, f"diner {k}" if len(table.seats) > 1 else "diner", compact)
    stacks = _stacks(arrangement.placements)
    by_name = {p.name: p for p in arrangement.placements}
    order = sorted(range(len(arrangement.placements)),
                   key=lambda i: stacks[arrangement.placements[i].name][0])
    colors = kind_colors(arrangement.placements)
    levels: dict[str, int] = {}
    names: list[Text] = []
    for i in order:
        p = arrangement.placements[i]
        depth, root = stacks[p.name]
        name = _draw_object(ax, p, depth, colors[p.kind or p.name], compact)
        if name is not None:
            names.append(name)
        if depth > 0:
            # Labels of one stack are put one above the other, next to the stack.
            _label_stacked(ax, p, by_name[root], levels.get(root, 0), compact)
            levels[root] = levels.get(root, 0) + 1
    if show_relations:
        _draw_relations(ax, arrangement, compact)
    _set_limits(ax, arrangement, compact)
    separate(ax, names)


def _draw_diner(ax: Axes, seat: Seat, label: str, compact: bool = False) -> None:
    """A diner at ``seat`` (table frame), facing the way the seat faces: shoulders behind
    the edge, head towards the table, and a label behind them."""
    c, s = math.cos(seat.yaw), math.sin(seat.yaw)

    def at(back: float) -> tuple[float, float]:
        return (seat.x - back * c, seat.y - back * s)

    facing = math.degrees(seat.yaw)
    ax.add_patch(Wedge(at(0.10), 0.07, facing - 90, facing + 90, facecolor="#c8c8c8",
                       edgecolor="#7a7a7a", linewidth=1.0, zorder=1))
    ax.add_patch(Circle(at(0.055), 0.022, facecolor="#c8c8c8", edgecolor="#7a7a7a",
                        linewidth=1.0, zorder=1))
    x, y = at(0.13)
    ax.text(x, y, label, ha="center", va="center", fontsize=6 if compact else 9,
            color="#444444", zorder=1)


def _stacks(placements: Sequence[Placement]) -> dict[str, tuple[int, str]]:
    """``(depth, root)`` of each object: how many objects it rests on (0: the table) and
    the bottom object of its stack. A cycle of supports counts as resting on the table."""
    on = {p.name: p.on for p in placements}
    out: dict[str, tuple[int, str]] = {}
    for name in on:
        depth, root, seen, cur = 0, name, {name}, on[name]
        while cur is not None:
            if cur in seen:
                depth, root = 0, name
                break
            depth += 1
            if cur not in on:
                break
            seen.add(cur)
            root, cur = cur, on[cur]
        out[name] = (depth, root)
    return out


def _half_extent_y(p: Placement) -> float:
    """Half the height (along y, metres) of ``p``'s footprint's bounding box."""
    sx, sy = p.size
    if p.shape == "circle":
        return sx / 2
    return abs(sx / 2 * math.sin(p.yaw)) + abs(sy / 2 * math.cos(p.yaw))


def _draw_object(ax: Axes, p: Placement, depth: int, color: str, compact: bool = False
                 ) -> Text | None:
    """Draw ``p`` and, unless it is stacked (labelled beside its stack), its name: the
    name's text."""
    stacked = depth > 0
    # A stacked object is see-through with a dashed, opaque outline, so both it and
    # its support stay visible.
    style = {"facecolor": to_rgba(color, 0.45 if stacked else 0.85), "edgecolor": "#111111",
             "linewidth": 1.3 if stacked else 0.8, "linestyle": "--" if stacked else "-",
             "zorder": 2 + depth}
    sx, sy = p.size
    patch: Patch
    if p.shape == "circle":
        patch = Circle((p.x, p.y), sx / 2, **style)
    else:
        patch = Rectangle((p.x - sx / 2, p.y - sy / 2), sx, sy, angle=math.degrees(p.yaw),
                          rotation_point="center", **style)
    ax.add_patch(patch)
    if not stacked:
        rotation = 0.0
        if p.shape == "box" and sy > 1.5 * sx:
            rotation = (math.degrees(p.yaw) + 90.0) % 180.0  # along the long side, upright
            rotation = rotation - 180.0 if rotation > 90.0 else rotation
        return ax.text(p.x, p.y, p.name, ha="center", va="center",
                       fontsize=_small(7, compact), rotation=rotation, rotation_mode="anchor",
                       bbox=_LABEL_BOX, zorder=10)
    return None


def _label_stacked(ax: Axes, p: Placement, root: Placement, level: int,
                   compact: bool = False) -> None:
    """Label ``p`` (resting on another object) beside the top of its stack's ``root``.

    Labels lean toward the middle of the table (so they stay in the picture) and go
    one line higher per ``level``, so they stay clear of the support's own label.
    """
    right = root.x > 0
    scale = 0.65 if compact else 1.0
    dx = (-16 if right else 16) * scale
    place = offset_copy(ax.transData, fig=ax.figure, x=dx, y=(6 + 12 * level) * scale,
                        units="points")
    ax.annotate(f"{p.name} (on {p.on})", xy=(p.x, p.y + _half_extent_y(p) * 0.6),
                xytext=(root.x, root.y + _half_extent_y(root)), textcoords=place,
                fontsize=_small(7, compact),
                ha="right" if right else "left", va="bottom", zorder=12, bbox=_LABEL_BOX,
                arrowprops={"arrowstyle": "-", "color": "#444444", "linewidth": 0.7,
                            "shrinkA": 0, "shrinkB": 1})


def _boundary_distance(p: Placement, ux: float, uy: float) -> float:
    """Distance (metres) from ``p``'s centre to its footprint's edge along unit ``(ux, uy)``."""
    sx, sy = p.size
    if p.shape == "circle":
        return sx / 2
    c, s = math.cos(p.yaw), math.sin(p.yaw)
    lx, ly = abs(ux * c + uy * s), abs(-ux * s + uy * c)  # the direction in p's own frame
    return min(sx / 2 / lx if lx > 1e-12 else math.inf, sy / 2 / ly if ly > 1e-12 else math.inf)


def _draw_relations(ax: Axes, arrangement: Arrangement, compact: bool = False) -> None:
    """An arrow from each relation's subject to its reference, edge to edge, labelled."""
    by_name = {p.name: p for p in arrangement.placements}
    for rel in arrangement.relations:
        subject = by_name.get(rel.subject)
        if rel.relation in STACKING or subject is None:
            continue
        if rel.relation == CENTER:
            end, reference = (0.0, 0.0), None
        elif rel.reference in by_name:
            reference = by_name[rel.reference]
            end = (reference.x, reference.y)
        else:
            continue
        label = relation_label(rel.relation)
        length = math.dist((subject.x, subject.y), end)
        if length < 1e-6:
            continue
        ux, uy = (end[0] - subject.x) / length, (end[1] - subject.y) / length
        a = _boundary_distance(subject, ux, uy)
        b = 0.0 if reference is None else _boundary_distance(reference, -ux, -uy)
        if a + b >= length:  # overlapping footprints: join the centres
            a = b = 0.0
        start = (subject.x + ux * a, subject.y + uy * a)
        stop = (end[0] - ux * b, end[1] - uy * b)
        ax.annotate("", xy=stop, xytext=start, zorder=20,
                    arrowprops={"arrowstyle": "->", "color": RELATION_COLOR, "linewidth": 0.9,
                                "linestyle": ":", "shrinkA": 0, "shrinkB": 0})
        mid = ((start[0] + stop[0]) / 2, (start[1] + stop[1]) / 2)
        ax.text(*mid, label, fontsize=_small(6.5, compact), color=RELATION_COLOR,
                ha="center", va="center", zorder=21,
                bbox={"boxstyle": "round,pad=0.1", "facecolor": "#ffffe0", "alpha": 0.85,
                      "edgecolor": "none"})


def relation_label(name: str) -> str:
    """The label of relation ``name`` (a name of ``world/relations.yaml``) on a picture: the
    name without "to the", its two directions joined by a hyphen ("to the left of": "left
    of", "above and to the left of": "above-left of", "above": "above")."""
    return name.replace(" and to the ", "-").removeprefix("to the ")


def _small(size: float, compact: bool) -> float:
    """A font size in points, shrunk for a compact drawing."""
    return round(size * 0.7, 1) if compact else size


def _set_limits(ax: Axes, arrangement: Arrangement, compact: bool = False) -> None:
    w, d = arrangement.table.width, arrangement.table.depth
    x0, x1 = -w / 2 - _MARGIN_M, w / 2 + _MARGIN_M
    y0, y1 = -d / 2 - _DINER_SPACE_M, d / 2 + _MARGIN_M
    for seat in arrangement.table.diners:
        x0, x1 = min(x0, seat.x - _DINER_SPACE_M), max(x1, seat.x + _DINER_SPACE_M)
        y0, y1 = min(y0, seat.y - _DINER_SPACE_M), max(y1, seat.y + _DINER_SPACE_M)
    for p in arrangement.placements:
        r = math.hypot(*p.size) / 2 if p.shape == "box" else p.size[0] / 2
        x0, x1 = min(x0, p.x - r - _MARGIN_M), max(x1, p.x + r + _MARGIN_M)
        y0, y1 = min(y0, p.y - r - _MARGIN_M), max(y1, p.y + r + _MARGIN_M)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box", anchor="C" if compact else "N")
    step = _tick_step(max(x1 - x0, y1 - y0))
    cm = FuncFormatter(lambda v, _pos: f"{v * 100:.0f}")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(MultipleLocator(step))
        axis.set_major_formatter(cm)
    ax.grid(True, color="#d9d9d9", linewidth=0.5, zorder=0)
    ax.set_axisbelow(True)
    if compact:
        ax.tick_params(labelbottom=False, labelleft=False, length=0)
        return
    ax.tick_params(labelsize=7, length=2)
    ax.set_xlabel("x (cm), to the diner's right", fontsize=8)
    ax.set_ylabel("y (cm), away from the diner", fontsize=8)


def _tick_step(span_m: float) -> float:
    """A grid step (metres) giving at most about 12 lines across ``span_m``."""
    for step in (0.05, 0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 5.0):
        if span_m / step <= 12:
            return step
    return 10.0 ** math.ceil(math.log10(span_m / 10))


def _clip_lines(text: str, width: int, max_lines: int) -> str:
    lines = textwrap.wrap(text, width) or [""]
    if len(lines) > max_lines:
        lines = lines[:max_lines]
        lines[-1] = lines[-1][: width - 1].rstrip() + "\u2026"
    return "\n".join(lines)


def _draw_title(fig: Figure, arrangement: Arrangement, title: str | None,
                width_chars: int = _TITLE_WIDTH_CHARS) -> None:
    heading = title if title is not None else (arrangement.request or "arrangement")
    head = fig.text(0.5, 0.975, _clip_lines(heading, width_chars, 2), ha="center",
                    va="top", fontsize=11, fontweight="bold")
    names = [p.name for p in arrangement.placements]
    table = arrangement.table
    top = (f"round table \u00f8 {table.width * 100:g} cm" if table.is_round
           else f"table {table.width * 100:g} \u00d7 {table.depth * 100:g} cm")
    listed = f"objects ({len(names)}): {', '.join(names) or 'none'}  |  {top}"
    fig.axes[0].annotate(_clip_lines(listed, width_chars + 15, 2), xy=(0.5, 0.0),
                         xycoords=head, xytext=(0, -5), textcoords="offset points",
                         ha="center", va="top", fontsize=8.5, color="#333333",
                         annotation_clip=False)
