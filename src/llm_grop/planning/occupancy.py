"""The grid the robot plans on: clearance at every cell of the room (room frame, metres).

The pre-built map holds the interior walls and every table; chairs are added when the
robot senses them (``include_chairs``). The room's outer walls are its boundary.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from llm_grop.geometry.obstacles import Floats, Obstacles
from llm_grop.world.scene import Scene


@dataclass(frozen=True)
class OccupancyGrid:
    """A grid over the room: cell ``(i, j)`` has its centre at
    ``((j + 0.5) * resolution_m, (i + 0.5) * resolution_m)``; ``clearance_m[i, j]`` is the
    centre's distance to the nearest obstacle, metres (rows are y, columns are x)."""

    resolution_m: float
    clearance_m: Floats

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, columns)``."""
        return self.clearance_m.shape  # type: ignore[return-value]

    def cell_of(self, xy: Floats) -> NDArray[np.int64]:
        """The ``(row, column)`` of each room-frame point, clipped to the grid, ``(N, 2)``."""
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        rows, cols = self.shape
        j = np.clip(np.floor(pts[:, 0] / self.resolution_m), 0, cols - 1).astype(np.int64)
        i = np.clip(np.floor(pts[:, 1] / self.resolution_m), 0, rows - 1).astype(np.int64)
        return np.stack([i, j], axis=1)

    def centre_of(self, cells: NDArray[np.int64]) -> Floats:
        """Room-frame centres of ``(row, column)`` cells, ``(N, 2)`` metres."""
        cells = np.asarray(cells).reshape(-1, 2)
        return (cells[:, ::-1] + 0.5) * self.resolution_m

def build_grid(scene: Scene, resolution_m: float = 0.05,
               include_chairs: bool = True) -> OccupancyGrid:
    """The occupancy grid of ``scene`` with exact clearance at every cell centre."""
    cols = max(1, int(np.ceil(scene.width / resolution_m)))
    rows = max(1, int(np.ceil(scene.depth / resolution_m)))
    jj, ii = np.meshgrid(np.arange(cols), np.arange(rows))
    centres = (np.stack([jj.ravel(), ii.ravel()], axis=1) + 0.5) * resolution_m
    clearance = Obstacles(scene, include_chairs).clearance(centres).reshape(rows, cols)
    return OccupancyGrid(resolution_m, clearance)
