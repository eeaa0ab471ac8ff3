"""Trips for a robot that carries more than one object (``capacity > 1``).

Given the standing positions (chosen as for capacity 1), the objects are ordered and the
order cut into trips: on a trip the robot picks its objects up in order, then places them
in order. A trip of one object rides in the hand, as with capacity 1; a trip of several
rides on the robot's tray (:mod:`llm_grop.world.tray`), so its objects must fit the
tray's slots together, and each of them costs a load onto the tray and an unload off
it, which succeed as a place and a pick at the arm's sure reach (``robot.reach_min_m``)
and take the belief's load and unload seconds (a place's and a pick's unless its
profile states ``load_time_s`` / ``unload_time_s``; :attr:`TripCosts.handling_s`). A
trip is therefore only chosen where the drive it saves outweighs its loads and unloads.

A trip's cost is its driving time (paths read from the cost-to-go fields, at the robot's
speed) plus that handling. The cut of one order is exact dynamic programming:
``best[b] = min_a best[a - 1] + trip(a..b)``. The order is searched, not taken from
capacity 1 (whose best order ignores what trips share): up to :data:`EXACT_OBJECTS`
objects every order keeping supports first is cut (exact for these standing positions);
beyond, from the capacity-1 order and from a greedy grouping (:func:`grouped_order`),
objects are moved one at a time while that lowers the cost. The capacity-1 order cut
into one object per trip is among the candidates, so more capacity never plans a slower
episode. ``benchmarks/family_planning.py`` measures the gap to the best over every order
and every cut on instances small enough to enumerate.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from llm_grop.planning.feasibility import action_times, expected_failures, placing
from llm_grop.planning.utility import PlanningContext
from llm_grop.world.tray import Tray, load_tray

Trips = tuple[tuple[int, ...], ...]
Footprint = tuple[str, tuple[float, float]]

#: Up to this many objects every order is tried (6! = 720 cuts).
EXACT_OBJECTS = 6
#: Beyond it, at most this many rounds of single-object moves.
MAX_ROUNDS = 20
#: Beyond it, an object is moved at most this many places along the order per move.
MOVE_SPAN = 8


@dataclass(frozen=True)
class TripCosts:
    """What a trip costs, for one configuration's standing positions.

    Attributes:
        capacity: most objects on one trip.
        between_m: path length, metres, from object ``i``'s standing position to object
            ``k``'s, ``(n, n)`` in item order (:func:`stand_distances`).
        speed_mps: the robot's driving speed, metres per second.
        handling_s: expected seconds one object adds on a trip of several: its load onto
            the tray and its unload from it, each with its expected failed attempts.
        footprints: each item's footprint ``(shape, size in metres)``, in item order.
        tray: the tray whose slots a trip of several must fit.
    """

    capacity: int
    between_m: NDArray[np.float64]
    speed_mps: float
    handling_s: float
    footprints: tuple[Footprint, ...]
    tray: Tray
    _fit: dict[tuple[Footprint, ...], bool] = field(default_factory=dict, compare=False,
                                                    repr=False)

    def fits(self, objects: Sequence[int]) -> bool:
        """Whether ``objects`` (item indices) can ride one trip: one in the hand, several
        on the tray, each in a slot of its own."""
        if len(objects) <= 1:
            return True
        if len(objects) > self.capacity:
            return False
        key = tuple(sorted(self.footprints[j] for j in objects))
        got = self._fit.get(key)
        if got is None:
            got = self._fit[key] = self.tray.assign(key) is not None
        return got


def stand_distances(ctx: PlanningContext, stand: Sequence[int]) -> NDArray[np.float64]:
    """Path length, metres, from object ``i``'s standing position to object ``k``'s,
    ``(n, n)`` in item order (``stand[i]`` indexes ``ctx.candidates``)."""
    xy = ctx.cand_xy[list(stand)]
    return np.stack([f.cost_at(xy) for f in ctx.graph.fields([tuple(p) for p in xy])])


def handling_s(ctx: PlanningContext) -> float:
    """Expected seconds an object adds on a trip of several under the planner's belief:
    a load onto the tray and an unload from it (the belief's ``load_s`` and ``unload_s``),
    succeeding as a place and a pick at ``robot.reach_min_m``, each with its
    expected failed attempts (as :func:`~llm_grop.planning.grop.expected_duration_s`
    counts them)."""
    robot = ctx.scene.robot
    times = action_times(ctx.model, robot)
    reach = np.array([robot.reach_min_m])
    p_load = float(placing(ctx.model, reach, robot)[0])
    p_unload = float(ctx.model.manipulation(reach, robot)[0])
    return times.load_s + times.unload_s + times.failed_attempt_s * (
        expected_failures(p_load) + expected_failures(p_unload))


def trip_costs(ctx: PlanningContext, stand: Sequence[int], capacity: int,
               tray: Tray | None = None) -> TripCosts:
    """The :class:`TripCosts` of these standing positions (``tray``: the packaged one)."""
    return TripCosts(capacity, stand_distances(ctx, stand), ctx.speed, handling_s(ctx),
                     tuple((i.spec.shape, i.spec.size) for i in ctx.items),
                     tray or load_tray())


def plan_trips(ctx: PlanningContext, order: Sequence[int], stand: Sequence[int],
               capacity: int, before: Sequence[tuple[int, int]] = (),
               costs: TripCosts | None = None) -> tuple[Trips, float]:
    """The trips (item indices, in order) and the seconds they save (driving less the
    trips' handling) against ``order`` with one object per trip; every ``(a, b)`` of
    ``before`` keeps object ``a`` placed before ``b``."""
    n = len(order)
    if capacity <= 1 or n <= 1:
        return tuple((j,) for j in order), 0.0
    costs = costs or trip_costs(ctx, stand, capacity)
    trips, best_s, single_s = cut_order(ctx, order, stand, costs)

    def ok(perm: Sequence[int]) -> bool:
        pos = {j: k for k, j in enumerate(perm)}
        return all(pos[a] < pos[b] for a, b in before)

    if n <= EXACT_OBJECTS:
        for perm in itertools.permutations(sorted(order)):
            if ok(perm):
                got = cut_order(ctx, perm, stand, costs)
                if got[1] < best_s - 1e-9:
                    trips, best_s = got[0], got[1]
        return trips, max(single_s - best_s, 0.0)
    for start in (list(order), grouped_order(ctx, order, stand, costs, before)):
        if not ok(start):
            continue
        got_trips, got_s = _improve(ctx, start, stand, costs, ok)
        if got_s < best_s - 1e-9:
            trips, best_s = got_trips, got_s
    return trips, max(single_s - best_s, 0.0)


def _improve(ctx: PlanningContext, current: list[int], stand: Sequence[int],
             costs: TripCosts, ok: Callable[[Sequence[int]], bool]) -> tuple[Trips, float]:
    """``current`` improved by moving one object at a time (at most :data:`MOVE_SPAN`
    places) while its best cut gets cheaper; its trips and their cost, seconds."""
    n = len(current)
    trips, best_s, _ = cut_order(ctx, current, stand, costs)
    for _ in range(MAX_ROUNDS):
        moved = False
        for i in range(n):
            for k in range(max(0, i - MOVE_SPAN), min(n, i + MOVE_SPAN + 1)):
                if i == k:
                    continue
                trial = current[:i] + current[i + 1:]
                trial.insert(k, current[i])
                if ok(trial):
                    got = cut_order(ctx, trial, stand, costs)
                    if got[1] < best_s - 1e-9:
                        current, trips, best_s, moved = trial, got[0], got[1], True
        if not moved:
            break
    return trips, best_s


def grouped_order(ctx: PlanningContext, order: Sequence[int], stand: Sequence[int],
                  costs: TripCosts, before: Sequence[tuple[int, int]] = ()) -> list[int]:
    """An order built trip by trip: each trip starts with the first object of ``order``
    not yet carried whose supports are, then takes on the object (supports carried or
    aboard) that adds least driving to it, while the tray holds them and the trip costs
    less than carrying the added object alone."""
    v = costs.speed_mps
    field_of = [p.field for p in ctx.pickups]
    needs: dict[int, set[int]] = {}
    for a, b in before:
        needs.setdefault(b, set()).add(a)
    left = list(order)
    done: set[int] = set()
    out: list[int] = []
    while left:
        first = next(j for j in left if needs.get(j, set()) <= done)
        trip = [first]
        left.remove(first)
        while len(trip) < costs.capacity:
            last = trip[-1]
            best_k, best_add = -1, np.inf
            for k in left:
                if not needs.get(k, set()) <= done | set(trip) or not costs.fits([*trip, k]):
                    continue
                add = (float(ctx.pickup_dist_m[field_of[k], field_of[last]])
                       + float(costs.between_m[last, k])) / v
                if add < best_add:
                    best_k, best_add = k, add
            if best_k < 0:
                break
            alone = (float(ctx.dist_m[stand[best_k], field_of[best_k]]) * 2) / v
            handling = costs.handling_s * (len(trip) + 1 if len(trip) == 1 else 1)
            if best_add + handling >= alone:
                break
            trip.append(best_k)
            left.remove(best_k)
        out += trip
        done |= set(trip)
    return out


def cut_order(ctx: PlanningContext, order: Sequence[int], stand: Sequence[int],
              costs: TripCosts) -> tuple[Trips, float, float]:
    """The best cut of ``order`` into trips that fit (:meth:`TripCosts.fits`), its cost
    and that of one object per trip, seconds (driving at the robot's speed, plus
    :attr:`TripCosts.handling_s` for each object on a trip of several)."""
    n = len(order)
    v = costs.speed_mps
    field = [ctx.pickups[j].field for j in order]
    stand_idx = [stand[j] for j in order]
    dist, pickup_dist = ctx.dist_m, ctx.pickup_dist_m
    between = costs.between_m
    # Driving, metres: into each pickup from the previous object's place (or the start),
    # between consecutive pickups and consecutive places, and from a pickup to a place.
    into = [float(ctx.start_dist_m[field[0]])] + [
        float(dist[stand_idx[k - 1], field[k]]) for k in range(1, n)]
    step_pick = [float(pickup_dist[field[k + 1], field[k]]) for k in range(n - 1)]
    step_place = [float(between[order[k], order[k + 1]]) for k in range(n - 1)]

    def trip(a: int, b: int) -> float:
        d = into[a] + float(dist[stand_idx[a], field[b]])
        d += sum(step_pick[a:b]) + sum(step_place[a:b])
        return d / v + (costs.handling_s * (b - a + 1) if b > a else 0.0)

    best = np.full(n + 1, np.inf)
    cut = np.zeros(n + 1, dtype=int)
    best[0] = 0.0
    for b in range(1, n + 1):
        for a in range(b, max(1, b - costs.capacity + 1) - 1, -1):
            # A subset of what fits fits, so a longer trip ending at b fits no more.
            if not costs.fits(order[a - 1:b]):
                break
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
