"""The sampler's tests of candidate positions (:mod:`llm_grop.arrangement.sampling`).

Each :class:`Check` tests a batch of candidates for one object, shape ``(A, K)``, against
the positions already sampled in their configurations; lengths in metres, table frame
(or a diner's place frame). Every test is stricter than the exact predicates by
:data:`SAMPLE_MARGIN_M`, so that results pass them after rounding.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from shapely.geometry import Polygon

from llm_grop.arrangement.fidelity import edge_gap_m, realised_gap_m
from llm_grop.arrangement.predicates import (
    Footprint,
    clear_of,
    describe_failure,
    in_center,
    pair_relation_holds,
)
from llm_grop.geometry.places import inside_region
from llm_grop.world.relation import CENTER
from llm_grop.world.table import Table

#: Stricter-by margin in metres for accepting a candidate, so that results pass the
#: exact checks of :func:`~llm_grop.arrangement.sampling.violations` even after rounding
#: to 0.1 mm.
SAMPLE_MARGIN_M = 1e-4

Floats = NDArray[np.float64]
Bools = NDArray[np.bool_]
#: ``test(cx, cy, X, Y, rows)``: candidate x, y ``(A, K)``; positions so far ``(n, N)``;
#: the configurations ``rows`` ``(A,)`` the candidates belong to -> accepted ``(A, K)``.
Test = Callable[[Floats, Floats, Floats, Floats, NDArray[np.intp]], Bools]


@dataclass(frozen=True)
class Check:
    """One test of the sampler's candidates, and the reason it gives when it rejects."""

    reason: str
    test: Test


def pair_check(rel: str, subject: str, reference: str, cols: dict[str, int],
                foot: dict[str, Footprint], new: str) -> Check:
    """A check of ``subject rel reference`` when ``new`` (one of the two) is the candidate."""
    fs, fr = foot[subject], foot[reference]
    if new == subject:
        o = cols[reference]

        def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
            return pair_relation_holds(rel, cx, cy, fs, X[rows, o, None], Y[rows, o, None], fr,
                                       SAMPLE_MARGIN_M)
    else:
        o = cols[subject]

        def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
            return pair_relation_holds(rel, X[rows, o, None], Y[rows, o, None], fs, cx, cy, fr,
                                       SAMPLE_MARGIN_M)
    return Check(describe_failure(subject, rel, reference), test)


def clear_check(name: str, other: str, cols: dict[str, int],
                 foot: dict[str, Footprint]) -> Check:
    o, f, fo = cols[other], foot[name], foot[other]

    def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
        return clear_of(cx, cy, f, X[rows, o, None], Y[rows, o, None], fo, SAMPLE_MARGIN_M)
    return Check(f"{name} overlaps {other}", test)


def gap_check(rel: str, subject: str, reference: str, stated: float, tol: float,
               cols: dict[str, int], foot: dict[str, Footprint], new: str) -> Check:
    """A check that ``subject rel reference`` realises ``stated`` metres within ``tol``."""
    fs, fr = foot[subject], foot[reference]
    limit = tol - SAMPLE_MARGIN_M
    if new == subject:
        o = cols[reference]

        def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
            got = realised_gap_m(rel, stated, cx, cy, fs, X[rows, o, None], Y[rows, o, None], fr)
            return np.abs(got - stated) <= limit
    else:
        o = cols[subject]

        def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
            got = realised_gap_m(rel, stated, X[rows, o, None], Y[rows, o, None], fs, cx, cy, fr)
            return np.abs(got - stated) <= limit
    return Check(f"the gap of {subject} {rel} {reference} strays more than "
                  f"{100 * tol:g} cm from the stated {100 * stated:g} cm", test)


def edge_check(name: str, f: Footprint, stated: float, tol: float, table: Table) -> Check:
    """A check that ``name`` lies ``stated`` metres (within ``tol``) from the diner's edge."""
    def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
        return np.abs(edge_gap_m(cy, f, table) - stated) <= tol - SAMPLE_MARGIN_M
    return Check(f"{name} strays more than {100 * tol:g} cm from the stated {100 * stated:g} "
                  "cm from the diner's edge", test)


def region_check(name: str, f: Footprint, region: Polygon) -> Check:
    """A check that ``name`` lies wholly in its diner's place ``region``."""
    def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
        return inside_region(cx, cy, f.hx, f.hy, f.shape == "circle", region, SAMPLE_MARGIN_M)
    return Check(f"{name} leaves its diner's place", test)


def center_check(name: str, table: Table) -> Check:
    def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
        return in_center(cx, cy, table, SAMPLE_MARGIN_M)
    return Check(describe_failure(name, CENTER, None), test)
