"""Each diner's place at the table: the part of the top that is theirs, in their own frame.

A diner's **place** is the part of the table top nearer their seat than any other seat
(the seats' Voronoi cell clipped to the top), trimmed to a box symmetric about the
diner's line of sight. Its **frame** is the contract's table frame as that diner sees it:
+y the way they face, +x to their right, the origin on their line of sight at the middle
of the place's depth. A single diner at the -y edge (the contract's default) has the
whole table as place and the table frame as frame, so one-diner arrangements are exactly
what they always were. Settings are arranged, sampled and rated in the place frame; the
plan and the JSON use the table frame. Lengths in metres, angles in radians.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely import affinity
from shapely.geometry import Point, Polygon
from shapely.geometry import box as rect

from llm_grop.errors import BadInput
from llm_grop.world.angles import wrap_angle
from llm_grop.world.seat import Seat
from llm_grop.world.table import Table

Bools = NDArray[np.bool_]

#: Segments per quarter circle of a round top's outline.
_QUAD_SEGS = 32
#: A seat this far (metres) inside the top's outline still counts as at its edge.
_EDGE_TOL_M = 1e-3


def outline(table: Table) -> Polygon:
    """The table top's outline in the table frame."""
    if table.shape == "circle":
        return Point(0.0, 0.0).buffer(table.width / 2, quad_segs=_QUAD_SEGS)
    return rect(-table.width / 2, -table.depth / 2, table.width / 2, table.depth / 2)


def default_seats(table: Table, n: int) -> tuple[Seat, ...]:
    """``n`` seats round ``table``: a round top's evenly spaced, the first at -y; a
    rectangle's along its two long sides, the first (-y, or -x when deeper than wide)
    taking the odd one, evenly spaced along each side, facing across."""
    if n < 1:
        raise BadInput(f"diners: expected at least 1, got {n}")
    if table.shape == "circle":
        r = table.width / 2
        out = []
        for k in range(n):
            a = -math.pi / 2 + 2 * math.pi * k / n
            out.append(Seat(r * math.cos(a), r * math.sin(a), wrap_angle(a + math.pi)))
        return tuple(out)
    front = (n + 1) // 2
    back = n - front
    along, across = (table.width, table.depth) if table.width >= table.depth else \
        (table.depth, table.width)
    seats = []
    for count, sign in ((front, -1), (back, 1)):
        for k in range(count):
            u = -along / 2 + (k + 0.5) * along / count
            # Facing across the table: the far diner's left is the near diner's right.
            u = u if sign < 0 else 0.0 - u
            if table.width >= table.depth:
                seats.append(Seat(u, sign * across / 2, -sign * math.pi / 2))
            else:
                seats.append(Seat(sign * across / 2, -u, math.pi if sign > 0 else 0.0))
    return tuple(seats)


def check_seats(table: Table, seats: Sequence[Seat]) -> None:
    """:class:`BadInput` for a seat inside the top or one whose diner faces away from it."""
    Table(table.width, table.depth, table.shape, tuple(seats))  # a seat inside the top
    top = outline(table)
    for k, s in enumerate(seats):
        c, si = math.cos(s.yaw), math.sin(s.yaw)
        ray = [(s.x + _EDGE_TOL_M * c, s.y + _EDGE_TOL_M * si), (s.x + 10 * c, s.y + 10 * si)]
        if not shapely.LineString(ray).intersects(top):
            raise BadInput(f"table: diner {k} at ({s.x:+.2f}, {s.y:+.2f}) m faces away from "
                           f"the {table.label}")
    for k, s in enumerate(seats):
        for j in range(k):
            if math.hypot(s.x - seats[j].x, s.y - seats[j].y) < _EDGE_TOL_M:
                raise BadInput(f"table: diners {j} and {k} share the seat at "
                               f"({s.x:+.2f}, {s.y:+.2f}) m")


