"""LLM-guided positions: symbolic relations plus the LLM's distances -> object centres (§III-B).

Distances are **gaps between edges**, as in the authors' code: when the LLM says the
fork goes 2 cm to the left of the plate, 2 cm of table show between the fork's right
edge and the plate's left edge. So the subject's centre is the reference's centre
moved by ``gap + ½ extent_subject + ½ extent_reference`` along each axis the relation
moves on, where an extent is the footprint's bounding-box side on that axis.
Diagonal relations move on both axes by the same gap; cardinal ones keep the other
coordinate equal. A relation with no readable distance uses :data:`DEFAULT_GAP_M`.
``on top of`` puts the subject at its support's centre.

The layout hangs off one origin object (:func:`choose_origin`). With the diner's
distance (``edge_gap_m``, from the LLM or a preference) the origin sits in front of
the diner, centred on the diner's line of sight (x = 0), its near edge ``edge_gap_m``
from the table's diner (-y) edge; without it, at the table's centre (0, 0). The relation
graph is walked breadth-first and undirected from it (a
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

Each object but an origin is *anchored* to an object sampled before it (its support,
else its nearest breadth-first ancestor earlier in the sampling order): the sampler
draws it around its anchor's sampled position plus the guided offset, so a stated
gap is kept however far the anchor moved. The sampler's spread (``sigma``) is
:data:`GAP_SIGMA_M` along every axis on which a gap was stated (the gap's direction,
and the origin's distance from the diner) and wider only across it, so that gaps
stay within :data:`~llm_grop.arrangement.fidelity.GAP_TOLERANCE_M` of what was said
while the configurations still differ (mostly by where the whole setting sits).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Collection, Mapping, Sequence

import numpy as np

from llm_grop.arrangement.fit import fit_circle, smallest_shift
from llm_grop.arrangement.layout import (
    DINER_SIGMA_M,
    FREE_SIGMA_M,
    SIGMA_BY_RELATION_M,
    STACK_SIGMA_M,
    GuidedLayout,
    Key,
)
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
    CENTER,
    CONVERSE,
    DIRECTION,
    ON_TOP_OF,
    UNDER,
    Relation,
)
from llm_grop.world.table import Table

#: Gap between edges, in metres, when the LLM gives no readable distance (the authors' 5 cm).
DEFAULT_GAP_M = 0.05

#: Step, in metres, by which a position that overlaps a placed object is pushed outwards.
PUSH_STEP_M = 0.01

#: The most :data:`PUSH_STEP_M` steps one push tries (100 m), whatever the table's size
#: or the LLM's gaps: a bound on the memory a push takes (a few MB).
MAX_PUSH_STEPS = 10_000

def choose_origin(items: Sequence[Item], relations: Sequence[Relation],
                  anchored: Collection[str] = ()) -> str:
    """The subject of the first ``center`` relation, else the first item in ``anchored``
    (objects whose distance from the diner was stated), else the item with the largest
    footprint (ties: the first in ``items``)."""
    if not items:
        raise BadInput("arrangement: no objects to place")
    names = {it.name for it in items}
    for r in relations:
        if r.relation == CENTER and r.subject in names:
            return r.subject
    for it in items:
        if it.name in anchored:
            return it.name
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
        self.parent: dict[str, str | None] = {}

    def component(self, start: str) -> list[str]:
        """Every item the relations connect to ``start``, breadth-first from it."""
        seen, queue = [start], deque([start])
        while queue:
            for q, _, _ in self.adj[queue.popleft()]:
                if q not in seen:
                    seen.append(q)
                    queue.append(q)
        return seen

    def place_from(self, origin: str, at: tuple[float, float] = (0.0, 0.0),
                   sigma: tuple[float, float] = FREE_SIGMA_M) -> list[str]:
        """Lays out ``origin``'s group around ``at``; returns its members in BFS order."""
        self.pos[origin] = at
        self.sigma[origin] = sigma
        self.parent[origin] = None
        order, queue = [origin], deque([origin])
        while queue:
            p = queue.popleft()
            for q, rel, gap in self.adj[p]:
                if q in self.pos:
                    continue
                self.pos[q] = self._position(q, rel, p, gap, order)
                self.parent[q] = p
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
        steps = np.arange(self._push_steps(x, y, fq, (l0, b0, r0, t0)) + 1)
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

    def _push_steps(self, x: float, y: float, fq: Footprint,
                    box: tuple[float, float, float, float]) -> int:
        """How many :data:`PUSH_STEP_M` steps a position ``(x, y)`` (metres) may be pushed:
        a table's size, but never further than it takes to clear ``box``, the placed
        footprints' bounding box (beyond it, footprints inflated by less than twice
        included, nothing can overlap), so the steps tried stay few however large the
        table (at most :data:`MAX_PUSH_STEPS`). The push chosen is the same as with a
        table's size of steps: the first clear step lies within the bound."""
        left, bottom, right, top = box
        clear_m = (right - left) + (top - bottom) + 2 * (fq.hx + fq.hy) \
            + abs(x - (left + right) / 2) + abs(y - (bottom + top) / 2)
        table_m = max(self.table.width, self.table.depth)
        return min(int(min(table_m, clear_m + PUSH_STEP_M) / PUSH_STEP_M), MAX_PUSH_STEPS)

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


def guided_layout(items: Sequence[Item], relations: Sequence[Relation],
                  gaps_m: Mapping[Key, float], table: Table, edge_gap_m: float | None = None,
                  origin: str | None = None) -> GuidedLayout:
    """The LLM-guided position and sampling std dev of every item (see the module doc).

    ``gaps_m`` maps :meth:`Relation.key` to the LLM's gap between edges in metres;
    ``edge_gap_m`` is the origin's distance, metres, from the diner's edge of the table
    (``None``: the origin goes to the table's centre); ``origin`` overrides
    :func:`choose_origin`.
    """
    _validate(items, relations)
    if edge_gap_m is not None and not 0 <= edge_gap_m <= table.depth:
        raise BadInput(f"arrangement: the distance from the diner's edge must lie within the "
                       f"table's depth ({table.depth:g} m), got {edge_gap_m:g} m")
    b = _Builder(items, relations, gaps_m, table)
    origin = origin if origin is not None else choose_origin(items, relations)
    if origin not in b.foot:
        raise BadInput(f"arrangement: the origin {origin!r} is not an object to place")
    if edge_gap_m is None:
        bfs = b.place_from(origin)
    else:
        at_y = -table.depth / 2 + edge_gap_m + b.foot[origin].hy
        bfs = b.place_from(origin, (0.0, at_y), DINER_SIGMA_M)
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
        shift.append(smallest_shift(lo, hi, prefer))
    b.translate(order, shift[0], shift[1])
    if table.is_round:
        fit_circle(b.pos, b.foot, order, table.radius)

    rank = {n: k for k, n in enumerate(order)}
    anchor: dict[str, str | None] = {}
    for name in order:
        up = support[name]
        if up is None:
            up = b.parent.get(name)
            while up is not None and rank[up] > rank[name]:
                up = b.parent.get(up)
        anchor[name] = up
    names = [it.name for it in items]
    return GuidedLayout(
        origin=origin,
        positions={n: b.pos[n] for n in names},
        sigma={n: b.sigma[n] for n in names},
        support={n: support[n] for n in names},
        order=tuple(order),
        anchor={n: anchor[n] for n in names},
        edge_gap_m=edge_gap_m,
    )
