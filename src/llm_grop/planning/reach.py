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
  gaps were stated): the diner's setting is moved as a whole, towards its diner or along
  its place's width (never away from the diner), by the shortest move in whole
  centimetres that brings every object within sure reach (else the move within
  :data:`MAX_SHIFT_M` that brings the farthest object nearest), while every footprint
  stays on the top and clear of the other diners' objects, and the setting's stated
  distance from the diner's edge is kept within the sampler's tolerance
  (:data:`EDGE_TOLERANCE_M`). Along the width matters when a chair blocks the standing
  positions in front of the diner. A rigid move keeps every relation and gap between
  the setting's objects; what it changes is where the setting lies in the place, so the
  move's length is added to the configuration's ``origin_shift_m`` (charged by the
  fidelity weight) and the distance from the diner's edge is measured again. The
  planner never reads a relation: a ``center`` relation of a diner's place is not
  protected (a move of a few centimetres rarely breaks it).
* **Last resort**: when no configuration has a plan even so (an object beyond the arm's
  reach of every free standing position in all M), a stated setting makes the shortest
  move, up to :data:`LAST_RESORT_SHIFT_M` in any direction (its edge distance too), that
  brings every object within the arm's reach at all, or often enough
  (:data:`LAST_RESORT_P`; GROP keeps the one that scores best), rather than the episode
  failing; the plan's fidelity reports what that cost.
* **No stated geometry** (random configurations, GROP's and the baselines'): the diner's
  objects are taken as they lie in another of the M configurations, the one whose
  farthest object is reached most surely, when they are clear of the other diners';
  then each object still beyond sure reach is taken alone from the configuration that
  reaches it most surely, when that spot is clear of every other object. Each object
  lies where the random draw put it in one configuration or another (which one is
  chosen for reach), nothing is moved anywhere no draw put it, and a given arrangement
  (one configuration) is never changed.

