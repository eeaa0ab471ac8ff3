"""LLM-guided positions: symbolic relations plus the LLM's distances -> object centres (§III-B).

Distances are **gaps between edges**, as in the authors' code: when the LLM says the
fork goes 2 cm to the left of the plate, 2 cm of table show between the fork's right
edge and the plate's left edge. So the subject's centre is the reference's centre
moved by ``gap + ½ extent_subject + ½ extent_reference`` along each axis the relation
moves on, where an extent is the footprint's bounding-box side on that axis.
Diagonal relations move on both axes by the same gap; cardinal ones keep the other
coordinate equal. A relation with no readable distance uses :data:`DEFAULT_GAP_M`.
``on top of`` puts the subject at its support's centre.

The layout hangs off one origin object (:func:`choose_origin`) at the table centre
(0, 0): the relation graph is walked breadth-first and undirected from it (a
relation is followed from its reference to its subject as stated, and from its
subject to its reference as its converse). When a new position would overlap an
object already placed, it is pushed further away from its reference in
:data:`PUSH_STEP_M` steps until it is clear (at most a table's size away): along the
relation's direction, or for a diagonal also along just one of its two axes; of these,
the one that keeps the layout's extent within the table's, then the shortest.
Objects no relation connects to the origin form their own groups, each laid out
the same way around its own origin; the groups are spread left to right along a
row just above (+y of) everything placed so far, :data:`DEFAULT_GAP_M` apart.
No place-setting convention is used anywhere: positions follow only the relations.

Finally the whole layout is translated by the smallest shift, per axis, that brings
every footprint inside the table (preferring one that keeps ``center`` objects in
the middle of the table); on an axis where no shift fits, nothing moves.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from llm_grop.arrangement.predicates import (
    CENTER_FRACTION,
    Footprint,
    clear_of,
    rests_on_edges,
    stacked_pairs,
)
from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Item
from llm_grop.world.relation import (
    ABOVE,
    ABOVE_LEFT,
    ABOVE_RIGHT,
    BELOW,
    BELOW_LEFT,
    BELOW_RIGHT,
    CENTER,
    CONVERSE,
    DIRECTION,
    LEFT,
    ON_TOP_OF,
    RIGHT,
    UNDER,
    Relation,
)
from llm_grop.world.table import Table

#: Gap between edges, in metres, when the LLM gives no readable distance (the authors' 5 cm).
DEFAULT_GAP_M = 0.05

#: Step, in metres, by which a position that overlaps a placed object is pushed outwards.
PUSH_STEP_M = 0.01

#: Sampling std dev ``(sx, sy)`` in metres by the relation that placed an object (the
#: authors' values): tight across the direction of a cardinal relation, loose along it.
SIGMA_BY_RELATION_M: Mapping[str, tuple[float, float]] = {
    ABOVE: (0.01, 0.03), BELOW: (0.01, 0.03),
    LEFT: (0.03, 0.01), RIGHT: (0.03, 0.01),
    ABOVE_LEFT: (0.03, 0.03), ABOVE_RIGHT: (0.03, 0.03),
    BELOW_LEFT: (0.03, 0.03), BELOW_RIGHT: (0.03, 0.03),
}

#: Std dev in metres for an origin, a ``center`` object or an unconnected one.
FREE_SIGMA_M = (0.03, 0.03)

#: Std dev in metres for an object resting on another: it follows its support's
#: sampled position almost exactly. (An object placed as the support *under* a
#: placed one takes that object's std dev instead: it carries the stack.)
STACK_SIGMA_M = (0.002, 0.002)

Key = tuple[str, str, str | None]


@dataclass(frozen=True)
class GuidedLayout:
    """LLM-guided positions and the sampler's settings, in the table frame, in metres.

    ``positions``: guided centre ``(x, y)`` per item. ``sigma``: Gaussian std dev
    ``(sx, sy)`` per item. ``support``: what each item rests on (``None``: the table).
    ``order``: the sampling order, the origin first, then breadth-first along the
    relations; a support always comes before what it supports.
    """

    origin: str
    positions: Mapping[str, tuple[float, float]]
    sigma: Mapping[str, tuple[float, float]]
    support: Mapping[str, str | None]
    order: tuple[str, ...]


def choose_origin(items: Sequence[Item], relations: Sequence[Relation]) -> str:
    """The subject of the first ``center`` relation, else the item with the largest
    footprint (ties: the first in ``items``)."""
    if not items:
        raise BadInput("arrangement: no objects to place")
    names = {it.name for it in items}
    for r in relations:
        if r.relation == CENTER and r.subject in names:
            return r.subject
    best = items[0]
    for it in items[1:]:
        if it.spec.area > best.spec.area:
            best = it
    return best.name


def _validate(items: Sequence[Item], relations: Sequence[Relation]) -> None:
    if not items:
        raise BadInput("arrangement: no objects to place")
    names = [it.name for it in items]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise BadInput(f"arrangement: object name {dup!r} is used twice")
    known = set(names)
    for r in relations:
        for name in (r.subject, r.reference):
            if name is not None and name not in known:
                raise BadInput(f"relation {r.sentence()!r}: {name!r} is not an object to place")
        if r.subject == r.reference:
            raise BadInput(f"relation {r.sentence()!r}: an object cannot relate to itself")


def supports_of(items: Sequence[Item], relations: Sequence[Relation]) -> dict[str, str | None]:
    """What each item rests on, from ``on top of``/``under``; the first statement wins and
    one that would close a loop of supports is ignored."""
    support: dict[str, str | None] = {it.name: None for it in items}
    for upper, lower in rests_on_edges(r.key() for r in relations):
        if support[upper] is not None:
            continue
        below: str | None = lower
        while below is not None and below != upper:
            below = support[below]
        if below is None:
            support[upper] = lower
    return support


class _Builder:
    """Mutable state while one layout is computed."""

    def __init__(self, items: Sequence[Item], relations: Sequence[Relation],
                 gaps_m: Mapping[Key, float], table: Table) -> None:
        self.table = table
        self.foot = {it.name: Footprint.of_spec(it.spec) for it in items}
        self.chain = stacked_pairs(rests_on_edges(r.key() for r in relations))
        # adj[p] lists (q, rel, gap): "q rel p" holds, q is gap metres from p, edge to edge.
        self.adj: dict[str, list[tuple[str, str, float]]] = {it.name: [] for it in items}
        for r in relations:
            if r.reference is None:
                continue
            gap = float(gaps_m.get(r.key(), DEFAULT_GAP_M))
            self.adj[r.reference].append((r.subject, r.relation, gap))
            self.adj[r.subject].append((r.reference, CONVERSE[r.relation], gap))
        self.pos: dict[str, tuple[float, float]] = {}
        self.sigma: dict[str, tuple[float, float]] = {}

    def component(self, start: str) -> list[str]:
        """Every item the relations connect to ``start``, breadth-first from it."""
        seen, queue = [start], deque([start])
        while queue:
            for q, _, _ in self.adj[queue.popleft()]:
                if q not in seen:
                    seen.append(q)
                    queue.append(q)
        return seen

    def place_from(self, origin: str) -> list[str]:
        """Lays out ``origin``'s group around (0, 0); returns its members in BFS order."""
        self.pos[origin] = (0.0, 0.0)
        self.sigma[origin] = FREE_SIGMA_M
        order, queue = [origin], deque([origin])
        while queue:
            p = queue.popleft()
            for q, rel, gap in self.adj[p]:
                if q in self.pos:
                    continue
                self.pos[q] = self._position(q, rel, p, gap, order)
                if rel == ON_TOP_OF:
                    self.sigma[q] = STACK_SIGMA_M
                elif rel == UNDER:
                    self.sigma[q] = self.sigma[p]
                else:
                    self.sigma[q] = SIGMA_BY_RELATION_M[rel]
                order.append(q)
                queue.append(q)
        return order

    def _position(self, q: str, rel: str, p: str, gap: float,
                  placed: Sequence[str]) -> tuple[float, float]:
        """Where ``q`` goes so that ``q rel p`` holds ``gap`` metres edge to edge."""
        px, py = self.pos[p]
        if rel in (ON_TOP_OF, UNDER):
            return (px, py)
        dx, dy = DIRECTION[rel]
        fq, fp = self.foot[q], self.foot[p]
        x = px + dx * (gap + fq.hx + fp.hx)
        y = py + dy * (gap + fq.hy + fp.hy)
        others = [o for o in placed if frozenset((o, q)) not in self.chain]
        # A diagonal may also be pushed along one of its axes: it stays strict on both.
        ways = [(dx, dy)] if 0 in (dx, dy) else [(dx, dy), (dx, 0), (0, dy)]
        l0, b0, r0, t0 = self.bbox(placed)
        steps = np.arange(int(max(self.table.width, self.table.depth) / PUSH_STEP_M) + 1)
        best: tuple[float, float] | None = None
        best_score = (math.inf, math.inf)
        for ux, uy in ways:
            cx, cy = x + ux * steps * PUSH_STEP_M, y + uy * steps * PUSH_STEP_M
            clear = np.ones(steps.size, dtype=bool)
            for o in others:
                clear &= clear_of(cx, cy, fq, *self.pos[o], self.foot[o])
            if not clear.any():
                continue
            k = int(clear.argmax())
            # Prefer the push that keeps the layout fitting the table, then the shortest.
            wide = max(r0, cx[k] + fq.hx) - min(l0, cx[k] - fq.hx) - self.table.width
            deep = max(t0, cy[k] + fq.hy) - min(b0, cy[k] - fq.hy) - self.table.depth
            score = (max(wide, 0.0) + max(deep, 0.0), k * math.hypot(ux, uy))
            if score < best_score:
                best, best_score = (float(cx[k]), float(cy[k])), score
        return best if best is not None else (x, y)

    def bbox(self, names: Sequence[str]) -> tuple[float, float, float, float]:
        """``(left, bottom, right, top)`` of the footprints of ``names``."""
        boxes = [(self.pos[n][0] - self.foot[n].hx, self.pos[n][1] - self.foot[n].hy,
                  self.pos[n][0] + self.foot[n].hx, self.pos[n][1] + self.foot[n].hy)
                 for n in names]
        return (min(b[0] for b in boxes), min(b[1] for b in boxes),
                max(b[2] for b in boxes), max(b[3] for b in boxes))

    def translate(self, names: Sequence[str], dx: float, dy: float) -> None:
        for n in names:
            x, y = self.pos[n]
            self.pos[n] = (x + dx, y + dy)


