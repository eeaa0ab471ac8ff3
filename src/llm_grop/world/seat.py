"""Where a diner sits at the target table. Representation only."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Seat:
    """A diner's seat pose in the table frame: ``x``, ``y`` in metres, at or beyond the
    table's edge, and ``yaw``, the direction the diner faces, radians (counter-clockwise
    from +x). The contract's single diner sits at ``(0, -depth/2)`` facing ``pi/2``."""

    x: float
    y: float
    yaw: float = math.pi / 2

    def as_list(self) -> list[float]:
        """``[x, y, yaw]``, the contract's pose form."""
        return [self.x, self.y, self.yaw]
