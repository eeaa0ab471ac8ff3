"""Several diners' configurations brought within sure reach of the robot.

A table set for several diners is deep for the arm: a place setting lies in the half of
the top nearest its diner, and an object near the table's middle may be farther from
every free standing position than the arm reaches surely (where a place succeeds nearly
as often as at its best, :data:`SURE`), or reaches at all. A failed place may tip or
drop its object, so an object placed at long reach is often lost; with some twenty
objects on the table, nearly every configuration of M has one. Before GROP scores a
configuration, every diner whose objects are not all within sure reach is *repaired*,
and GROP keeps the repaired configuration when it scores better (its utility less the
fidelity penalty), so nothing is repaired that GROP would not prefer:

* **Stated geometry** (the configuration comes with a fidelity measure: relations and
  gaps were stated): the diner's setting is moved as a whole towards its diner, by the
  least whole centimetre that brings every object within sure reach (else the shift
  within :data:`MAX_SHIFT_M` that brings the farthest object nearest), while every
  footprint stays on the top and clear of the other diners' objects. A rigid move keeps
  every relation and gap between the setting's objects; what it changes is the setting's
  distance from the diner's edge, so the shift is added to the configuration's
  ``origin_shift_m`` (charged by the fidelity weight) and the edge distance is measured
  again. The planner never reads a relation: a ``center`` relation of a diner's place
  is not protected (a shift of a few centimetres rarely takes an object out of it).
* **No stated geometry** (random configurations, GROP's and the baselines'): the diner's
  objects are taken as they lie in another of the M configurations, the one whose
  farthest object is reached most surely, when they are clear of the other diners'.
  Nothing is moved, so a given arrangement (one configuration) is never changed.

Only configurations whose every object belongs to a diner are repaired, so one-diner
arrangements (the paper's experiment) are planned exactly as before.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from shapely.geometry.base import BaseGeometry

from llm_grop.geometry.footprint import footprint
from llm_grop.geometry.places import Place, outline, places
from llm_grop.planning.feasibility import placing
from llm_grop.planning.utility import PlanningContext
from llm_grop.world.arrangement import Configuration, Placement
from llm_grop.world.fidelity import Fidelity

Floats = NDArray[np.float64]

#: An object is within *sure* reach when a place from some free standing position
#: succeeds at least this fraction as often as a place at the arm's best reach (with the
#: default belief: within about 0.63 m of the base's centre).
SURE = 0.95
#: The largest move, metres, of a setting with stated geometry towards its diner.
MAX_SHIFT_M = 0.05
#: The step, metres, in which such a move is searched.
STEP_M = 0.01
#: Overlap, square metres, below which two footprints count as touching, not overlapping.
OVERLAP_M2 = 1e-7
#: A repair must raise the farthest object's best place probability by more than this.
GAIN = 1e-3


@dataclass(frozen=True)
class Repaired:
    """A configuration repaired for reach: the new ``configuration`` (the objects in the
    order given), its ``fidelity``, and each moved diner's shift, metres (stated
    geometry) or the configuration its objects were taken from (none stated)."""

    configuration: Configuration
    fidelity: Fidelity
    shifted_m: dict[int, float]
    taken_from: dict[int, int]


def sure_p(ctx: PlanningContext) -> float:
    """The place success probability, under the planner's belief, that counts as sure."""
    robot = ctx.scene.robot
    reach = np.linspace(robot.reach_min_m, robot.reach_max_m, 256)
    return SURE * float(np.max(placing(ctx.model, reach, robot)))


def best_place_p(ctx: PlanningContext, placements: Sequence[Placement]) -> Floats:
    """Per placement, the probability that placing it succeeds from the free standing
    position that reaches it best (the reach alone; navigation is GROP's to weigh)."""
    if not placements:
        return np.zeros(0)
    return ctx.place_manipulation(placements).max(axis=1)


def repair(ctx: PlanningContext, config: Configuration, fidelity: Fidelity | None,
           pool: Sequence[Configuration], cache: dict[int, Floats] | None = None
           ) -> Repaired | None:
    """``config`` with every diner whose objects are not all within sure reach repaired
    (see the module doc), or ``None`` when no diner needs or allows it. ``fidelity``:
    the configuration's measure (``None``: nothing was stated, and the diners' objects
    may be taken from the other configurations of ``pool``; ``cache`` keeps
    :func:`best_place_p` per configuration of the pool, by index)."""
    placements = list(config.placements)
    if not placements or any(p.diner is None for p in placements):
        return None
    table = ctx.scene.target_top
    seats = table.seats
    if max(p.diner for p in placements if p.diner is not None) >= len(seats):
        return None
    seated = places(table, seats)
    top = outline(table)
    sure = sure_p(ctx)
    best = best_place_p(ctx, placements)
    shifted: dict[int, float] = {}
    taken: dict[int, int] = {}
    for d in sorted({p.diner for p in placements if p.diner is not None}):
        mine = [j for j, p in enumerate(placements) if p.diner == d]
        now = float(best[mine].min())
        if now >= sure:
            continue
        others = [_shape(p) for p in placements if p.diner != d]
        group = [placements[j] for j in mine]
        if fidelity is not None:
            found = _shift(ctx, group, seated[d], top, others, sure, now)
            if found is None:
                continue
            group, shifted[d] = found
        else:
            swap = _swap(ctx, group, pool, top, others, now, cache if cache is not None else {})
            if swap is None:
                continue
            group, taken[d] = swap
        for j, q in zip(mine, group, strict=True):
            placements[j] = q
        best[mine] = best_place_p(ctx, group)
    if not shifted and not taken:
        return None
    repaired = Configuration(tuple(placements))
    fid = fidelity if fidelity is not None else Fidelity()
    if shifted:
        fid = _refit(fid, placements, seated, sum(shifted.values()))
    return Repaired(repaired, fid, shifted, taken)