def _smallest_shift(lo: float, hi: float, prefer: tuple[float, float] | None) -> float:
    """The shift nearest 0 within ``[lo, hi]`` (and within ``prefer`` if they meet)."""
    if lo > hi:
        return 0.0
    if prefer is not None and max(lo, prefer[0]) <= min(hi, prefer[1]):
        lo, hi = max(lo, prefer[0]), min(hi, prefer[1])
    return min(max(0.0, lo), hi)


def guided_layout(items: Sequence[Item], relations: Sequence[Relation],
                  gaps_m: Mapping[Key, float], table: Table) -> GuidedLayout:
    """The LLM-guided position and sampling std dev of every item (see the module doc).

    ``gaps_m`` maps :meth:`Relation.key` to the LLM's gap between edges in metres.
    """
    _validate(items, relations)
    b = _Builder(items, relations, gaps_m, table)
    origin = choose_origin(items, relations)
    bfs = b.place_from(origin)
    main = list(bfs)
    groups: list[list[str]] = []
    for it in items:
        if it.name in b.pos:
            continue
        members = set(b.component(it.name))
        sub_items = [x for x in items if x.name in members]
        sub_rels = [r for r in relations if r.subject in members]
        groups.append(b.place_from(choose_origin(sub_items, sub_rels)))
        bfs += groups[-1]
    if groups:
        row_bottom = b.bbox(main)[3] + DEFAULT_GAP_M
        widths = [b.bbox(g)[2] - b.bbox(g)[0] for g in groups]
        left = -(sum(widths) + DEFAULT_GAP_M * (len(groups) - 1)) / 2
        for g, w in zip(groups, widths, strict=True):
            gl, gb, _, _ = b.bbox(g)
            b.translate(g, left - gl, row_bottom - gb)
            left += w + DEFAULT_GAP_M

    support = supports_of(items, relations)
    order: list[str] = []

    def emit(name: str) -> None:
        if name in order:
            return
        below = support[name]
        if below is not None:
            emit(below)
            b.pos[name] = b.pos[below]
            b.sigma[name] = STACK_SIGMA_M
        order.append(name)

    for name in bfs:
        emit(name)

    centred = [r.subject for r in relations if r.relation == CENTER]
    shift = []
    for axis, half in ((0, table.width / 2), (1, table.depth / 2)):
        ext = [b.foot[n].hx if axis == 0 else b.foot[n].hy for n in order]
        lo = max(-half + e - b.pos[n][axis] for n, e in zip(order, ext, strict=True))
        hi = min(half - e - b.pos[n][axis] for n, e in zip(order, ext, strict=True))
        prefer = None
        if centred:
            limit = CENTER_FRACTION * 2 * half
            prefer = (max(-limit - b.pos[n][axis] for n in centred),
                      min(limit - b.pos[n][axis] for n in centred))
        shift.append(_smallest_shift(lo, hi, prefer))
    b.translate(order, shift[0], shift[1])

    names = [it.name for it in items]
    return GuidedLayout(
        origin=origin,
        positions={n: b.pos[n] for n in names},
        sigma={n: b.sigma[n] for n in names},
        support={n: support[n] for n in names},
        order=tuple(order),
    )
