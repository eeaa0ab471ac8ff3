"""Trips for a robot that carries more than one object (``capacity > 1``).

Given the order and the standing positions (chosen as for capacity 1), the order is cut
into trips of at most ``capacity`` objects: on a trip the robot picks its objects up in
order, then places them in order. The cut is exact dynamic programming over the order:
``best[b] = min_a best[a - 1] + trip(a..b)``, with every trip's driving distance read from
the cost-to-go fields. One object per trip is among the cuts, so more capacity never
plans a longer drive.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from llm_grop.planning.utility import PlanningContext


def plan_trips(ctx: PlanningContext, order: Sequence[int], stand: Sequence[int],
               capacity: int) -> tuple[tuple[tuple[int, ...], ...], float]:
    """The trips (item indices, in order) and the driving distance they save, metres,
    against one object per trip."""
    n = len(order)
    if capacity <= 1 or n <= 1:
        return tuple((j,) for j in order), 0.0
    field = [ctx.pickups[j].field for j in order]
    stand_xy = ctx.cand_xy[[stand[j] for j in order]]
    from_stand = ctx.graph.fields([tuple(p) for p in stand_xy])
    # stand_to_stand[i, k]: from order[i]'s stand to order[k]'s stand.
    stand_to_stand = np.stack([f.cost_at(stand_xy) for f in from_stand])
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
        d += sum(float(stand_to_stand[i, i + 1]) for i in range(a, b))
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
    return tuple(trips), max(single - float(best[n]), 0.0)
