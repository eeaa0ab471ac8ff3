"""The colour of each kind of object, shared by every picture: the 2D drawings and the
3D renders. Representation only.

Listed kinds take their colour from ``kind_colors.yaml``; any other kind (one a user's
catalog adds) takes a :data:`PALETTE` colour picked from its name, the same in every run.
"""

from __future__ import annotations

import functools
import zlib
from importlib import resources

import yaml

#: The target table's top in every picture: a light cloth under the kinds' colours.
TABLE_TOP = "#eadcc3"

#: Colours for kinds the list lacks, as ``#rrggbb``.
PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b",
           "#e377c2", "#bcbd22", "#393b79")


@functools.cache
def listed_colors() -> dict[str, str]:
    """The kinds' colours of ``kind_colors.yaml`` (``#rrggbb`` by kind)."""
    text = resources.files("llm_grop.world").joinpath("kind_colors.yaml").read_text("utf-8")
    return {str(k): str(v) for k, v in yaml.safe_load(text).items()}


def kind_color(kind: str) -> str:
    """The colour of ``kind`` in every picture, ``#rrggbb``: listed in
    ``kind_colors.yaml``, else a palette colour picked from its name."""
    listed = listed_colors().get(kind)
    return listed if listed is not None else PALETTE[zlib.crc32(kind.encode()) % len(PALETTE)]


def kind_rgb(kind: str) -> tuple[float, float, float]:
    """:func:`kind_color` as red, green and blue from 0 to 1."""
    return hex_rgb(kind_color(kind))


def hex_rgb(color: str) -> tuple[float, float, float]:
    """``#rrggbb`` as red, green and blue from 0 to 1."""
    h = color.lstrip("#")
    return (int(h[0:2], 16) / 255, int(h[2:4], 16) / 255, int(h[4:6], 16) / 255)
