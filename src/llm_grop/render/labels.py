"""Keeping object labels apart: a label that would cover another is moved up or down, by
its own height at a time, to the nearest free place, with a thin line back to its object.
So names stay legible where objects lie close together (four breads around a plate), at
a phone's size too."""

from __future__ import annotations

from collections.abc import Sequence

from matplotlib.axes import Axes
from matplotlib.text import Text
from matplotlib.transforms import Bbox

#: Pixels kept free around a label.
PAD_PX = 2.0
#: Places tried on each side before a label is left where it is.
MAX_STEPS = 12
#: Colour and width (points) of the line from a moved label to its object.
LEADER_COLOR = "#555555"
LEADER_WIDTH_PT = 0.6


def separate(ax: Axes, labels: Sequence[Text]) -> int:
    """Move each of ``labels`` (texts in ``ax``'s data coordinates, in drawing order) that
    overlaps one placed before it to the nearest free place above or below; the number
    moved. Each moved label gets a line back to where it was."""
    # The equal aspect is applied at drawing time; apply it now, so pixels are final.
    ax.apply_aspect()
    canvas = ax.figure.canvas
    renderer = canvas.get_renderer()  # type: ignore[attr-defined]
    to_data = ax.transData.inverted()
    placed: list[Bbox] = []
    moved = 0
    for label in labels:
        box = _box(label, renderer)
        if not any(box.overlaps(other) for other in placed):
            placed.append(box)
            continue
        x, y = label.get_position()
        px, py = ax.transData.transform((x, y))
        step = box.height + PAD_PX
        for k in range(1, 2 * MAX_STEPS + 1):
            shift = step * ((k + 1) // 2) * (1 if k % 2 else -1)
            candidate = box.translated(0.0, shift)
            if not any(candidate.overlaps(other) for other in placed):
                nx, ny = to_data.transform((px, py + shift))
                label.set_position((nx, ny))
                ax.plot([x, nx], [y, ny], color=LEADER_COLOR, linewidth=LEADER_WIDTH_PT,
                        zorder=label.get_zorder() - 0.5)
                placed.append(candidate)
                moved += 1
                break
        else:
            placed.append(box)
    return moved


def _box(label: Text, renderer: object) -> Bbox:
    """The label's extent in pixels, its box's padding and :data:`PAD_PX` included."""
    patch = label.get_bbox_patch()
    if patch is not None:
        label.update_bbox_position_size(renderer)  # type: ignore[arg-type]
    box = patch.get_window_extent(renderer) if patch is not None else \
        label.get_window_extent(renderer)  # type: ignore[arg-type]
    return box.expanded(1.0, 1.0).padded(PAD_PX / 2)
