"""The footprint of an object on a table, as a shapely shape (table frame, metres)."""

from __future__ import annotations

import math

from shapely.geometry import Point, Polygon
from shapely.geometry.base import BaseGeometry


def footprint(x: float, y: float, yaw: float, shape: str, size: tuple[float, float]
              ) -> BaseGeometry:
    """The footprint polygon in the table frame (a circle of diameter ``size[0]``, or a
    ``size`` box turned by ``yaw`` radians counter-clockwise)."""
    if shape == "circle":
        return Point(x, y).buffer(size[0] / 2, quad_segs=32)
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = size[0] / 2, size[1] / 2
    return Polygon([(x + c * u - s * v, y + s * u + c * v)
                    for u, v in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))])
