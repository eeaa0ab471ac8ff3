"""Every picture colours an object by its kind, the same colour whatever shares the table."""

from __future__ import annotations

from matplotlib.colors import is_color_like

from llm_grop.render.table import kind_color, kind_colors
from llm_grop.world.catalog import Catalog
from scenes import placement


def test_every_catalog_kind_has_its_own_listed_colour() -> None:
    names = Catalog.load().names()
    colors = [kind_color(n) for n in names]
    assert all(is_color_like(c) for c in colors)
    assert len(set(colors)) == len(names)


def test_a_kind_keeps_its_colour_whatever_shares_the_picture() -> None:
    alone = kind_colors([placement("mug", 0.0, 0.0)])
    crowded = kind_colors([placement("dinner plate", 0.0, 0.0), placement("bread", 0.1, 0.0),
                           placement("mug", 0.2, 0.0)])
    assert alone["mug"] == crowded["mug"] == kind_color("mug")


def test_a_kind_the_list_lacks_gets_the_same_palette_colour_every_time() -> None:
    assert kind_color("teapot") == kind_color("teapot")
    assert is_color_like(kind_color("teapot"))