def _shape(p: Placement) -> BaseGeometry:
    return footprint(p.x, p.y, p.yaw, p.shape, p.size)


def _fits(group: Sequence[Placement], top: BaseGeometry,
          others: Sequence[BaseGeometry]) -> bool:
    """Whether every footprint of ``group`` lies on ``top`` and clear of ``others``."""
    for p in group:
        shape = _shape(p)
        if not top.contains(shape):
            return False
        if any(shape.intersection(o).area > OVERLAP_M2 for o in others
               if shape.intersects(o)):
            return False
    return True


def _shift(ctx: PlanningContext, group: Sequence[Placement], place: Place,
           top: BaseGeometry, others: Sequence[BaseGeometry], sure: float, now: float
           ) -> tuple[list[Placement], float] | None:
    """``group`` moved towards its diner (the place frame's -y) by the least whole step
    that brings all of it within sure reach, else by the step within :data:`MAX_SHIFT_M`
    that reaches its farthest object best; ``None`` when no step gains."""
    c, s = np.cos(place.yaw), np.sin(place.yaw)
    toward = (float(s), float(-c))   # the place frame's -y, in the table frame
    best: tuple[float, float, list[Placement]] | None = None
    for k in range(1, int(round(MAX_SHIFT_M / STEP_M)) + 1):
        delta = k * STEP_M
        moved = [replace(p, x=p.x + delta * toward[0], y=p.y + delta * toward[1])
                 for p in group]
        if not _fits(moved, top, others):
            break  # a step farther leaves the top or meets a neighbour sooner still
        low = float(best_place_p(ctx, moved).min())
        if best is None or low > best[0] + 1e-12:
            best = (low, delta, moved)
        if low >= sure:
            break
    if best is None or best[0] <= now + GAIN:
        return None
    return best[2], best[1]


def _swap(ctx: PlanningContext, group: Sequence[Placement], pool: Sequence[Configuration],
          top: BaseGeometry, others: Sequence[BaseGeometry], now: float,
          cache: dict[int, Floats]) -> tuple[list[Placement], int] | None:
    """The diner's objects as they lie in the configuration of ``pool`` whose farthest of
    them is reached most surely, clear of ``others``; ``None`` when none gains."""
    names = [p.name for p in group]
    found: tuple[float, int, list[Placement]] | None = None
    for k, other in enumerate(pool):
        by_name = other.by_name()
        if not all(n in by_name for n in names):
            continue
        if k not in cache:
            cache[k] = best_place_p(ctx, other.placements)
        index = {p.name: i for i, p in enumerate(other.placements)}
        low = float(cache[k][[index[n] for n in names]].min())
        if low <= now + GAIN or (found is not None and low <= found[0] + 1e-12):
            continue
        variant = [by_name[n] for n in names]
        if _fits(variant, top, others):
            found = (low, k, variant)
    if found is None:
        return None
    return found[2], found[1]


def _refit(fid: Fidelity, placements: Sequence[Placement], seated: Sequence[Place],
           shift_m: float) -> Fidelity:
    """``fid`` after the diners' settings moved ``shift_m`` metres in all (rigidly): the
    gaps are the same, the origins' summed shift grows by at most ``shift_m``, and the
    worst diner's distance from their edge is measured again."""
    fid = replace(fid, origin_shift_m=fid.origin_shift_m + shift_m)
    if fid.edge_stated_m is None or not fid.origin:
        return fid
    origins = set(fid.origin.split(", "))
    worst: float | None = None
    for p in placements:
        if p.name not in origins or p.diner is None:
            continue
        place = seated[p.diner]
        _, y = place.to_place(p.x, p.y)
        turn = p.yaw - place.yaw
        hy = p.size[0] / 2 if p.shape == "circle" else \
            (abs(np.sin(turn)) * p.size[0] + abs(np.cos(turn)) * p.size[1]) / 2
        edge = float(y) - hy + place.box.depth / 2
        if worst is None or abs(edge - fid.edge_stated_m) > abs(worst - fid.edge_stated_m):
            worst = edge
    return fid if worst is None else replace(fid, edge_realised_m=worst)
