"""The adaptive 2D Gaussian rejection sampler (paper §III-B).

Objects are sampled one at a time in the layout's order. For an object, every
unfinished configuration draws ``batch`` candidates from N(guided position,
diag(sigma²)) at once (arrays of shape ``(configurations, batch)``); a candidate is
rejected when it breaks an accepted relation with an object already placed in its
configuration (``center`` included), overlaps one (stacking chains excepted) or
leaves the table. Each configuration keeps its first surviving candidate. An object
resting on another is drawn around its support's *sampled* position.

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
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from llm_grop.arrangement.geometry import GuidedLayout
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
from llm_grop.errors import BadInput, Infeasible
from llm_grop.world.arrangement import Configuration, Item, Placement
from llm_grop.world.relation import CENTER, Relation
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

#: Stricter-by margin in metres for accepting a candidate, so that results pass the
#: exact checks of :func:`violations` even after rounding to 0.1 mm.
SAMPLE_MARGIN_M = 1e-4

Floats = NDArray[np.float64]
Bools = NDArray[np.bool_]
#: ``test(cx, cy, X, Y, rows)``: candidate x, y ``(A, K)``; positions so far ``(n, N)``;
#: the configurations ``rows`` ``(A,)`` the candidates belong to -> accepted ``(A, K)``.
Test = Callable[[Floats, Floats, Floats, Floats, NDArray[np.intp]], Bools]


@dataclass(frozen=True)
class _Check:
    reason: str
    test: Test


@dataclass(frozen=True)
class _Step:
    """How one object is sampled: its column, mean, std dev and checks."""

    name: str
    col: int
    foot: Footprint
    mean: tuple[float, float]
    sigma: tuple[float, float]
    support: int  # column of the support, -1 for the table
    checks: tuple[_Check, ...]


def _pair_check(rel: str, subject: str, reference: str, cols: dict[str, int],
                foot: dict[str, Footprint], new: str) -> _Check:
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
    return _Check(describe_failure(subject, rel, reference), test)


def _clear_check(name: str, other: str, cols: dict[str, int],
                 foot: dict[str, Footprint]) -> _Check:
    o, f, fo = cols[other], foot[name], foot[other]

    def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
        return clear_of(cx, cy, f, X[rows, o, None], Y[rows, o, None], fo, SAMPLE_MARGIN_M)
    return _Check(f"{name} overlaps {other}", test)


def _center_check(name: str, table: Table) -> _Check:
    def test(cx: Floats, cy: Floats, X: Floats, Y: Floats, rows: NDArray[np.intp]) -> Bools:
        return in_center(cx, cy, table, SAMPLE_MARGIN_M)
    return _Check(describe_failure(name, CENTER, None), test)


def _plan(items: Sequence[Item], layout: GuidedLayout, relations: Sequence[Relation],
          table: Table) -> list[_Step]:
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
    checks: dict[str, list[_Check]] = {n: [] for n in names}
    for r in relations:
        if r.reference is None:
            checks[r.subject].append(_center_check(r.subject, table))
            continue
        new = max(r.subject, r.reference, key=rank.__getitem__)
        checks[new].append(_pair_check(r.relation, r.subject, r.reference, cols, foot, new))
    steps = []
    for k, name in enumerate(layout.order):
        clear = [_clear_check(name, other, cols, foot) for other in layout.order[:k]
                 if frozenset((name, other)) not in chain]
        support = layout.support.get(name)
        if support is not None and rank[support] > k:
            raise BadInput(f"sampler: {name!r} is ordered before its support {support!r}")
        steps.append(_Step(name, cols[name], foot[name], layout.positions[name], layout.sigma[name],
                           -1 if support is None else cols[support], tuple(checks[name] + clear)))
    return steps


@dataclass
class _Stats:
    """Why configurations got stuck: how often at each object, and, per object, how many
    candidates each check rejected in draws where nothing survived. Only the first round
    is recorded: later ones search so widely that they mostly show their own misses."""

    gave_up: Counter[str] = field(default_factory=Counter)
    reasons: defaultdict[str, Counter[str]] = field(default_factory=lambda: defaultdict(Counter))

    def main_reason(self) -> str:
        """The commonest rejection at the object where configurations got stuck most."""
        if not self.gave_up:
            return "none recorded"
        worst = self.gave_up.most_common(1)[0][0]
        return self.reasons[worst].most_common(1)[0][0]


def _first_accepted(step: _Step, mean: tuple[Floats | float, Floats | float],
                    sigma: tuple[float, float], X: Floats, Y: Floats,
                    pending: NDArray[np.intp], table: Table, rng: np.random.Generator,
                    batch: int, stats: _Stats) -> tuple[Bools, int]:
    """Draws up to ``batch`` candidates per row of ``pending`` and writes the first accepted
    one into X, Y; returns which rows got one and how many candidates were drawn.

    Candidates are drawn and checked in chunks (:data:`FIRST_CHUNK` columns, then doubling)
    and a row stops drawing once it has its candidate: rows that accept early cost little.
    """
    size = f"{table.width:.2f} x {table.depth:.2f} m table"
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
            if step.support >= 0:
                mx, my = X[pending, step.support, None], Y[pending, step.support, None]
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
    size = f"{table.width:.2f} x {table.depth:.2f} m table"
    for it in items:
        sx, sy = it.spec.size
        if sx > table.width or sy > table.depth:
            raise Infeasible(f"no feasible arrangement: the {size} is too small for {it.name} "
                             f"({sx:.2f} x {sy:.2f} m)")
    flat = [it for it in items if layout.support.get(it.name) is None]
    need = sum(it.spec.area for it in flat)
    has = table.width * table.depth
    if need > has:
        names = ", ".join(it.name for it in flat[:4]) + (", ..." if len(flat) > 4 else "")
        raise Infeasible(f"no feasible arrangement: the {size} is too small for {names} "
                         f"(needs about {need:.2f} m² of footprint; has {has:.2f} m²)")


def sample_configurations(items: Sequence[Item], layout: GuidedLayout,
                          relations: Sequence[Relation], table: Table,
                          rng: np.random.Generator, m: int = 25, batch: int = 256,
                          max_rounds: int = DEFAULT_MAX_ROUNDS) -> tuple[Configuration, ...]:
    """``m`` configurations of ``items`` near ``layout`` that keep every relation.

    Deterministic for a given state of ``rng``. Raises :class:`Infeasible` when fewer
    than ``m`` are found within ``max_rounds`` rounds.
    """
    if m < 1 or batch < 1 or max_rounds < 1:
        raise BadInput(f"sampler: m, batch and max_rounds must be positive, got "
                       f"{m}, {batch}, {max_rounds}")
    steps = _plan(items, layout, relations, table)
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
        reason = stats.main_reason()
        raise Infeasible(f"no feasible arrangement after {drawn} samples "
                         f"({len(found)} of {m} configurations found): "
                         f"most rejections were because {reason}")
    return tuple(_configuration(items, layout, x, y) for x, y in found)


def _configuration(items: Sequence[Item], layout: GuidedLayout, x: Floats,
                   y: Floats) -> Configuration:
    return Configuration(tuple(
        Placement(name=it.name, x=px, y=py, yaw=0.0, shape=it.spec.shape, size=it.spec.size,
                  on=layout.support.get(it.name), kind=it.kind, height=it.spec.height)
        for it, px, py in zip(items, x.tolist(), y.tolist(), strict=True)))


def violations(config: Configuration, relations: Sequence[Relation], table: Table) -> list[str]:
    """Why ``config`` is not a valid arrangement for ``relations`` on ``table``, in words.

    Empty when every object lies on the table, no two footprints overlap (stacking
    chains excepted) and every relation holds.
    """
    out: list[str] = []
    places = config.by_name()
    foot = {n: Footprint.of_placement(p) for n, p in places.items()}
    size = f"{table.width:.2f} x {table.depth:.2f} m table"
    for n, p in places.items():
        if not inside_table(p.x, p.y, foot[n], table):
            out.append(f"{n} leaves the {size}")
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