@dataclass(frozen=True)
class Place:
    """One diner's place: ``origin`` ``(x, y)`` and ``yaw`` of its frame in the table frame
    (a place-frame point ``p`` is ``origin + R(yaw) p`` in the table frame); ``box``, the
    place's extent as a table centred on the frame's origin; ``region``, the place's exact
    outline in its frame (``None``: the whole ``box`` is the place)."""

    origin: tuple[float, float]
    yaw: float
    box: Table
    region: Polygon | None = None

    def to_table(self, x: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """Place-frame points in the table frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        return (self.origin[0] + c * x - s * y, self.origin[1] + s * x + c * y)

    def to_place(self, x: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """Table-frame points in the place frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        dx = np.asarray(x, dtype=float) - self.origin[0]
        dy = np.asarray(y, dtype=float) - self.origin[1]
        return (c * dx + s * dy, -s * dx + c * dy)


def places(table: Table, seats: Sequence[Seat]) -> tuple[Place, ...]:
    """Every diner's place at ``table`` (see the module doc)."""
    check_seats(table, seats)
    if len(seats) == 1 and math.isclose(seats[0].x, 0.0, abs_tol=1e-9) \
            and math.isclose(seats[0].yaw, math.pi / 2, abs_tol=1e-9):
        return (Place((0.0, 0.0), 0.0, table),)
    top = outline(table)
    big = 4 * max(table.width, table.depth)
    out = []
    for k, s in enumerate(seats):
        cell = top
        for j, o in enumerate(seats):
            if j == k:
                continue
            cell = cell.intersection(_closer_half_plane((s.x, s.y), (o.x, o.y), big))
        frame_yaw = s.yaw - math.pi / 2
        # The place frame before choosing its origin: the seat at x = 0.
        local = affinity.rotate(affinity.translate(cell, -s.x, -s.y), -frame_yaw,
                                origin=(0.0, 0.0), use_radians=True)
        x0, y0, x1, y1 = local.bounds
        half = min(-x0, x1)
        if half <= 0 or y1 <= y0:
            raise BadInput(f"table: diner {k}'s place at the {table.label} is empty")
        mid = (y0 + y1) / 2
        region = affinity.translate(local, 0.0, -mid).intersection(
            rect(-half, -(y1 - y0) / 2, half, (y1 - y0) / 2))
        c, si = math.cos(frame_yaw), math.sin(frame_yaw)
        origin = (s.x - si * mid, s.y + c * mid)
        out.append(Place(origin, frame_yaw, Table(2 * half, y1 - y0), region))
    return tuple(out)


def _closer_half_plane(me: tuple[float, float], other: tuple[float, float],
                       big: float) -> Polygon:
    """The points nearer ``me`` than ``other``, within ``big`` metres of ``me``."""
    mx, my = (me[0] + other[0]) / 2, (me[1] + other[1]) / 2
    nx, ny = other[0] - me[0], other[1] - me[1]
    norm = math.hypot(nx, ny)
    nx, ny = nx / norm, ny / norm
    tx, ty = -ny, nx
    return Polygon([(mx + tx * big, my + ty * big), (mx - tx * big, my - ty * big),
                    (mx - tx * big - nx * big, my - ty * big - ny * big),
                    (mx + tx * big - nx * big, my + ty * big - ny * big)])


@functools.lru_cache(maxsize=256)
def _eroded(region: Polygon, by: float) -> Polygon:
    return region.buffer(-by, quad_segs=8) if by > 0 else region


def inside_region(x: ArrayLike, y: ArrayLike, hx: float, hy: float, circle: bool,
                  region: Polygon, margin: float = 0.0) -> Bools:
    """Whether a footprint (a circle of radius ``hx``, else a box of half sides ``hx``,
    ``hy``) centred at ``(x, y)`` lies in the convex ``region`` with ``margin`` to spare."""
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    if circle:
        return shapely.contains_xy(_eroded(region, hx + margin), x, y)
    inner = _eroded(region, margin)
    ok = np.ones(x.shape, dtype=bool)
    for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        ok &= shapely.contains_xy(inner, x + sx * hx, y + sy * hy)
    return ok

