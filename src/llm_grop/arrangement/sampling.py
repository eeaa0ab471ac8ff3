"""The adaptive 2D Gaussian rejection sampler (paper §III-B).

Objects are sampled one at a time in the layout's order. For an object, every
unfinished configuration draws ``batch`` candidates from N(guided position,
diag(sigma²)) at once (arrays of shape ``(configurations, batch)``); a candidate is
rejected when it breaks an accepted relation with an object already placed in its
configuration (``center`` included), overlaps one (stacking chains excepted),
leaves the table, or (with a tolerance) realises a stated gap or the diner's distance
more than the tolerance away from what was said (:mod:`llm_grop.arrangement.fidelity`).
Each configuration keeps its first surviving candidate. An object is drawn around its
anchor's *sampled* position plus its guided offset (see
:class:`~llm_grop.arrangement.layout.GuidedLayout`), so that the gap to the object it
was laid out from holds wherever that one landed; an origin is drawn around its guided
position.

Adaptive: a configuration with no surviving candidate draws again with sigma
widened by :data:`WIDEN_FACTOR` (capped at half the table), up to
:data:`WIDEN_STEPS` draws; a configuration still stuck starts over from its first
object in the next round. Each round starts every sigma :data:`ROUND_WIDEN` times
wider than the last, so that when the guided positions lead nowhere (say, two
objects pushed side by side where only one above the other leaves room for a third)
later rounds search the table more broadly.

Unlike the authors' code, every returned configuration satisfies every accepted
relation: :func:`violations` is empty for each.
"""

from __future__ import annotations

import math
from collections import Counter, defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from shapely.geometry import Polygon

from llm_grop.arrangement.fidelity import (
    GAP_TOLERANCE_M,
    edge_gap_m,
    has_gap,
    realised_gap_m,
)
from llm_grop.arrangement.layout import GuidedLayout, Key
from llm_grop.arrangement.predicates import (
    Footprint,
    clear_of,
    describe_failure,
    in_center,
    inside_table,
    pair_relation_holds,
    rests_on_edges,
    stacked_pairs,
)
from llm_grop.arrangement.sampler_checks import (
    SAMPLE_MARGIN_M,
    Check,
    center_check,
    clear_check,
    edge_check,
    gap_check,
    pair_check,
    region_check,
)
from llm_grop.errors import BadInput, Infeasible, NoArrangement
from llm_grop.geometry.places import inside_region
from llm_grop.settings import DEFAULTS
from llm_grop.world.arrangement import Configuration, Item, Placement
from llm_grop.world.relation import Relation
from llm_grop.world.table import Table

#: Each sigma is multiplied by this after a draw in which nothing survived.
WIDEN_FACTOR = 1.5

#: Draws per object before a configuration gives up and starts over.
WIDEN_STEPS = 8

#: Candidates drawn per configuration at first; each further chunk doubles (up to ``batch``).
FIRST_CHUNK = 32

#: Each round's sigmas are this many times the previous round's.
ROUND_WIDEN = 1.25

#: Rounds (a fresh start of the unfinished configurations) before giving up.
DEFAULT_MAX_ROUNDS = 40


Floats = NDArray[np.float64]
Bools = NDArray[np.bool_]


@dataclass(frozen=True)
class _Step:
    """How one object is sampled: its column, mean (an offset from the anchor's sampled
    position, or absolute without an anchor), std dev and checks."""

    name: str
    col: int
    foot: Footprint
    mean: tuple[float, float]
    sigma: tuple[float, float]
    anchor: int  # column of the anchor, -1 for none
    checks: tuple[Check, ...]


def realisable(layout: GuidedLayout, relation: Relation, stated: float, items: Sequence[Item],
               tol: float = GAP_TOLERANCE_M) -> bool:
    """Whether the guided layout itself keeps ``relation``'s stated gap within ``tol``
    (the other relations may have pushed the pair apart)."""
    if relation.reference is None:
        return False
    foot = {it.name: Footprint.of_spec(it.spec) for it in items}
    xs, ys = layout.positions[relation.subject]
    xr, yr = layout.positions[relation.reference]
    got = realised_gap_m(relation.relation, stated, xs, ys, foot[relation.subject], xr, yr,
                         foot[relation.reference])
    return bool(abs(float(got) - stated) <= tol)