Only configurations whose every object belongs to a diner are repaired, so one-diner
arrangements (the paper's experiment) are planned exactly as before.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from shapely.affinity import translate
from shapely.geometry.base import BaseGeometry

from llm_grop.geometry.footprint import footprint
from llm_grop.geometry.places import Place, outline, places
from llm_grop.planning.feasibility import placing
from llm_grop.planning.utility import PlanningContext
from llm_grop.world.arrangement import Configuration, Placement
from llm_grop.world.fidelity import GAP_TOLERANCE_M, Fidelity
from llm_grop.world.table import Table

Floats = NDArray[np.float64]

#: An object is within *sure* reach when a place from some free standing position
#: succeeds at least this fraction as often as a place at the arm's best reach (with the
#: default belief: within about 0.61 m of the base's centre, just past the knee). Over
#: 60 seeds of six diners, GROP placed all 24 objects in 41, 44 and 45 episodes with
#: 0.95, 0.98 and 0.995 (benchmarks/family_table.py).
SURE = 0.995
#: The largest move, metres, of a setting with stated geometry.
MAX_SHIFT_M = 0.05
#: How far short of its stated distance from the diner's edge a setting may come by a
#: move, metres: the sampler's tolerance of a stated gap.
EDGE_TOLERANCE_M = GAP_TOLERANCE_M
#: The largest move, metres, when no configuration has a plan otherwise (a last resort,
#: in any direction, away from the diner too).
LAST_RESORT_SHIFT_M = 0.15
#: The probabilities with which a last resort's moves (the shortest that let every
#: object be placed at least that often) are tried; GROP keeps the one that scores best,
#: so a longer move, farther from what was stated, is made only when its plan is worth
#: the fidelity it costs.
LAST_RESORT_P = (1e-3, 0.1, 0.25, 0.5)
#: The step, metres, in which such a move is searched.
STEP_M = 0.01
#: The step, metres, of a last resort's moves (coarser: they range farther).
LAST_RESORT_STEP_M = 0.025
#: Overlap, square metres, below which two footprints count as touching, not overlapping.
OVERLAP_M2 = 1e-7
#: A repair must raise the farthest object's best place probability by more than this.
GAIN = 1e-3


@dataclass(frozen=True)
class Repaired:
    """A configuration repaired for reach: the new ``configuration`` (the objects in the
    order given), its ``fidelity``, each moved diner's move, metres, by diner index
    (stated geometry), and the configuration of the pool each object taken from another
    lies as in, by object name (none stated)."""

    configuration: Configuration
    fidelity: Fidelity
    shifted_m: dict[int, float]
    taken_from: dict[str, int]


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
           pool: Sequence[Configuration], cache: dict[int, Floats] | None = None,
           last_resort: float = 0.0) -> Repaired | None:
    """``config`` with every diner whose objects are not all within sure reach repaired
    (see the module doc), or ``None`` when no diner needs or allows it. ``fidelity``:
    the configuration's measure (``None``: nothing was stated, and the diners' objects
    may be taken from the other configurations of ``pool``; ``cache`` keeps
    :func:`best_place_p` per configuration of the pool, by index). ``last_resort`` (a
    probability; 0: none): a stated setting makes the shortest move, up to
    :data:`LAST_RESORT_SHIFT_M` in any direction, with which every object is placed
    with at least that probability (for when no configuration has a plan otherwise)."""
    placements = list(config.placements)
    if not placements or any(p.diner is None for p in placements):
        return None
    table = ctx.scene.target_top
    seats = table.seats
    if max(p.diner for p in placements if p.diner is not None) >= len(seats):
        return None
    seated, top = _places(table)
    sure = sure_p(ctx)
    best = best_place_p(ctx, placements)
    shifted: dict[int, float] = {}
    taken: dict[str, int] = {}
    shapes: list[BaseGeometry | None] = [None] * len(placements)
    for d in sorted({p.diner for p in placements if p.diner is not None}):
        mine = [j for j, p in enumerate(placements) if p.diner == d]
        now = float(best[mine].min())
        if now >= sure:
            continue
        for j, p in enumerate(placements):
            if shapes[j] is None and p.diner != d:
                shapes[j] = _shape(p)
        others = [g for j, g in enumerate(shapes) if g is not None and j not in mine]
        group = [placements[j] for j in mine]
        if fidelity is not None:
            found = _shift(ctx, group, seated[d], top, others, sure, now, last_resort,
                           _toward_m(fidelity, group, seated[d]))
            if found is None:
                continue
            group, shifted[d] = found
        else:
            swap = _swap(ctx, group, pool, top, others, now, cache if cache is not None else {})
            if swap is None:
                continue
            group, k = swap
            taken.update((q.name, k) for q in group)
        for j, q in zip(mine, group, strict=True):
            placements[j], shapes[j] = q, None
        best[mine] = best_place_p(ctx, group)
    if fidelity is None:
        taken.update(_swap_objects(ctx, placements, best, pool, top, sure,
                                   cache if cache is not None else {}))
    if not shifted and not taken:
        return None
    repaired = Configuration(tuple(placements))
    fid = fidelity if fidelity is not None else Fidelity()
    if shifted:
        fid = _refit(fid, placements, seated, sum(shifted.values()))
    return Repaired(repaired, fid, shifted, taken)


@lru_cache(maxsize=16)
def _places(table: Table) -> tuple[tuple[Place, ...], BaseGeometry]:
    """The diners' places at ``table`` and its outline (the same top in every
    configuration and episode, so they are kept)."""
    return places(table, table.seats), outline(table)


def _shape(p: Placement) -> BaseGeometry:
    return footprint(p.x, p.y, p.yaw, p.shape, p.size)


def _fits(group: Sequence[BaseGeometry], top: BaseGeometry,
          others: Sequence[BaseGeometry]) -> bool:
    """Whether every footprint of ``group`` lies on ``top`` and clear of ``others``."""
    for shape in group:
        if not top.contains(shape):
            return False
        if any(shape.intersection(o).area > OVERLAP_M2 for o in others
               if shape.intersects(o)):
            return False
    return True


