"""The geometric meaning of the symbolic relations, and the feasibility rules (paper §III-B).

Shared by the sampler (vectorised over arrays of candidate positions, shape ``(K,)``
or ``(M, K)``), by :func:`llm_grop.arrangement.sampling.violations` and by tests.
Positions are object centres in the table frame (origin at the table-top centre,
+x to the diner's right, +y away from the diner), in metres.

Relations, for a subject X and a reference Y with half extents ``hx``, ``hy`` (half
the footprint's axis-aligned bounding box; a circle's radius). What each relation means
is the relations table (``world/relations.yaml``, read as
:data:`~llm_grop.world.relation.MEANINGS`): the subject's state against the reference on
each axis, one of three, the same ones the ASP encoding uses. Here each state gets its
tolerance:

* aligned: ``|x_X - x_Y| <= max(hx_X, hx_Y)`` (one centre lies within the other's span);
* less:    ``x_X < x_Y - max(hx_X, hx_Y)``;
* greater: ``x_X > x_Y + max(hx_X, hx_Y)``;

and the same on y with ``hy``. So ``to the left of`` (x less, y aligned) holds when X's
centre is left of Y's by more than the larger half width of the two, and the centres are
no further apart in y than the larger half depth.
A stacking relation, where the table says one object rests on the other, holds when the
upper's centre lies within the lower's footprint (which implies aligned on both axes, as
the table demands): ``on top of`` (X, Y) is X on Y, ``under`` (X, Y) is Y on X.
``center`` (X): X's centre lies in the middle half of the table on both axes,
``|x| <= CENTER_FRACTION * width`` and ``|y| <= CENTER_FRACTION * depth``.

Feasibility: every footprint's bounding box lies inside the table, and no two
footprints overlap, comparing true shapes (circle-circle by centre distance,
box-box by bounding boxes, circle-box by clamped distance) inflated by
``INFLATION`` as the authors did; touching is allowed. Pairs in one stacking chain
(one rests on the other, directly or through others) are exempt: they are meant
to overlap.

Every test takes a ``margin`` in metres (default 0) that makes it stricter by that
much; the sampler accepts with a small positive margin so that its results still
pass the exact (margin 0) checks after a round trip through text.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from llm_grop.world.arrangement import Placement
from llm_grop.world.catalog import ObjectSpec
from llm_grop.world.relation import CENTER, MEANINGS, AxisState
from llm_grop.world.table import Table

#: ``center`` holds within this fraction of the table's width (depth) either side of
#: the centre along x (y): 1/4, i.e. the middle half of the table on each axis.
CENTER_FRACTION = 0.25

#: Footprints are scaled by this factor for the overlap test (the authors' 5 %).
INFLATION = 1.05

Bools = NDArray[np.bool_]


@dataclass(frozen=True)
class Footprint:
    """An object's footprint at yaw 0: ``shape`` and half extents ``hx``, ``hy`` in metres.

    For a circle ``hx == hy`` is the radius; for a box they are half its sides.
    """

    shape: Literal["circle", "box"]
    hx: float
    hy: float

    @classmethod
    def of_spec(cls, spec: ObjectSpec) -> Footprint:
        """The footprint of a catalog kind, unrotated."""
        return cls(spec.shape, spec.size[0] / 2, spec.size[1] / 2)

    @classmethod
    def of_placement(cls, p: Placement) -> Footprint:
        """The footprint of a placed object; a rotated box becomes its bounding box."""
        sx, sy = p.size
        if p.shape == "circle" or p.yaw == 0.0:
            return cls(p.shape, sx / 2, sy / 2)
        c, s = abs(math.cos(p.yaw)), abs(math.sin(p.yaw))
        return cls("box", (c * sx + s * sy) / 2, (s * sx + c * sy) / 2)

    @property
    def area(self) -> float:
        """Footprint area in square metres."""
        return math.pi * self.hx * self.hx if self.shape == "circle" else 4 * self.hx * self.hy


def _axis_ok(state: AxisState, a: ArrayLike, b: ArrayLike, half: float,
             margin: float) -> Bools:
    """Whether ``a`` is in ``state`` (less, aligned or greater) against ``b`` on one axis,
    ``half`` metres being the larger half extent of the two."""
    d = np.subtract(a, b)
    if state == "aligned":
        return np.abs(d) <= half - margin
    if state == "less":
        return d < -(half + margin)
    return d > half + margin


def centre_within(x: ArrayLike, y: ArrayLike, fx: ArrayLike, fy: ArrayLike, f: Footprint,
                  margin: float = 0.0) -> Bools:
    """Whether the point ``(x, y)`` lies within footprint ``f`` centred at ``(fx, fy)``."""
    dx, dy = np.subtract(x, fx), np.subtract(y, fy)
    if f.shape == "circle":
        reach = max(f.hx - margin, 0.0)
        return dx * dx + dy * dy <= reach * reach
    return (np.abs(dx) <= f.hx - margin) & (np.abs(dy) <= f.hy - margin)


def pair_relation_holds(relation: str, xs: ArrayLike, ys: ArrayLike, fs: Footprint,
                        xr: ArrayLike, yr: ArrayLike, fr: Footprint,
                        margin: float = 0.0) -> Bools:
    """Whether ``subject relation reference`` holds for subject at ``(xs, ys)``.

    ``relation`` is any relation name but ``center``; arrays broadcast.
    """
    meaning = MEANINGS.get(relation)
    if meaning is None or not meaning.reference:
        raise ValueError(f"{relation!r} is not a relation between two objects")
    # Resting is the stronger test: the table makes a resting pair aligned on both axes,
    # and a centre within the lower footprint is within the pair's larger half extents.
    if meaning.rests == "subject":
        return centre_within(xs, ys, xr, yr, fr, margin)
    if meaning.rests == "reference":
        return centre_within(xr, yr, xs, ys, fs, margin)
    return (_axis_ok(meaning.state("x"), xs, xr, max(fs.hx, fr.hx), margin)
            & _axis_ok(meaning.state("y"), ys, yr, max(fs.hy, fr.hy), margin))


def in_center(x: ArrayLike, y: ArrayLike, table: Table, margin: float = 0.0) -> Bools:
    """Whether ``center`` holds for an object centred at ``(x, y)``.

    On a round table of diameter ``D`` the middle is a disc: the centre lies within
    ``CENTER_FRACTION * D`` metres of the table's centre (half the radius).
    """
    if table.is_round:
        reach = CENTER_FRACTION * table.width - margin
        return _within_radius(x, y, reach)
    return ((np.abs(x) <= CENTER_FRACTION * table.width - margin)
            & (np.abs(y) <= CENTER_FRACTION * table.depth - margin))


def inside_table(x: ArrayLike, y: ArrayLike, f: Footprint, table: Table,
                 margin: float = 0.0) -> Bools:
    """Whether footprint ``f`` centred at ``(x, y)`` lies on the table top.

    On a round table a circular footprint must lie within the top's radius, and a box's
    bounding box must have all four corners within it (its farthest corner decides).
    """
    if table.is_round:
        if f.shape == "circle":
            return _within_radius(x, y, table.radius - f.hx - margin)
        return _within_radius(np.abs(x) + f.hx, np.abs(y) + f.hy, table.radius - margin)
    return ((np.abs(x) <= table.width / 2 - f.hx - margin)
            & (np.abs(y) <= table.depth / 2 - f.hy - margin))


def _within_radius(x: ArrayLike, y: ArrayLike, reach: float) -> Bools:
    """Whether each point ``(x, y)`` lies within ``reach`` metres of the origin (none does
    for a negative ``reach``)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if reach < 0:
        return np.zeros(np.broadcast(x, y).shape, dtype=bool)
    return x * x + y * y <= reach * reach