def _plan(items: Sequence[Item], layout: GuidedLayout, relations: Sequence[Relation],
          table: Table, gaps_m: Mapping[Key, float] | None = None,
          tolerance_m: float | None = None, region: Polygon | None = None) -> list[_Step]:
    names = [it.name for it in items]
    if sorted(layout.order) != sorted(names):
        raise BadInput("sampler: the guided layout does not cover exactly the objects to place")
    cols = {n: k for k, n in enumerate(names)}
    rank = {n: k for k, n in enumerate(layout.order)}
    foot = {it.name: Footprint.of_spec(it.spec) for it in items}
    for r in relations:
        for n in (r.subject, r.reference):
            if n is not None and n not in cols:
                raise BadInput(f"relation {r.sentence()!r}: {n!r} is not an object to place")
        if r.subject == r.reference:
            raise BadInput(f"relation {r.sentence()!r}: an object cannot relate to itself")
    edges = rests_on_edges(r.key() for r in relations)
    edges += [(n, s) for n, s in layout.support.items() if s is not None]
    chain = stacked_pairs(edges)
    checks: dict[str, list[Check]] = {n: [] for n in names}
    for r in relations:
        if r.reference is None:
            checks[r.subject].append(center_check(r.subject, table))
            continue
        new = max(r.subject, r.reference, key=rank.__getitem__)
        checks[new].append(pair_check(r.relation, r.subject, r.reference, cols, foot, new))
        stated = None if gaps_m is None else gaps_m.get(r.key())
        if tolerance_m is not None and stated is not None and has_gap(r) \
                and realisable(layout, r, stated, items, tolerance_m):
            checks[new].append(gap_check(r.relation, r.subject, r.reference, stated,
                                          tolerance_m, cols, foot, new))
    edge = layout.edge_gap_m
    if tolerance_m is not None and edge is not None:
        f = foot[layout.origin]
        if abs(float(edge_gap_m(layout.positions[layout.origin][1], f, table)) - edge) \
                <= tolerance_m:
            checks[layout.origin].append(edge_check(layout.origin, f, edge, tolerance_m,
                                                     table))
    if region is not None:
        for name in names:
            checks[name].insert(0, region_check(name, foot[name], region))
    steps = []
    for k, name in enumerate(layout.order):
        clear = [clear_check(name, other, cols, foot) for other in layout.order[:k]
                 if frozenset((name, other)) not in chain]
        support = layout.support.get(name)
        if support is not None and rank[support] > k:
            raise BadInput(f"sampler: {name!r} is ordered before its support {support!r}")
        anchor = layout.anchor.get(name, support)
        if anchor is not None and rank[anchor] > k:
            raise BadInput(f"sampler: {name!r} is ordered before its anchor {anchor!r}")
        mean = layout.positions[name] if anchor is None else layout.offset(name)
        if anchor is not None and anchor not in layout.anchor:
            # A layout without anchors (built by hand): draw around the support itself.
            mean = (0.0, 0.0)
        steps.append(_Step(name, cols[name], foot[name], mean, layout.sigma[name],
                           -1 if anchor is None else cols[anchor], tuple(checks[name] + clear)))
    return steps


@dataclass
class _Stats:
    """Why configurations got stuck: how often at each object, and, per object, how many
    candidates each check rejected in draws where nothing survived. Only the first round
    is recorded: later ones search so widely that they mostly show their own misses."""

    gave_up: Counter[str] = field(default_factory=Counter)
    reasons: defaultdict[str, Counter[str]] = field(default_factory=lambda: defaultdict(Counter))

    def main_reason(self) -> tuple[str, str]:
        """The object where configurations got stuck most and the commonest rejection
        there (``("", "none recorded")`` when nothing was)."""
        if not self.gave_up:
            return "", "none recorded"
        worst = self.gave_up.most_common(1)[0][0]
        return worst, self.reasons[worst].most_common(1)[0][0]


