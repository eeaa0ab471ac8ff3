"""Standing positions (``loc`` in the paper): where the base may stand next to a table.

Candidates lie on loops around the table's top at several stand-off distances (its
outline grown by the stand-off plus the base's radius, so corners are rounded; circles
round a round table), spaced evenly all the way round, each facing the nearest point of
the table (a round table's centre). A candidate is kept only where the base's footprint
touches nothing: walls, tables and sensed chairs.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np
import shapely
from shapely.geometry import Point, Polygon

from llm_grop.errors import Infeasible
from llm_grop.geometry.obstacles import Floats, Obstacles
from llm_grop.planning.feasibility import FeasibilityModel
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import StandingPose
from llm_grop.world.robot import Robot
from llm_grop.world.scene import ObjectSource, Scene, SceneTable


@lru_cache(maxsize=64)
def _loop_points(table: SceneTable, base_radius_m: float, spacing_m: float,
                 standoffs_m: tuple[float, ...]) -> tuple[Floats, Floats]:
    """Points on the loops round the table, ``(N, 2)``, and their headings, ``(N,)`` radians
    (read-only: the same table gives the same loops in every episode, so they are kept)."""
    xy, heading = _loops(table, base_radius_m, spacing_m, standoffs_m)
    xy.flags.writeable = False
    heading.flags.writeable = False
    return xy, heading


def _loops(table: SceneTable, base_radius_m: float, spacing_m: float,
           standoffs_m: tuple[float, ...]) -> tuple[Floats, Floats]:
    """:func:`_loop_points`, computed."""
    box = table.box
    # A round top's loops are circles (its buffer), and its nearest point lies towards
    # the centre, so every candidate faces the centre.
    top = Point(box.x, box.y).buffer(box.width / 2, quad_segs=64) if table.is_round \
        else Polygon(box.corners())
    pts: list[Floats] = []
    for standoff in standoffs_m:
        ring = top.buffer(standoff + base_radius_m, quad_segs=8).exterior
        n = max(8, int(round(ring.length / spacing_m)))
        along = np.arange(n) * ring.length / n
        pts.append(shapely.get_coordinates(shapely.line_interpolate_point(ring, along)))
    xy = np.concatenate(pts)
    if table.is_round:
        return xy, np.arctan2(box.y - xy[:, 1], box.x - xy[:, 0])
    c, s = np.cos(box.yaw), np.sin(box.yaw)
    dx, dy = xy[:, 0] - box.x, xy[:, 1] - box.y
    u = np.clip(c * dx + s * dy, -box.width / 2, box.width / 2)
    v = np.clip(-s * dx + c * dy, -box.depth / 2, box.depth / 2)
    near = np.stack([box.x + c * u - s * v, box.y + s * u + c * v], axis=1)
    heading = np.arctan2(near[:, 1] - xy[:, 1], near[:, 0] - xy[:, 0])
    return xy, heading


def candidate_standing_poses(scene: Scene, table_name: str, robot: Robot, *,
                             spacing_m: float = 0.10,
                             standoffs_m: Sequence[float] = (0.05, 0.10, 0.15, 0.25),
                             include_chairs: bool = True) -> tuple[StandingPose, ...]:
    """Collision-free standing positions around table ``table_name``, facing it.

    ``spacing_m`` is the distance between neighbours along a loop and ``standoffs_m`` the
    gaps, metres, between the table's edge and the base's footprint.
    """
    xy, heading = _loop_points(scene.table(table_name), robot.base_radius_m, spacing_m,
                               tuple(standoffs_m))
    clearance = Obstacles(scene, include_chairs).clearance(xy) - robot.base_radius_m
    keep = np.flatnonzero(clearance >= -1e-9)
    return tuple(StandingPose(Pose2D(float(xy[i, 0]), float(xy[i, 1]), float(heading[i])),
                              max(float(clearance[i]), 0.0), table_name) for i in keep)


def reach(poses: Sequence[StandingPose], xy: Floats) -> Floats:
    """Horizontal distance, metres, from each pose's base centre to each point: ``(P, n)``."""
    base = np.array([[p.pose.x, p.pose.y] for p in poses]).reshape(-1, 2)
    pts = np.asarray(xy, dtype=float).reshape(-1, 2)
    return np.hypot(base[:, None, 0] - pts[None, :, 0], base[:, None, 1] - pts[None, :, 1])


def pickup_pose(scene: Scene, source: ObjectSource, robot: Robot, model: FeasibilityModel,
                candidates: Sequence[StandingPose] | None = None) -> StandingPose:
    """The standing position at the object's table where picking it up is likeliest to
    succeed (navigation times manipulation); ties go to the first candidate."""
    if candidates is None:
        candidates = candidate_standing_poses(scene, source.table, robot)
    if not candidates:
        raise Infeasible(f"no free standing position next to table {source.table!r}, "
                         f"where {source.object!r} starts")
    nav = model.navigation(np.array([c.clearance_m for c in candidates]))
    manip = model.manipulation(reach(candidates, np.array([[source.x, source.y]]))[:, 0], robot)
    p = nav * manip
    best = int(np.argmax(p))
    if p[best] <= 0:
        raise Infeasible(f"{source.object!r} at ({source.x:.2f}, {source.y:.2f}) on table "
                         f"{source.table!r} is out of the arm's reach "
                         f"({robot.reach_max_m:.2f} m) from every standing position")
    return candidates[best]


def blocked_reason(scene: Scene, table_name: str, robot: Robot) -> str:
    """Why no standing position around ``table_name`` is free (for an :class:`Infeasible`)."""
    free_without_chairs = candidate_standing_poses(scene, table_name, robot,
                                                   include_chairs=False)
    if free_without_chairs and scene.chairs:
        names = ", ".join(c.name for c in scene.chairs)
        return (f"the sensed chairs ({names}) block every side of table {table_name!r}: "
                f"no standing position is free for a base of radius "
                f"{robot.base_radius_m:.2f} m")
    return (f"no standing position around table {table_name!r} is free for a base of "
            f"radius {robot.base_radius_m:.2f} m: walls or other tables are too close")
