"""The room's obstacles as a round base sees them: exact clearance and straight-line checks
(room frame, metres).

Walls and tables are the pre-built map; chairs are included on request. The room's outer
walls are its boundary. The planner plans in these obstacles and the simulators execute
in them, so they live below both.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from llm_grop.world.geometry2d import Box, Disc
from llm_grop.world.scene import Scene

Floats = NDArray[np.float64]


class Obstacles:
    """The obstacles of ``scene`` (rectangles, and discs for round tables), for exact
    clearance queries.

    Distances are computed in closed form per shape, not with a geometry library,
    because the sampling planner asks for one point at a time, tens of thousands of times.
    """

    def __init__(self, scene: Scene, include_chairs: bool = True,
                 extra: tuple[Box | Disc, ...] = ()) -> None:
        shapes = scene.static_obstacles() + extra
        if include_chairs:
            shapes = shapes + tuple(c.box for c in scene.chairs)
        boxes = [b for b in shapes if isinstance(b, Box)]
        self.width, self.depth = scene.width, scene.depth
        # (x, y, cos, sin, half width, half depth) per rectangle.
        self._boxes = tuple((b.x, b.y, math.cos(b.yaw), math.sin(b.yaw), b.width / 2,
                             b.depth / 2) for b in boxes)
        self._arr = np.array(self._boxes, dtype=float).reshape(-1, 6)
        # (x, y, radius) per disc.
        self._discs = tuple((d.x, d.y, d.radius) for d in shapes if isinstance(d, Disc))
        self._disc_arr = np.array(self._discs, dtype=float).reshape(-1, 3)

    def clearance(self, xy: Floats) -> Floats:
        """Distance, metres, from each room-frame point of ``xy`` (shape ``(N, 2)``) to the
        nearest obstacle or outer wall; 0 inside an obstacle or outside the room."""
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        x, y = pts[:, 0], pts[:, 1]
        d = np.minimum(np.minimum(x, self.width - x), np.minimum(y, self.depth - y))
        if len(self._arr):
            bx, by, c, s, hw, hd = (col[:, None] for col in self._arr.T)
            dx, dy = x[None, :] - bx, y[None, :] - by
            u = np.abs(c * dx + s * dy) - hw
            v = np.abs(-s * dx + c * dy) - hd
            inside = (u <= 0) & (v <= 0)
            dist = np.where(inside, 0.0, np.hypot(np.maximum(u, 0), np.maximum(v, 0)))
            d = np.minimum(d, dist.min(axis=0))
        if len(self._disc_arr):
            cx, cy, r = (col[:, None] for col in self._disc_arr.T)
            d = np.minimum(d, (np.hypot(x[None, :] - cx, y[None, :] - cy) - r).min(axis=0))
        return np.maximum(d, 0.0)

    def segment_free(self, a: tuple[float, float], b: tuple[float, float], radius_m: float,
                     step_m: float = 0.02, tolerance_m: float = 1e-9) -> bool:
        """Whether a disc of ``radius_m`` can move straight from ``a`` to ``b`` (checked
        every ``step_m`` metres), touching nothing by more than ``tolerance_m``."""
        n = max(2, math.ceil(math.dist(a, b) / step_m) + 1)
        return bool((self.clearance(np.linspace(a, b, n)) >= radius_m - tolerance_m).all())

    def free(self, x: float, y: float, radius_m: float) -> bool:
        """Whether a disc of ``radius_m`` at room-frame ``(x, y)`` touches nothing."""
        if x < radius_m or y < radius_m or x > self.width - radius_m \
                or y > self.depth - radius_m:
            return False
        r2 = radius_m * radius_m
        for bx, by, c, s, hw, hd in self._boxes:
            dx, dy = x - bx, y - by
            u = abs(c * dx + s * dy) - hw
            if u >= radius_m:
                continue
            v = abs(c * dy - s * dx) - hd
            if v >= radius_m:
                continue
            if u <= 0 or v <= 0 or u * u + v * v < r2:
                return False
        return all(math.hypot(x - cx, y - cy) >= r + radius_m for cx, cy, r in self._discs)