def _first_accepted(step: _Step, mean: tuple[Floats | float, Floats | float],
                    sigma: tuple[float, float], X: Floats, Y: Floats,
                    pending: NDArray[np.intp], table: Table, rng: np.random.Generator,
                    batch: int, stats: _Stats) -> tuple[Bools, int]:
    """Draws up to ``batch`` candidates per row of ``pending`` and writes the first accepted
    one into X, Y; returns which rows got one and how many candidates were drawn.

    Candidates are drawn and checked in chunks (:data:`FIRST_CHUNK` columns, then doubling)
    and a row stops drawing once it has its candidate: rows that accept early cost little.
    """
    size = table.label
    reasons = [f"{step.name} leaves the {size}", *(c.reason for c in step.checks)]
    rejected = np.zeros((len(reasons), pending.size), dtype=np.int64)
    got = np.zeros(pending.size, dtype=bool)
    todo = np.arange(pending.size)
    mx, my = mean
    per_row = np.ndim(mx) > 0
    drawn, width = 0, FIRST_CHUNK
    while drawn < batch and todo.size:
        width = min(width, batch - drawn)
        noise = rng.standard_normal((2, todo.size, width))
        drawn += width
        cx = (mx[todo] if per_row else mx) + sigma[0] * noise[0]
        cy = (my[todo] if per_row else my) + sigma[1] * noise[1]
        rows = pending[todo]
        ok = inside_table(cx, cy, step.foot, table, SAMPLE_MARGIN_M)
        rejected[0, todo] += width - np.count_nonzero(ok, axis=1)
        for k, check in enumerate(step.checks, start=1):
            passed = check.test(cx, cy, X, Y, rows)
            rejected[k, todo] += width - np.count_nonzero(passed, axis=1)
            ok &= passed
        hit = ok.any(axis=1)
        first = ok.argmax(axis=1)[hit]
        X[rows[hit], step.col] = cx[hit, first]
        Y[rows[hit], step.col] = cy[hit, first]
        got[todo[hit]] = True
        todo = todo[~hit]
        width *= 2
    if todo.size:
        counts = rejected[:, todo].sum(axis=1)
        for reason, count in zip(reasons, counts, strict=True):
            stats.reasons[step.name][reason] += int(count)
    return got, drawn * pending.size


def _build(steps: Sequence[_Step], n: int, n_objects: int, table: Table, scale: float,
           rng: np.random.Generator, batch: int,
           stats: _Stats) -> tuple[Floats, Floats, NDArray[np.intp], int]:
    """Samples ``n`` configurations in one round; returns X, Y, the finished rows and the
    number of candidates drawn, and records in ``stats`` why configurations got stuck."""
    X = np.zeros((n, n_objects))
    Y = np.zeros((n, n_objects))
    alive = np.arange(n)
    drawn = 0
    cap = (table.width / 2, table.depth / 2)
    for step in steps:
        pending = alive
        for w in range(WIDEN_STEPS):
            widen = scale * WIDEN_FACTOR ** w
            sx, sy = min(step.sigma[0] * widen, cap[0]), min(step.sigma[1] * widen, cap[1])
            if step.anchor >= 0:
                mx = X[pending, step.anchor, None] + step.mean[0]
                my = Y[pending, step.anchor, None] + step.mean[1]
            else:
                mx, my = step.mean
            got, k = _first_accepted(step, (mx, my), (sx, sy), X, Y, pending, table, rng,
                                     batch, stats)
            drawn += k
            pending = pending[~got]
            if not pending.size:
                break
        if pending.size:
            stats.gave_up[step.name] += pending.size
            alive = alive[~np.isin(alive, pending)]
            if not alive.size:
                break
    return X, Y, alive, drawn


def _precheck(items: Sequence[Item], layout: GuidedLayout, table: Table) -> None:
    """Raises :class:`Infeasible` when the objects plainly cannot fit on the table."""
    size = table.label
    for it in items:
        sx, sy = it.spec.size
        if not inside_table(0.0, 0.0, Footprint.of_spec(it.spec), table):
            raise Infeasible(f"no feasible arrangement: the {size} is too small for {it.name} "
                             f"({sx:.2f} x {sy:.2f} m)")
    flat = [it for it in items if layout.support.get(it.name) is None]
    need = sum(it.spec.area for it in flat)
    has = table.area
    if need > has:
        names = ", ".join(it.name for it in flat[:4]) + (", ..." if len(flat) > 4 else "")
        raise Infeasible(f"no feasible arrangement: the {size} is too small for {names} "
                         f"(needs about {need:.2f} m² of footprint; has {has:.2f} m²)")


