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
from llm_grop.simulation.supply import ROUND_ARC_RAD, supply_layout
from llm_grop.world.arrangement import Item
from llm_grop.world.geometry2d import Box, Disc
from llm_grop.world.scene import Chair, Scene

#: Extra clearance, beyond the base radius, between chairs and the robot's start, metres.
START_CLEARANCE_M = 0.1
#: Clearance kept around sampled chairs, metres, so rounding in JSON never makes one touch.
CHAIR_CLEARANCE_M = 0.01
#: Draws per chair before giving up.
TRIES = 200
#: Times the whole set of chairs is drawn afresh before giving up.
RESTARTS = 20


def prepare_episode(scene: Scene, items: Sequence[Item], seed: int, *,
                    chairs: int | None = None,
                    chair_size_m: tuple[float, float] = (0.45, 0.45)) -> Scene:
    """``scene`` set up for the episode seeded ``seed`` with ``items``: chairs from the
    ``chairs`` random stream, object starts from the ``scene`` stream (:mod:`llm_grop.seeds`).

    Every item gets one source (:func:`~llm_grop.simulation.supply.supply_layout`): its
    own or its kind's from the scene (a kind's source goes to the first item of that kind
    only), else the top of a pile of its kind with room, else a random spot on a supply
    table, the items spread round-robin over the supply tables; each within the arm's sure
    reach from a side of its table. With ``chairs`` an int, that many
    chairs of ``chair_size_m`` (width, depth in metres) replace the scene's, on either long
    side of the target table (a round one: on the arcs within 45 degrees of its ±y axis,
    facing its centre), their near edge ``scene.chair_band_m`` from the table's edge;
    with ``None`` the scene's chairs stay.

    Raises :class:`BadInput` for a negative ``chairs`` and :class:`Infeasible` when the
    chairs or the objects do not fit (one line naming each object that does not, and why).
    """
    if chairs is not None:
        if chairs < 0:
            raise BadInput(f"chairs: must not be negative, got {chairs}")
        scene = scene.with_chairs(_sample_chairs(scene, chairs, chair_size_m,
                                                 seeds.stream(seed, "chairs")))
    spots = supply_layout(scene, items, seeds.stream(seed, "scene"))
    return scene.with_sources(tuple(s.source for s in spots))


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


def _poly(b: Box | Disc) -> Polygon:
    """``b``'s outline as a shapely polygon (room frame, metres)."""
    return Polygon(b.outline())
