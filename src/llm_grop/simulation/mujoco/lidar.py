"""The base's 2D laser scanner: rays cast in MuJoCo (``mj_multiRay``) in one horizontal
plane through the base's centre. It sees furniture, walls and tableware that cross its
scan plane; the robot itself and anything above or below the plane are invisible to it."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from llm_grop.simulation.mujoco.options import LidarOptions
from llm_grop.world.geometry2d import Pose2D

#: Geom groups the rays hit: the world's (furniture, walls, tableware: 0, and the collision
#: shapes behind drawn looks: 4), not the robot's (2) nor what is drawn only (1).
WORLD_GROUPS = np.array([1, 0, 0, 0, 1, 0], dtype=np.uint8)


class Lidar:
    """A planar scanner on the base body (``base_body``: its MuJoCo body id, excluded)."""

    def __init__(self, model: mujoco.MjModel, options: LidarOptions, base_body: int) -> None:
        self.m, self.o, self.base_body = model, options, base_body
        n = options.beams
        self.angles = np.arange(n) * (2 * math.pi / n)
        self._geomid = np.zeros(n, dtype=np.int32)
        self._dist = np.zeros(n, dtype=np.float64)
        #: The last sweep: simulated time (seconds), the base's pose and each ray's range
        #: (metres, ``inf`` for a miss), for an episode's observer.
        self.last: tuple[float, Pose2D, np.ndarray] | None = None

    def scan(self, data: mujoco.MjData, pose: Pose2D) -> np.ndarray:
        """Where the rays hit, ``(N, 2)`` room-frame points (metres), for the base at
        ``pose``; rays that hit nothing within range are left out."""
        a = self.angles + pose.theta
        vec = np.zeros((len(a), 3))
        vec[:, 0], vec[:, 1] = np.cos(a), np.sin(a)
        origin = np.array([pose.x, pose.y, self.o.height_m])
        mujoco.mj_multiRay(self.m, data, origin, vec.ravel(), WORLD_GROUPS, 1,
                           self.base_body, self._geomid, self._dist, None, len(a),
                           self.o.range_m)
        hit = (self._geomid >= 0) & (self._dist >= 0) & (self._dist <= self.o.range_m)
        self.last = (float(data.time), pose, np.where(hit, self._dist, np.inf))
        return origin[:2] + self._dist[hit, None] * vec[hit, :2]
