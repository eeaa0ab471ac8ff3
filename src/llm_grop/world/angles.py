"""The one convention for angles (radians): every heading and yaw llm-grop wraps, it wraps
with :func:`wrap_angle`, into ``(-pi, pi]``."""

from __future__ import annotations

import math

#: A full turn, radians.
TURN = 2 * math.pi


def wrap_angle(angle: float) -> float:
    """``angle`` (radians) turned by whole turns into ``(-pi, pi]``, radians.

    The half turn is ``pi`` whichever way it was reached: ``-pi`` becomes ``pi``.
    It is computed as ``fmod(angle + pi, 2 pi) - pi``, as the scene's frames and the
    planner always have, so that their numbers (and the paper experiment's rows) stay the
    same to the bit. ``angle + pi`` is rounded, so the result may be off the exact one by
    up to about 4.4e-16 rad (one unit in the last place of pi), even for an angle already
    in range, and an angle within about 2.2e-16 rad of a whole turn is exactly 0. Raises
    :class:`ValueError` for an infinite angle; NaN stays NaN.
    """
    a = math.fmod(angle + math.pi, TURN)
    if a <= 0:
        # fmod keeps the sign of its first argument; a 0 is the half turn's -pi end,
        # which this convention reads as pi.
        a += TURN
    return a - math.pi


__all__ = ["TURN", "wrap_angle"]
