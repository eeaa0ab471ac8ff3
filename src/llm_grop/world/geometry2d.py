"""Poses, rectangles and discs in the room frame (metres, radians). Representation only."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Pose2D:
    """A pose in the room frame: position ``x``, ``y`` in metres, heading ``theta`` in radians
    (counter-clockwise from +x)."""

    x: float
    y: float
    theta: float = 0.0

    def as_list(self) -> list[float]:
        """``[x, y, theta]``, the contract's pose form."""
        return [self.x, self.y, self.theta]


@dataclass(frozen=True)
class Box:
    """A rectangle in the room frame: centre ``(x, y)`` in metres, ``width`` along its own x,
    ``depth`` along its own y (metres), turned by ``yaw`` radians counter-clockwise."""

    x: float
    y: float
    width: float
    depth: float
    yaw: float = 0.0

    def corners(self) -> tuple[tuple[float, float], ...]:
        """The four corners in the room frame, counter-clockwise from the box's (-x, -y) corner."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        hw, hd = self.width / 2, self.depth / 2
        return tuple(
            (self.x + c * u - s * v, self.y + s * u + c * v)
            for u, v in ((-hw, -hd), (hw, -hd), (hw, hd), (-hw, hd))
        )

    def to_local(self, x: float, y: float) -> tuple[float, float]:
        """Room-frame point ``(x, y)`` in this box's own frame (origin at its centre)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        dx, dy = x - self.x, y - self.y
        return (c * dx + s * dy, -s * dx + c * dy)

    def to_room(self, u: float, v: float) -> tuple[float, float]:
        """A point ``(u, v)`` of this box's own frame in the room frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return (self.x + c * u - s * v, self.y + s * u + c * v)

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        """Whether room-frame point ``(x, y)`` is inside the box grown by ``margin`` metres."""
        u, v = self.to_local(x, y)
        return abs(u) <= self.width / 2 + margin and abs(v) <= self.depth / 2 + margin

    def outline(self) -> tuple[tuple[float, float], ...]:
        """The footprint's outline as polygon vertices in the room frame: its corners."""
        return self.corners()


@dataclass(frozen=True)
class Disc:
    """A circle in the room frame: centre ``(x, y)`` and ``radius``, metres."""

    x: float
    y: float
    radius: float

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        """Whether room-frame point ``(x, y)`` is inside the disc grown by ``margin`` metres."""
        return math.hypot(x - self.x, y - self.y) <= self.radius + margin

    def outline(self, segments: int = 64) -> tuple[tuple[float, float], ...]:
        """A regular polygon of ``segments`` sides round the disc, counter-clockwise.

        Its sides touch the circle (the vertices lie ``radius / cos(pi / segments)`` from
        the centre), so the polygon covers the whole disc: an obstacle drawn from it is
        never smaller than the true one (by under 1 mm for a 1.2 m table at 64 sides).
        """
        r = self.radius / math.cos(math.pi / segments)
        return tuple((self.x + r * math.cos(2 * math.pi * k / segments),
                      self.y + r * math.sin(2 * math.pi * k / segments))
                     for k in range(segments))
