"""The grid the robot plans on: clearance at every cell of the room (room frame, metres).

The pre-built map holds the interior walls and every table; chairs are added when the
robot senses them (``include_chairs``). The room's outer walls are its boundary.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import cast

import numpy as np
from numpy.typing import NDArray

from llm_grop.geometry.obstacles import Floats, Obstacles
from llm_grop.world.geometry2d import Box, Disc
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
    """The occupancy grid of ``scene`` with exact clearance at every cell centre.

    The clearance is the least of each obstacle's, so the pre-built map's part (walls and
    tables, the same in every episode of a room) is computed once per room and kept
    (:func:`_map_clearance`), and only the chairs' is computed per episode."""
    room = _Room(scene.width, scene.depth, scene.static_obstacles())
    centres, clearance = _map_clearance(room, resolution_m)
    if include_chairs and scene.chairs:
        chairs = _Room(scene.width, scene.depth, tuple(c.box for c in scene.chairs))
        clearance = np.minimum(clearance, _obstacles(chairs).clearance(centres))
    rows = max(1, int(np.ceil(scene.depth / resolution_m)))
    return OccupancyGrid(resolution_m, clearance.reshape(rows, -1))


@dataclass(frozen=True)
class _Room:
    """A room's size, metres, and some of its obstacles: what :class:`Obstacles` reads
    of a scene."""

    width: float
    depth: float
    shapes: tuple[Box | Disc, ...]
    chairs: tuple[()] = ()

    def static_obstacles(self) -> tuple[Box | Disc, ...]:
        return self.shapes


def _obstacles(room: _Room) -> Obstacles:
    return Obstacles(cast(Scene, room), include_chairs=False)


@lru_cache(maxsize=16)
def _map_clearance(room: _Room, resolution_m: float) -> tuple[Floats, Floats]:
    """The cell centres of ``room``'s grid, ``(N, 2)``, and their clearance from its
    obstacles, ``(N,)``, metres (read-only: a cache of a pure function)."""
    cols = max(1, int(np.ceil(room.width / resolution_m)))
    rows = max(1, int(np.ceil(room.depth / resolution_m)))
    jj, ii = np.meshgrid(np.arange(cols), np.arange(rows))
    centres = (np.stack([jj.ravel(), ii.ravel()], axis=1) + 0.5) * resolution_m
    clearance = _obstacles(room).clearance(centres)
    centres.flags.writeable = False
    clearance.flags.writeable = False
    return centres, clearance
