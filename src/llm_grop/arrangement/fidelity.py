"""Fidelity: how far a configuration realises the gaps and the diner's distance that were
stated (by the LLM or by the user's preferences).

A relation's realised gap is measured the way the layout sets it
(:mod:`llm_grop.arrangement.geometry`): between the footprints' bounding boxes, along each
axis the relation moves on (x for ``to the left of``, both for a diagonal). For a
diagonal the axis whose gap is farther from the stated one counts, so
``realised - stated`` is the worst error. The diner's distance is the gap between the
table's diner (-y) edge and the origin object's near edge. Lengths in metres.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from llm_grop.arrangement.layout import GuidedLayout, Key
from llm_grop.arrangement.predicates import Footprint
from llm_grop.world.arrangement import Configuration
from llm_grop.world.fidelity import GAP_TOLERANCE_M as GAP_TOLERANCE_M
from llm_grop.world.fidelity import Fidelity, GapFidelity
from llm_grop.world.relation import CENTER, DIRECTION, STACKING, Relation
from llm_grop.world.table import Table

Floats = NDArray[np.float64]


def has_gap(relation: Relation) -> bool:
    """Whether ``relation`` states a gap (every relation but ``center`` and stacking)."""
    return relation.relation != CENTER and relation.relation not in STACKING \
        and relation.reference is not None


def axis_gaps_m(relation: str, xs: ArrayLike, ys: ArrayLike, fs: Footprint, xr: ArrayLike,
                yr: ArrayLike, fr: Footprint) -> list[Floats]:
    """The gap, metres, on each axis ``relation`` moves on (x, then y; both for a diagonal):
    the distance between the bounding boxes' facing edges, negative where they overlap on
    that axis (arrays broadcast)."""
    dx, dy = DIRECTION[relation]
    gaps = []
    if dx:
        gaps.append(np.asarray(dx * np.subtract(xs, xr) - fs.hx - fr.hx, dtype=float))
    if dy:
        gaps.append(np.asarray(dy * np.subtract(ys, yr) - fs.hy - fr.hy, dtype=float))
    return gaps


def realised_gap_m(relation: str, stated_m: float, xs: ArrayLike, ys: ArrayLike,
                   fs: Footprint, xr: ArrayLike, yr: ArrayLike, fr: Footprint) -> Floats:
    """The gap ``subject relation reference`` realises with the subject at ``(xs, ys)`` and
    the reference at ``(xr, yr)`` (arrays broadcast): on each axis the relation moves on,
    the distance between the bounding boxes' facing edges; of two axes, the one farther
    from ``stated_m``."""
    gaps = axis_gaps_m(relation, xs, ys, fs, xr, yr, fr)
    if len(gaps) == 1:
        return np.asarray(gaps[0], dtype=float)
    gx, gy = np.broadcast_arrays(*gaps)
    return np.where(np.abs(gx - stated_m) >= np.abs(gy - stated_m), gx, gy).astype(float)


def edge_gap_m(y: ArrayLike, f: Footprint, table: Table) -> Floats:
    """The gap, metres, between the table's diner (-y) edge and a footprint at ``y``."""
    return np.asarray(np.subtract(y, f.hy) + table.depth / 2, dtype=float)


def measure(config: Configuration, relations: Sequence[Relation], gaps_m: Mapping[Key, float],
            layout: GuidedLayout, table: Table) -> Fidelity:
    """How faithfully ``config`` realises the stated ``gaps_m`` and the layout's diner distance."""
    places = config.by_name()
    foot = {n: Footprint.of_placement(p) for n, p in places.items()}
    out = []
    for r in relations:
        if not has_gap(r) or r.key() not in gaps_m or r.reference is None:
            continue
        s, ref = places.get(r.subject), places.get(r.reference)
        if s is None or ref is None:
            continue
        stated = gaps_m[r.key()]
        got = realised_gap_m(r.relation, stated, s.x, s.y, foot[r.subject], ref.x, ref.y,
                             foot[r.reference])
        out.append(GapFidelity(r.subject, r.relation, r.reference, stated, float(got)))
    origin = places.get(layout.origin)
    if origin is None:
        return Fidelity(tuple(out))
    gx, gy = layout.positions[layout.origin]
    shift = float(np.hypot(origin.x - gx, origin.y - gy))
    edge = None if layout.edge_gap_m is None else \
        float(edge_gap_m(origin.y, foot[layout.origin], table))
    return Fidelity(tuple(out), layout.origin, shift, layout.edge_gap_m, edge)