@lru_cache(maxsize=64)
def _offsets(place: Place, last_resort: bool = False) -> tuple[Floats, Floats, Floats]:
    """The moves a stated setting may make, nearest first: in the place frame, whole
    steps of :data:`STEP_M` along its width and towards its diner (never away), within
    :data:`MAX_SHIFT_M` (``last_resort``: steps of :data:`LAST_RESORT_STEP_M` every way,
    within :data:`LAST_RESORT_SHIFT_M`); as ``(k, 2)`` table-frame vectors, their lengths and
    how far each goes towards the diner, metres."""
    limit, step = (LAST_RESORT_SHIFT_M, LAST_RESORT_STEP_M) if last_resort \
        else (MAX_SHIFT_M, STEP_M)
    steps = int(round(limit / step))
    u, v = np.meshgrid(np.arange(-steps, steps + 1),
                       np.arange(-steps if last_resort else 0, steps + 1))
    u, v = step * u.ravel(), step * v.ravel()
    length = np.hypot(u, v)
    keep = (length > 0) & (length <= limit + 1e-9)
    u, v, length = u[keep], v[keep], length[keep]
    # Shortest first; of equal length, the one least across the place, then towards the
    # diner rather than away.
    order = np.lexsort((-v, np.abs(u), length))
    u, v, length = u[order], v[order], length[order]
    c, s = np.cos(place.yaw), np.sin(place.yaw)
    # Place-frame (u, -v) in the table frame: u along the place's x, v towards the diner.
    return np.stack([c * u + s * v, s * u - c * v], axis=1), length, v


def _shift(ctx: PlanningContext, group: Sequence[Placement], place: Place,
           top: BaseGeometry, others: Sequence[BaseGeometry], sure: float, now: float,
           last_resort: float = 0.0, toward_m: float = MAX_SHIFT_M
           ) -> tuple[list[Placement], float] | None:
    """``group`` moved whole, along its place's width or towards its diner (by at most
    ``toward_m``), by the shortest move of :func:`_offsets` that brings all of it within
    sure reach, else by the move that reaches its farthest object best; with the move's
    length, metres. ``None`` when no move gains. ``last_resort`` (a probability): any
    way, up to :data:`LAST_RESORT_SHIFT_M`, and placed that often counts as sure."""
    offsets, length, toward = _offsets(place, last_resort > 0)
    if last_resort <= 0:
        keep = toward <= toward_m + 1e-9
        offsets, length = offsets[keep], length[keep]
    box = ctx.scene.target_table.box
    c, s = np.cos(box.yaw), np.sin(box.yaw)
    room = np.stack([c * offsets[:, 0] - s * offsets[:, 1],
                     s * offsets[:, 0] + c * offsets[:, 1]], axis=1)
    pts = ctx.targets_room(group).reshape(-1, 2)
    # Only the standing positions that could reach some object after some move.
    near = np.hypot(pts[:, None, 0] - ctx.cand_xy[None, :, 0],
                    pts[:, None, 1] - ctx.cand_xy[None, :, 1]).min(axis=0)
    stands = ctx.cand_xy[near <= ctx.scene.robot.reach_max_m + length.max()]
    if not len(stands):
        return None
    moved_xy = pts[None, :, :] + room[:, None, :]                     # (k, n, 2)
    reach = np.hypot(moved_xy[..., None, 0] - stands[None, None, :, 0],
                     moved_xy[..., None, 1] - stands[None, None, :, 1])
    p = np.asarray(placing(ctx.model, reach, ctx.scene.robot), dtype=float)
    low = p.max(axis=2).min(axis=1)                                   # (k,)
    # The shortest move that makes all of it sure (offsets are nearest first), else the
    # move that reaches its farthest object best; each tried only if it fits.
    if last_resort > 0:
        # Not to be reached surely, only as often as asked, by the shortest move.
        sure = min(sure, last_resort)
    sure_k = [k for k in range(len(low)) if low[k] >= sure]
    rest = sorted((k for k in range(len(low)) if now + GAIN < low[k] < sure),
                  key=lambda k: (-low[k], length[k]))
    shapes = [_shape(q) for q in group]
    table = ctx.scene.target_top
    if not table.is_round:
        # A rectangle's top holds a shape exactly when it holds the shape's bounds.
        lo = np.min([g.bounds[:2] for g in shapes], axis=0)
        hi = np.max([g.bounds[2:] for g in shapes], axis=0)
        half = np.array([table.width / 2, table.depth / 2])
        on_top = np.all((lo + offsets >= -half) & (hi + offsets <= half), axis=1)
        sure_k = [k for k in sure_k if on_top[k]]
        rest = [k for k in rest if on_top[k]]
    for k in (*sure_k, *rest):
        dx, dy = float(offsets[k, 0]), float(offsets[k, 1])
        if _fits([translate(g, dx, dy) for g in shapes], top, others):
            return [replace(q, x=q.x + dx, y=q.y + dy) for q in group], float(length[k])
    return None


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
        if _fits([_shape(q) for q in variant], top, others):
            found = (low, k, variant)
    if found is None:
        return None
    return found[2], found[1]


