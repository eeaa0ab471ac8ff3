"""Bringing a guided layout onto the table top: the smallest shift per axis that fits a
rectangle, and moves towards a round top's centre (metres, table frame)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from llm_grop.arrangement.predicates import Footprint


def smallest_shift(lo: float, hi: float, prefer: tuple[float, float] | None) -> float:
    """The shift nearest 0 within ``[lo, hi]`` (and within ``prefer`` if they meet)."""
    if lo > hi:
        return 0.0
    if prefer is not None and max(lo, prefer[0]) <= min(hi, prefer[1]):
        lo, hi = max(lo, prefer[0]), min(hi, prefer[1])
    return min(max(0.0, lo), hi)


def fit_circle(pos: dict[str, tuple[float, float]], foot: Mapping[str, Footprint],
               names: Sequence[str], radius: float, steps: int = 20) -> None:
    """Moves the layout towards a round top's centre until every footprint lies on it (or
    ``steps`` moves are spent): each move takes back the farthest object's overhang."""
    for _ in range(steps):
        worst, far = 0.0, (0.0, 0.0)
        for n in names:
            (x, y), f = pos[n], foot[n]
            reach = math.hypot(x, y) + f.hx if f.shape == "circle" else \
                math.hypot(abs(x) + f.hx, abs(y) + f.hy)
            if reach - radius > worst:
                worst, far = reach - radius, (x, y)
        norm = math.hypot(*far)
        if worst <= 1e-9 or norm == 0.0:
            return
        dx, dy = -worst * far[0] / norm, -worst * far[1] / norm
        for n in names:
            pos[n] = (pos[n][0] + dx, pos[n][1] + dy)
