"""Trips for a robot that carries more than one object (``capacity > 1``).

Given the standing positions (chosen as for capacity 1), the objects are ordered and the
order cut into trips of at most ``capacity`` objects: on a trip the robot picks its
objects up in order, then places them in order. The cut of one order is exact dynamic
programming: ``best[b] = min_a best[a - 1] + trip(a..b)``, with every trip's driving
distance read from the cost-to-go fields. The order is searched, not taken from capacity
1 (whose best order ignores what trips share): up to :data:`EXACT_OBJECTS` objects every
order keeping supports first is cut (exact for these standing positions); beyond, the
capacity-1 order is improved by moving one object at a time while that shortens the
drive. The capacity-1 order cut into one object per trip is among the candidates, so
more capacity never plans a longer drive. ``benchmarks/family_planning.py`` measures the
gap to the best over every order and every cut on instances small enough to enumerate.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from llm_grop.planning.utility import PlanningContext

Trips = tuple[tuple[int, ...], ...]

#: Up to this many objects every order is tried (6! = 720 cuts).
EXACT_OBJECTS = 6
#: Beyond it, at most this many rounds of single-object moves.
MAX_ROUNDS = 20


def stand_distances(ctx: PlanningContext, stand: Sequence[int]) -> NDArray[np.float64]:
    """Path length, metres, from object ``i``'s standing position to object ``k``'s,
    ``(n, n)`` in item order (``stand[i]`` indexes ``ctx.candidates``)."""
    xy = ctx.cand_xy[list(stand)]
    return np.stack([f.cost_at(xy) for f in ctx.graph.fields([tuple(p) for p in xy])])


def plan_trips(ctx: PlanningContext, order: Sequence[int], stand: Sequence[int],
               capacity: int, before: Sequence[tuple[int, int]] = ()
               ) -> tuple[Trips, float]:
    """The trips (item indices, in order) and the driving distance they save, metres,
    against ``order`` with one object per trip; every ``(a, b)`` of ``before`` keeps
    object ``a`` placed before ``b``."""
    n = len(order)
    if capacity <= 1 or n <= 1:
        return tuple((j,) for j in order), 0.0
    between = stand_distances(ctx, stand)
    trips, best_m, single_m = cut_order(ctx, order, stand, capacity, between)

    def ok(perm: Sequence[int]) -> bool:
        pos = {j: k for k, j in enumerate(perm)}
        return all(pos[a] < pos[b] for a, b in before)

    if n <= EXACT_OBJECTS:
        for perm in itertools.permutations(sorted(order)):
            if ok(perm):
                got = cut_order(ctx, perm, stand, capacity, between)
                if got[1] < best_m - 1e-9:
                    trips, best_m = got[0], got[1]
    else:
        current = list(order)
        for _ in range(MAX_ROUNDS):
            moved = False
            for i in range(n):
                for k in range(n):
                    if i == k:
                        continue
                    trial = current[:i] + current[i + 1:]
                    trial.insert(k, current[i])
                    if ok(trial):
                        got = cut_order(ctx, trial, stand, capacity, between)
                        if got[1] < best_m - 1e-9:
                            current, trips, best_m, moved = trial, got[0], got[1], True
            if not moved:
                break
    return trips, max(single_m - best_m, 0.0)


def cut_order(ctx: PlanningContext, order: Sequence[int], stand: Sequence[int],
              capacity: int, between: NDArray[np.float64]) -> tuple[Trips, float, float]:
    """The best cut of ``order`` into trips of at most ``capacity``, its driving distance
    and that of one object per trip, metres (``between``: :func:`stand_distances`)."""
    n = len(order)
    field = [ctx.pickups[j].field for j in order]
    stand_idx = [stand[j] for j in order]

    def into_pickup(prev: int, k: int) -> float:
        """From where object ``prev`` (position in the order; -1: start) was placed to the
        pickup of the object at position ``k``."""
        if prev < 0:
            return float(ctx.start_dist_m[field[k]])
        return float(ctx.dist_m[stand_idx[prev], field[k]])

    def trip(a: int, b: int) -> float:
        d = into_pickup(a - 1, a)
        d += sum(float(ctx.pickup_dist_m[field[i + 1], field[i]]) for i in range(a, b))
        d += float(ctx.dist_m[stand_idx[a], field[b]])
        d += sum(float(between[order[i], order[i + 1]]) for i in range(a, b))
        return d

    best = np.full(n + 1, np.inf)
    cut = np.zeros(n + 1, dtype=int)
    best[0] = 0.0
    for b in range(1, n + 1):
        for a in range(max(1, b - capacity + 1), b + 1):
            c = best[a - 1] + trip(a - 1, b - 1)
            if c < best[b] - 1e-12:
                best[b], cut[b] = c, a
    trips: list[tuple[int, ...]] = []
    b = n
    while b > 0:
        a = int(cut[b])
        trips.append(tuple(order[a - 1:b]))
        b = a - 1
    trips.reverse()
    single = sum(trip(i, i) for i in range(n))
    return tuple(trips), float(best[n]), single
