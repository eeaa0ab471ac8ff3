"""Setting up an episode: where each requested object starts and which chairs stand around
the target table (room frame, metres and radians).

Everything is drawn from the seed's own random streams, so a seed fixes the episode; drawn
positions are rounded to 0.1 mm, so the run JSON's scene reads back as the same scene. Chairs
and objects' starts have generators of their own, so the same seed gives the same chairs
whatever is requested (methods compared on a seed see the same room).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from shapely.geometry import Point, Polygon
from shapely.geometry import box as rect

from llm_grop import seeds
from llm_grop.errors import BadInput, Infeasible
from llm_grop.files.jsonio import rounded
from llm_grop.world.arrangement import Item
from llm_grop.world.geometry2d import Box, Disc
from llm_grop.world.scene import Chair, ObjectSource, Scene, SceneTable

#: Smallest radius of the disc an object occupies on a supply table while it waits, metres;
#: larger objects take the disc round their footprint.
OBJECT_RADIUS_M = 0.06
#: Gap kept between two waiting objects' discs, metres.
OBJECT_GAP_M = 0.01
#: Clearance between a waiting object's disc and its table's edge, metres.
EDGE_MARGIN_M = 0.05
#: Extra clearance, beyond the base radius, between chairs and the robot's start, metres.
START_CLEARANCE_M = 0.1
#: Clearance kept around sampled chairs, metres, so rounding in JSON never makes one touch.
CHAIR_CLEARANCE_M = 0.01
#: Waiting objects lie at most this far, metres, from a table edge the robot can stand at,
#: so that the arm reaches them comfortably.
EDGE_BAND_M = 0.20
#: Chairs at a round table stand within this angle, radians, either side of its ±y axis.
ROUND_ARC_RAD = math.pi / 4
#: Step, metres, of the sweep along a crowded supply table's edge (see ``_free_spot``).
SWEEP_STEP_M = 0.01
#: Draws per chair and per object and table before giving up.
TRIES = 200
#: Times the whole set of chairs is drawn afresh before giving up.
RESTARTS = 20


def prepare_episode(scene: Scene, items: Sequence[Item], seed: int, *,
                    chairs: int | None = None,
                    chair_size_m: tuple[float, float] = (0.45, 0.45)) -> Scene:
    """``scene`` set up for the episode seeded ``seed`` with ``items``: chairs from the
    ``chairs`` random stream, object starts from the ``scene`` stream (:mod:`llm_grop.seeds`).

    Every item gets one source: its own or its kind's from the scene (a kind's source
    goes to the first item of that kind only), else a random spot on a supply table, the
    items spread round-robin over the supply tables. With ``chairs`` an int, that many
    chairs of ``chair_size_m`` (width, depth in metres) replace the scene's, on either long
    side of the target table (a round one: on the arcs within 45 degrees of its ±y axis,
    facing its centre), their near edge ``scene.chair_band_m`` from the table's edge;
    with ``None`` the scene's chairs stay.

    Raises :class:`BadInput` for a negative ``chairs`` and :class:`Infeasible` when the
    chairs or the objects do not fit.
    """
    if chairs is not None:
        if chairs < 0:
            raise BadInput(f"chairs: must not be negative, got {chairs}")
        scene = scene.with_chairs(_sample_chairs(scene, chairs, chair_size_m,
                                                 seeds.stream(seed, "chairs")))
    return scene.with_sources(_assign_sources(scene, items, seeds.stream(seed, "scene")))


def _sample_chairs(scene: Scene, n: int, size: tuple[float, float],
                   rng: np.random.Generator) -> tuple[Chair, ...]:
    best: list[Chair] = []
    # Chairs placed one by one can box each other out; starting over usually fits them.
    for _ in range(RESTARTS):
        chairs = _chair_round(scene, n, size, rng)
        if len(chairs) == n:
            return tuple(chairs)
        best = max(best, chairs, key=len)
    lo, hi = scene.chair_band_m
    plural = "chair" if n == 1 else "chairs"
    raise Infeasible(f"cannot place {n} {plural} near {scene.target!r}: at most {len(best)} "
                     f"fit {lo:g}-{hi:g} m from its ±y sides")


def _chair_round(scene: Scene, n: int, size: tuple[float, float],
                 rng: np.random.Generator) -> list[Chair]:
    """Up to ``n`` chairs placed one after another; fewer when one does not fit."""
    target = scene.target_table
    table = target.box
    lo, hi = scene.chair_band_m
    cw, cd = size
    room = rect(0.0, 0.0, scene.width, scene.depth)
    blocked = [_poly(b) for b in scene.static_obstacles()]
    start = scene.robot_start
    keep_off = Point(start.x, start.y).buffer(scene.robot.base_radius_m + START_CLEARANCE_M)
    out: list[Chair] = []
    for k in range(n):
        for _ in range(TRIES):
            side = 1.0 if rng.random() < 0.5 else -1.0
            if target.is_round:
                # Round the arc on that side, the chair's back away from the centre.
                phi = side * math.pi / 2 + rng.uniform(-ROUND_ARC_RAD, ROUND_ARC_RAD)
                reach = table.width / 2 + rng.uniform(lo, hi) + cd / 2
                u, v = reach * math.cos(phi), reach * math.sin(phi)
                yaw = rounded(table.yaw + phi - math.pi / 2)
            else:
                u = rng.uniform(-table.width / 2, table.width / 2)
                v, yaw = side * (table.depth / 2 + rng.uniform(lo, hi) + cd / 2), table.yaw
            x, y = (rounded(c) for c in table.to_room(u, v))
            box = Box(x, y, cw, cd, yaw)
            grown = _poly(box).buffer(CHAIR_CLEARANCE_M, join_style="mitre")
            if (room.contains(grown) and not grown.intersects(keep_off)
                    and not any(grown.intersects(p) for p in blocked)):
                out.append(Chair(f"chair {k + 1}", box))
                blocked.append(_poly(box))
                break
        else:
            return out
    return out


def _assign_sources(scene: Scene, items: Sequence[Item],
                    rng: np.random.Generator) -> tuple[ObjectSource, ...]:
    given: dict[str, ObjectSource] = {}
    used: set[ObjectSource] = set()
    for item in items:
        s = scene.source_for(item.name, item.kind)
        if s is not None and s not in used:
            used.add(s)
            given[item.name] = ObjectSource(item.name, s.table, s.x, s.y)
    radius = {i.name: _radius(i) for i in items}
    half = {i.name: (i.spec.size[0] / 2, i.spec.size[1] / 2) for i in items}
    taken = [(s.x, s.y, radius[n], *half[n]) for n, s in given.items()]
    supply = scene.supply_tables
    out: list[ObjectSource] = []
    turn = 0
    for item in items:
        if item.name in given:
            out.append(given[item.name])
            continue
        if not supply:
            raise Infeasible(f"no supply table for {item.name!r}: the scene has no table "
                             "besides the target")
        for j in range(len(supply)):
            table = supply[(turn + j) % len(supply)]
            spot = _free_spot(scene, table, taken, radius[item.name], rng, half[item.name])
            if spot is not None:
                break
        else:
            names = ", ".join(repr(t.name) for t in supply)
            raise Infeasible(f"cannot fit {item.name!r} on the supply tables ({names})")
        turn += 1
        taken.append((*spot, radius[item.name], *half[item.name]))
        out.append(ObjectSource(item.name, table.name, *spot))
    return tuple(out)


def _radius(item: Item) -> float:
    """Radius, metres, of the disc round ``item``'s footprint (at least
    :data:`OBJECT_RADIUS_M`)."""
    sx, sy = item.spec.size
    r = sx / 2 if item.spec.shape == "circle" else math.hypot(sx, sy) / 2
    return max(OBJECT_RADIUS_M, r)


def _free_spot(scene: Scene, table: SceneTable,
               taken: list[tuple[float, float, float, float, float]], radius: float,
               rng: np.random.Generator, half: tuple[float, float] = (0.0, 0.0)
               ) -> tuple[float, float] | None:
    """A random room-frame point on ``table``, within :data:`EDGE_BAND_M` of an edge the
    robot can stand at, whose object disc (``radius`` metres) is clear of the edge and of
    the discs ``(x, y, radius, ...)`` in ``taken``; ``None`` when none turns up.

    When random draws find no room, the band along each open side is swept for the first
    spot where the object's footprint (half sides ``half``, unturned in the room) keeps
    :data:`OBJECT_GAP_M` from every waiting footprint: a fork stood across a counter's
    edge takes a few centimetres of it, not the disc round it."""
    box = table.box
    inset = EDGE_MARGIN_M + radius
    hw, hd = box.width / 2 - inset, box.depth / 2 - inset
    if hw < 0 or hd < 0:
        return None
    sides = _open_sides(scene, table)
    if not sides:
        return None
    for _ in range(TRIES):
        du, dv = sides[int(rng.integers(len(sides)))]
        u, v = rng.uniform(-hw, hw), rng.uniform(-hd, hd)
        if table.is_round:
            # On the arc facing the open side, its edge gap between the inset and the band.
            phi = math.atan2(dv, du) + rng.uniform(-ROUND_ARC_RAD, ROUND_ARC_RAD)
            reach = box.width / 2 - rng.uniform(inset, max(inset, EDGE_BAND_M))
            u, v = reach * math.cos(phi), reach * math.sin(phi)
        # Pull the point towards the chosen open side, into the band along it.
        elif du:
            u = du * (box.width / 2 - min(box.width / 2 - u * du, EDGE_BAND_M))
            u = float(np.clip(u, -hw, hw))
        else:
            v = dv * (box.depth / 2 - min(box.depth / 2 - v * dv, EDGE_BAND_M))
            v = float(np.clip(v, -hd, hd))
        x, y = (rounded(c) for c in box.to_room(u, v))
        if all(math.hypot(x - tx, y - ty) >= radius + tr + OBJECT_GAP_M
               for tx, ty, tr, _, _ in taken):
            return (x, y)
    if table.is_round or box.yaw != 0.0:
        return None
    # A crowded table (several diners' tableware): sweep each open side's band in
    # :data:`SWEEP_STEP_M` steps for the first free spot, so the tables fill up.
    bw = box.width / 2 - EDGE_MARGIN_M - half[0]
    bd = box.depth / 2 - EDGE_MARGIN_M - half[1]
    if bw < 0 or bd < 0:
        return None
    for du, dv in sides:
        along = np.arange(-(bd if du else bw), (bd if du else bw) + 1e-9, SWEEP_STEP_M)
        for t in along:
            u = du * bw if du else float(t)
            v = dv * bd if dv else float(t)
            x, y = (rounded(c) for c in box.to_room(u, v))
            if all(abs(x - tx) >= half[0] + hx + OBJECT_GAP_M
                   or abs(y - ty) >= half[1] + hy + OBJECT_GAP_M
                   for tx, ty, _, hx, hy in taken):
                return (x, y)
    return None


def _open_sides(scene: Scene, table: SceneTable) -> list[tuple[int, int]]:
    """The sides of ``table`` (as outward unit directions in its own frame) in front of
    whose middle the robot's base fits."""
    box = table.box
    radius = scene.robot.base_radius_m
    obstacles = [_poly(b) for b in scene.static_obstacles()]
    room = rect(0.0, 0.0, scene.width, scene.depth)
    out = []
    for du, dv in ((0, -1), (0, 1), (-1, 0), (1, 0)):
        gap = 0.1 + radius
        x, y = box.to_room(du * (box.width / 2 + gap), dv * (box.depth / 2 + gap))
        base = Point(x, y).buffer(radius)
        if room.contains(base) and not any(base.intersects(p) for p in obstacles):
            out.append((du, dv))
    return out


def _poly(b: Box | Disc) -> Polygon:
    """``b``'s outline as a shapely polygon (room frame, metres)."""
    return Polygon(b.outline())