def clear_of(x1: ArrayLike, y1: ArrayLike, f1: Footprint, x2: ArrayLike, y2: ArrayLike,
             f2: Footprint, margin: float = 0.0) -> Bools:
    """Whether two footprints, inflated by :data:`INFLATION`, do not overlap.

    Touching counts as clear; ``margin`` demands that much clearance in addition.
    """
    dx, dy = np.abs(np.subtract(x1, x2)), np.abs(np.subtract(y1, y2))
    if f1.shape == "circle" and f2.shape == "circle":
        reach = INFLATION * (f1.hx + f2.hx) + margin
        return dx * dx + dy * dy >= reach * reach
    if f1.shape == "box" and f2.shape == "box":
        return ((dx >= INFLATION * (f1.hx + f2.hx) + margin)
                | (dy >= INFLATION * (f1.hy + f2.hy) + margin))
    circle, box = (f1, f2) if f1.shape == "circle" else (f2, f1)
    # Distance from the circle's centre to the nearest point of the box.
    ex = np.maximum(dx - INFLATION * box.hx, 0.0)
    ey = np.maximum(dy - INFLATION * box.hy, 0.0)
    reach = INFLATION * circle.hx + margin
    return ex * ex + ey * ey >= reach * reach


def rests_on_edges(relations: Iterable[tuple[str, str, str | None]]) -> list[tuple[str, str]]:
    """``(upper, lower)`` pairs stated by stacking relation keys ``(subject, relation, ref)``."""
    edges = []
    for subject, relation, reference in relations:
        meaning = MEANINGS.get(relation)
        if meaning is None or meaning.rests is None or reference is None:
            continue
        edges.append((subject, reference) if meaning.rests == "subject"
                     else (reference, subject))
    return edges


def stacked_pairs(edges: Iterable[tuple[str, str]]) -> frozenset[frozenset[str]]:
    """Pairs in one stacking chain: one rests on the other, directly or transitively.

    ``edges`` are ``(upper, lower)`` pairs (X on Y).
    """
    below: dict[str, set[str]] = {}
    for upper, lower in edges:
        below.setdefault(upper, set()).add(lower)
    pairs: set[frozenset[str]] = set()
    for start in below:
        seen: set[str] = set()
        todo = list(below[start])
        while todo:
            lower = todo.pop()
            if lower in seen:
                continue
            seen.add(lower)
            todo += below.get(lower, ())
        pairs |= {frozenset((start, lower)) for lower in seen if lower != start}
    return frozenset(pairs)


def describe_failure(subject: str, relation: str, reference: str | None) -> str:
    """The reason a relation check fails, in words: ``dinner fork is not to the left of ...``."""
    if relation == CENTER:
        return f"{subject} is not in the center of the table"
    return f"{subject} is not {relation} {reference}"