def _swap_objects(ctx: PlanningContext, placements: list[Placement], best: Floats,
                  pool: Sequence[Configuration], top: BaseGeometry, sure: float,
                  cache: dict[int, Floats]) -> dict[str, int]:
    """Each object still beyond sure reach put where it lies in the configuration of
    ``pool`` from which it is reached most surely, when that spot is clear of every other
    object (``placements`` and ``best`` are updated); the configuration each came from,
    by object name."""
    taken: dict[str, int] = {}
    shapes = [_shape(p) for p in placements]
    for j, p in enumerate(placements):
        if best[j] >= sure:
            continue
        options = []
        for k, other in enumerate(pool):
            index = {q.name: i for i, q in enumerate(other.placements)}
            if p.name not in index:
                continue
            if k not in cache:
                cache[k] = best_place_p(ctx, other.placements)
            options.append((-float(cache[k][index[p.name]]), k, other.placements[index[p.name]]))
        rest = shapes[:j] + shapes[j + 1:]
        for minus_p, k, q in sorted(options, key=lambda o: (o[0], o[1])):
            if -minus_p <= best[j] + GAIN:
                break
            shape = _shape(q)
            if _fits([shape], top, rest):
                placements[j], shapes[j], best[j] = q, shape, -minus_p
                taken[p.name] = k
                break
    return taken


def _edge_m(p: Placement, place: Place) -> float:
    """The gap, metres, between ``p``'s footprint and its diner's edge of the table."""
    _, y = place.to_place(p.x, p.y)
    turn = p.yaw - place.yaw
    hy = p.size[0] / 2 if p.shape == "circle" else \
        (abs(np.sin(turn)) * p.size[0] + abs(np.cos(turn)) * p.size[1]) / 2
    return float(y) - hy + place.box.depth / 2


def _toward_m(fid: Fidelity, group: Sequence[Placement], place: Place) -> float:
    """How far, metres, ``group`` may move towards its diner: until its origin's distance
    from the diner's edge is :data:`EDGE_TOLERANCE_M` short of the stated one (no stated
    distance: :data:`MAX_SHIFT_M`)."""
    origins = set(fid.origin.split(", ")) if fid.origin else set()
    mine = [p for p in group if p.name in origins]
    if fid.edge_stated_m is None or not mine:
        return MAX_SHIFT_M
    short = _edge_m(mine[0], place) - (fid.edge_stated_m - EDGE_TOLERANCE_M)
    return min(max(short, 0.0), MAX_SHIFT_M)


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
        edge = _edge_m(p, seated[p.diner])
        if worst is None or abs(edge - fid.edge_stated_m) > abs(worst - fid.edge_stated_m):
            worst = edge
    return fid if worst is None else replace(fid, edge_realised_m=worst)