def sample_configurations(items: Sequence[Item], layout: GuidedLayout,
                          relations: Sequence[Relation], table: Table,
                          rng: np.random.Generator, m: int = DEFAULTS.m, batch: int = 256,
                          max_rounds: int = DEFAULT_MAX_ROUNDS,
                          gaps_m: Mapping[Key, float] | None = None,
                          tolerance_m: float | None = GAP_TOLERANCE_M,
                          region: Polygon | None = None) -> tuple[Configuration, ...]:
    """``m`` configurations of ``items`` near ``layout`` that keep every relation.

    With ``gaps_m`` (the stated gaps, metres, by relation key) and ``tolerance_m``, every
    configuration also keeps each stated gap that the guided layout realises, and the
    layout's diner distance, within ``tolerance_m``. Deterministic for a given state of
    ``rng``. ``region``: a diner's place (:mod:`llm_grop.geometry.places`), in the frame
    of ``table``, that every footprint must also lie in. Raises :class:`Infeasible` when
    fewer than ``m`` are found within ``max_rounds`` rounds.
    """
    if m < 1 or batch < 1 or max_rounds < 1:
        raise BadInput(f"sampler: m, batch and max_rounds must be positive, got "
                       f"{m}, {batch}, {max_rounds}")
    if tolerance_m is not None and tolerance_m <= SAMPLE_MARGIN_M:
        raise BadInput(f"sampler: the gap tolerance must exceed {SAMPLE_MARGIN_M:g} m, "
                       f"got {tolerance_m:g}")
    steps = _plan(items, layout, relations, table, gaps_m, tolerance_m, region)
    _precheck(items, layout, table)
    stats = _Stats()
    found: list[tuple[Floats, Floats]] = []
    drawn = 0
    rate = 1.0
    for round_ in range(max_rounds):
        need = m - len(found)
        n = min(4 * m, math.ceil(need / max(rate, 0.25)))
        X, Y, done, k = _build(steps, n, len(items), table, ROUND_WIDEN ** round_, rng,
                               batch, stats if round_ == 0 else _Stats())
        drawn += k
        rate = done.size / n
        found += [(X[r], Y[r]) for r in done[:need]]
        if len(found) == m:
            break
    else:
        worst, reason = stats.main_reason()
        raise NoArrangement(f"no feasible arrangement after {drawn} samples "
                            f"({len(found)} of {m} configurations found): "
                            f"most rejections were because {reason}",
                            (worst,) if worst else (), reason)
    return tuple(_configuration(items, layout, x, y) for x, y in found)


def _configuration(items: Sequence[Item], layout: GuidedLayout, x: Floats,
                   y: Floats) -> Configuration:
    return Configuration(tuple(
        Placement(name=it.name, x=px, y=py, yaw=0.0, shape=it.spec.shape, size=it.spec.size,
                  on=layout.support.get(it.name), kind=it.kind, height=it.spec.height,
                  diner=it.diner)
        for it, px, py in zip(items, x.tolist(), y.tolist(), strict=True)))


def violations(config: Configuration, relations: Sequence[Relation], table: Table,
               region: Polygon | None = None) -> list[str]:
    """Why ``config`` is not a valid arrangement for ``relations`` on ``table``, in words.

    Empty when every object lies on the table, no two footprints overlap (stacking
    chains excepted) and every relation holds.
    """
    out: list[str] = []
    places = config.by_name()
    foot = {n: Footprint.of_placement(p) for n, p in places.items()}
    size = table.label
    for n, p in places.items():
        if not inside_table(p.x, p.y, foot[n], table):
            out.append(f"{n} leaves the {size}")
        elif region is not None and not inside_region(p.x, p.y, foot[n].hx, foot[n].hy,
                                                      foot[n].shape == "circle", region):
            out.append(f"{n} leaves its diner's place")
    edges = rests_on_edges(r.key() for r in relations)
    edges += [(n, p.on) for n, p in places.items() if p.on is not None]
    chain = stacked_pairs(edges)
    names = list(places)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            if frozenset((a, b)) in chain:
                continue
            pa, pb = places[a], places[b]
            if not clear_of(pa.x, pa.y, foot[a], pb.x, pb.y, foot[b]):
                out.append(f"{a} overlaps {b}")
    for r in relations:
        missing = [n for n in (r.subject, r.reference) if n is not None and n not in places]
        if missing:
            out.append(f"{r.sentence()!r} names {missing[0]!r}, which is not placed")
            continue
        s = places[r.subject]
        if r.reference is None:
            ok = in_center(s.x, s.y, table)
        else:
            ref = places[r.reference]
            ok = pair_relation_holds(r.relation, s.x, s.y, foot[r.subject], ref.x, ref.y,
                                     foot[r.reference])
        if not ok:
            out.append(describe_failure(r.subject, r.relation, r.reference))
    return out
