"""Driving a path: its length, the turns on the way and how long it takes (room frame,
metres, radians, seconds). The planner predicts with these and the simulators execute
with them."""

from __future__ import annotations

import math
from collections.abc import Sequence

from llm_grop.world.angles import wrap_angle
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.robot import Robot


def turning_rad(start: Pose2D, goal: Pose2D, path: Sequence[tuple[float, float]]) -> float:
    """Radians turned in place driving ``path`` from ``start``: to each segment's heading,
    then to the goal's heading."""
    heading, total = start.theta, 0.0
    for a, b in zip(path, path[1:], strict=False):
        if math.dist(a, b) < 1e-9:
            continue
        h = math.atan2(b[1] - a[1], b[0] - a[0])
        total += abs(wrap_angle(h - heading))
        heading = h
    return total + abs(wrap_angle(goal.theta - heading))


def path_length_m(path: Sequence[tuple[float, float]]) -> float:
    """Length of a polyline, metres."""
    return sum(math.dist(a, b) for a, b in zip(path, path[1:], strict=False))


def leg_duration_s(start: Pose2D, goal: Pose2D, path: Sequence[tuple[float, float]],
                   robot: Robot) -> float:
    """Seconds to drive ``path`` at the robot's speed, turning in place at its corners."""
    return path_length_m(path) / robot.speed_mps \
        + turning_rad(start, goal, path) / robot.turn_speed_radps


def arrival_error(here: Pose2D, goal: Pose2D) -> tuple[float, float]:
    """How far a base standing at ``here`` is from ``goal``: distance (metres) and absolute
    heading difference (radians), rounded to 0.1 mm and 0.1 mrad."""
    return (round(math.dist((here.x, here.y), (goal.x, goal.y)), 4),
            round(abs(wrap_angle(here.theta - goal.theta)), 4))


#: The former name of :func:`~llm_grop.world.angles.wrap_angle` (which wraps into
#: ``(-pi, pi]``; this module's own wrap gave ``-pi`` for the half turn).
wrap = wrap_angle


def path_prefix(path: Sequence[tuple[float, float]], distance_m: float
                ) -> tuple[tuple[float, float], ...]:
    """The first ``distance_m`` metres of ``path``."""
    out = [path[0]]
    left = distance_m
    for a, b in zip(path, path[1:], strict=False):
        seg = math.dist(a, b)
        if seg >= left:
            f = left / seg if seg > 0 else 0.0
            out.append((a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])))
            return tuple(out)
        out.append(b)
        left -= seg
    return tuple(out)
