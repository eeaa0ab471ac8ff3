"""Top-down PNG pictures of arrangements, checked by reading their pixels back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from llm_grop.errors import BadInput
from llm_grop.render import draw_arrangement
from llm_grop.render.table import BACKGROUND, DPI, FIGSIZE_IN, TABLE_FACE, relation_label
from llm_grop.world.arrangement import Arrangement, Placement
from llm_grop.world.relation import MEANINGS, Relation
from llm_grop.world.table import Table

REQUEST = "set the table with a dinner plate, a dinner fork and a dinner knife"


def placement(name: str, x: float, y: float, shape: str, size: tuple[float, float],
              on: str | None = None, yaw: float = 0.0) -> Placement:
    return Placement(name, x, y, yaw, shape, size, on, name, 0.02)  # type: ignore[arg-type]


PLATE = placement("dinner plate", 0.0, -0.1, "circle", (0.27, 0.27))
FORK = placement("dinner fork", -0.17, -0.1, "box", (0.025, 0.2))
KNIFE = placement("dinner knife", 0.17, -0.1, "box", (0.02, 0.23))
MUG = placement("mug", 0.3, 0.12, "circle", (0.09, 0.09))


def rgb(hex_color: str) -> np.ndarray:
    return np.array([int(hex_color[i:i + 2], 16) for i in (1, 3, 5)], dtype=float)


class Picture:
    """A rendered PNG and the table-frame -> pixel map found from its table-coloured area."""

    def __init__(self, path: Path, table: Table) -> None:
        self.pixels = imread(path)[:, :, :3] * 255.0
        near_table = np.all(np.abs(self.pixels - rgb(TABLE_FACE)) < 3, axis=2)
        rows, cols = np.nonzero(near_table)
        self.top, self.bottom = rows.min(), rows.max()
        self.left, self.right = cols.min(), cols.max()
        self.table = table

    def at(self, x: float, y: float) -> np.ndarray:
        """The RGB colour (0-255) at table-frame point ``(x, y)`` metres."""
        w, d = self.table.size
        col = self.left + (x + w / 2) / w * (self.right - self.left)
        row = self.bottom - (y + d / 2) / d * (self.bottom - self.top)
        return self.pixels[round(row), round(col)]

    def is_table(self, x: float, y: float) -> bool:
        return bool(np.all(np.abs(self.at(x, y) - rgb(TABLE_FACE)) < 3))


def draw(tmp_path: Path, placements: tuple[Placement, ...], name: str = "a.png",
         table: Table | None = None, **kwargs: object) -> Path:
    path = tmp_path / name
    arrangement = Arrangement(REQUEST, table or Table(), placements,
                              (Relation("dinner fork", "to the left of", "dinner plate"),))
    draw_arrangement(arrangement, path, **kwargs)  # type: ignore[arg-type]
    return path


def test_png_has_the_fixed_size(tmp_path: Path) -> None:
    path = draw(tmp_path, (PLATE, FORK, KNIFE))
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    height, width = imread(path).shape[:2]
    assert (width, height) == (round(FIGSIZE_IN[0] * DPI), round(FIGSIZE_IN[1] * DPI))


def test_same_arrangement_same_bytes(tmp_path: Path) -> None:
    a = draw(tmp_path, (PLATE, FORK, KNIFE, MUG), "a.png", show_relations=True)
    b = draw(tmp_path, (PLATE, FORK, KNIFE, MUG), "b.png", show_relations=True)
    assert a.read_bytes() == b.read_bytes()
    assert b"matplotlib" not in a.read_bytes()


@pytest.mark.parametrize("table", [Table(), Table(1.2, 0.5), Table(0.5, 0.5)])
def test_table_is_drawn_to_scale(tmp_path: Path, table: Table) -> None:
    picture = Picture(draw(tmp_path, (), table=table), table)
    ratio = (picture.right - picture.left) / (picture.bottom - picture.top)
    assert ratio == pytest.approx(table.width / table.depth, rel=0.02)


def test_objects_are_drawn_where_they_are_with_plus_y_up(tmp_path: Path) -> None:
    picture = Picture(draw(tmp_path, (PLATE, FORK, KNIFE, MUG)), Table())
    # Points inside the plate (away from its centred label) and its mirror image in y.
    assert not picture.is_table(0.0, -0.19)
    assert picture.is_table(0.0, 0.19)
    assert not picture.is_table(0.08, -0.1)
    assert picture.is_table(0.08 + 0.135 + 0.01, 0.05)
    # The mug, at the upper right, and the empty upper left.
    assert not picture.is_table(0.3, 0.12 + 0.03)
    assert picture.is_table(-0.3, 0.12 + 0.03)
    # A fork 2.5 cm wide: covered at its lower end, table just beside it.
    assert not picture.is_table(-0.17, -0.18)
    assert picture.is_table(-0.17 - 0.03, -0.18)
    # Objects have distinct colours.
    assert not np.allclose(picture.at(0.0, -0.19), picture.at(0.3, 0.15), atol=3)


def test_diner_is_below_the_table(tmp_path: Path) -> None:
    table = Table()
    picture = Picture(draw(tmp_path, (PLATE,), table=table), table)
    grey = picture.at(0.0, -table.depth / 2 - 0.07)
    assert not np.allclose(grey, rgb(BACKGROUND), atol=3)
    assert not np.allclose(grey, rgb(TABLE_FACE), atol=3)


def test_rotated_box_follows_its_yaw(tmp_path: Path) -> None:
    fork = placement("dinner fork", 0.0, 0.0, "box", (0.025, 0.2), yaw=np.pi / 2)
    picture = Picture(draw(tmp_path, (fork,)), Table())
    assert not picture.is_table(0.08, 0.0)   # along its long side, now along x
    assert picture.is_table(0.0, 0.06)


def test_stacked_object_shows_over_its_support(tmp_path: Path) -> None:
    lid_on = placement("mug lid", 0.3, 0.12, "circle", (0.095, 0.095), on="mug")
    lid_off = placement("mug lid", -0.3, 0.12, "circle", (0.095, 0.095))
    stacked = Picture(draw(tmp_path, (MUG, lid_on), "stacked.png"), Table())
    apart = Picture(draw(tmp_path, (MUG, lid_off), "apart.png"), Table())
    point = (0.3, 0.12 - 0.03)
    assert not stacked.is_table(*point)
    assert not np.allclose(stacked.at(*point), apart.at(*point), atol=3)
    assert stacked.is_table(-0.3, 0.12 - 0.03)
    assert not apart.is_table(-0.3, 0.12 - 0.03)


def test_relations_and_titles_change_the_picture(tmp_path: Path) -> None:
    plain = draw(tmp_path, (PLATE, FORK), "plain.png").read_bytes()
    assert draw(tmp_path, (PLATE, FORK), "rel.png", show_relations=True).read_bytes() != plain
    assert draw(tmp_path, (PLATE, FORK), "title.png", title="Task 1").read_bytes() != plain


def test_long_requests_and_many_objects_render(tmp_path: Path) -> None:
    many = tuple(placement(f"strawberry {k}", -0.4 + 0.05 * k, 0.2, "circle", (0.035, 0.035))
                 for k in range(1, 17))
    path = tmp_path / "long.png"
    draw_arrangement(Arrangement("please " * 80, Table(), many), path)
    assert imread(path).shape[:2] == (round(FIGSIZE_IN[1] * DPI), round(FIGSIZE_IN[0] * DPI))


def test_overwrites_atomically_and_leaves_no_temporary_file(tmp_path: Path) -> None:
    path = tmp_path / "out.png"
    path.write_bytes(b"old")
    draw(tmp_path, (PLATE,), "out.png")
    assert path.read_bytes()[:4] == b"\x89PNG"
    assert [p.name for p in tmp_path.iterdir()] == ["out.png"]


def test_bad_paths_are_bad_input(tmp_path: Path) -> None:
    with pytest.raises(BadInput, match=r"^image .*out\.jpg: only PNG"):
        draw(tmp_path, (PLATE,), "out.jpg")
    with pytest.raises(BadInput, match=r"^image .*missing.*: cannot write"):
        draw_arrangement(Arrangement(REQUEST, Table(), (PLATE,)),
                         tmp_path / "missing" / "out.png")
    assert not (tmp_path / "missing").exists()


def test_relation_labels_are_the_relations_table_names_shortened() -> None:
    # The labels the pictures had when they were a table of their own.
    before = {"to the left of": "left of", "to the right of": "right of", "above": "above",
              "below": "below", "above and to the left of": "above-left of",
              "above and to the right of": "above-right of",
              "below and to the left of": "below-left of",
              "below and to the right of": "below-right of", "center": "center"}
    assert {name: relation_label(name) for name in before} == before
    assert set(before) <= set(MEANINGS)
    labels = [relation_label(name) for name in MEANINGS]
    assert len(set(labels)) == len(labels)


def _label_boxes(arrangement: Arrangement, size_in: tuple[float, float]) -> list:
    """The pixel boxes of the object names in the picture ``draw_arrangement`` makes."""
    from matplotlib.text import Text

    from llm_grop.render.table import _figure

    fig = _figure(arrangement, None, False, size_in)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    names = {p.name for p in arrangement.placements}
    texts = [t for t in fig.axes[0].findobj(Text) if t.get_text() in names]
    assert len(texts) == len(names)
    return [t.get_bbox_patch().get_window_extent(renderer) for t in texts]


@pytest.mark.parametrize("size", ["desktop", "phone"])
def test_names_of_objects_lying_close_together_stay_apart(size: str) -> None:
    from llm_grop.render.table import PHONE_SIZE_IN

    breads = [placement(f"bread {k}" if k else "bread", -0.05 + 0.035 * k, 0.15 + 0.01 * k,
                        "box", (0.1, 0.06)) for k in range(4)]
    arrangement = Arrangement("breakfast for two", Table(), (PLATE, *breads))
    boxes = _label_boxes(arrangement, PHONE_SIZE_IN if size == "phone" else FIGSIZE_IN)
    overlaps = [(a, b) for i, a in enumerate(boxes) for b in boxes[i + 1:] if a.overlaps(b)]
    assert not overlaps
