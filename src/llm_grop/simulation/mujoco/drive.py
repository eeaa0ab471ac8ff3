"""The wheeled base's navigation stack in MuJoCo.

The base is a differential drive: it moves along its heading and turns, never sideways.
Its three planar joints are driven by velocity actuators whose force is limited to the
wheels' traction (:attr:`BaseOptions.traction_n`), as ManiSkill drives Fetch's base, so a
bump stops it or pushes what it meets, and what it pushes moves by physics.

Every control period (``CONTROL_STEPS`` physics steps):

1. the lidar scans at its own rate (:class:`~llm_grop.simulation.mujoco.lidar.Lidar`);
2. the path follower (pure pursuit, turning in place at sharp bends and for the final
   heading) picks a forward speed and a turn rate within the speed and acceleration
   limits;
3. the safety layer slows the base so that its footprint, carrying on along the commanded
   arc, would reach a lidar return no sooner than ``slow_horizon_s`` (Nav2's collision
   monitor, approach behaviour), and stops it when the allowed speed falls below
   ``min_speed_mps``: the drive then fails ``blocked`` and the executive replans around
   what was seen;
4. a contact between the robot and furniture (a chair leg between the lidar's beams, a
   table top above its plane) stops the drive: it fails ``contact``, the base backs off,
   and the contact points join what the lidar saw, for the replan (which drops those on
   furniture it already knows, so they matter where a chair was pushed or is unknown).

The goal checker declares arrival when the base is within ``xy_goal_tolerance_m`` of the
goal and then within ``yaw_goal_tolerance_rad`` of its heading, as Nav2's
SimpleGoalChecker does; the arrival error is whatever the controller achieved.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from llm_grop.simulation.mujoco.options import BaseOptions
from llm_grop.world.angles import wrap_angle
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import Point, Reason

if TYPE_CHECKING:
    from llm_grop.simulation.mujoco.world import World

#: How far, metres, the base moves before furniture it touched at the start counts again.
CLEAR_M = 0.3
#: A path vertex where the path turns by more than this is approached slowly and turned
#: at in place, radians.
SHARP_BEND_RAD = 0.35
#: The safety layer's arc is sampled every this many metres.
ARC_STEP_M = 0.02
#: The footprint never comes nearer than this to a lidar return, metres.
TOUCH_M = 0.005
#: Speeds below these count as standing still (metres per second, radians per second).
STILL_MPS, STILL_RADPS = 0.01, 0.02
#: The follower plans to brake at this share of the braking limit, keeping the rest to
#: correct with.
APPROACH = 0.7
#: The progress checker wants the base to move this far (metres) or turn this much
#: (radians) within ``progress_timeout_s``.
PROGRESS_M, PROGRESS_RAD = 0.1, 0.5
#: The base backs off this far after a bump, metres, at this speed, metres per second.
BACK_OFF_M, BACK_OFF_MPS = 0.08, 0.1


@dataclass(frozen=True)
class Drive:
    """How one drive ended: ``ok``, the points the base passed (room frame), the seconds
    it took, and for a failure its ``reason`` and ``note``. ``seen`` holds the lidar's
    last returns (room frame, metres), for replanning around them."""

    ok: bool
    path: tuple[Point, ...]
    duration_s: float
    reason: Reason | None = None
    note: str = ""
    seen: tuple[Point, ...] = ()


class _Limits:
    """Speed and acceleration limits, and the velocity the base was last commanded."""

    def __init__(self, w: World, o: BaseOptions) -> None:
        self.v_max, self.w_max = w.speed, w.turn_speed
        self.dt = w.m.opt.timestep * w.control_steps
        self.o = o
        self.v, self.w = w.base_velocity()

    def step(self, v: float, turn: float) -> tuple[float, float]:
        """The command nearest ``(v, turn)`` reachable within one control period."""
        dv, dw = self.o.accel_mps2 * self.dt, self.o.turn_accel_radps2 * self.dt
        self.v += min(max(v - self.v, -dv), dv)
        self.w += min(max(turn - self.w, -dw), dw)
        return self.v, self.w


def follow(w: World, path: Sequence[Point], goal: Pose2D, o: BaseOptions,
           time_limit_s: float = 120.0) -> Drive:
    """Drive along ``path`` (room frame, ending at the goal's position) and turn to
    ``goal.theta``; see the module docstring."""
    t0 = w.d.time
    start = w.base_pose()
    pts = [(start.x, start.y)] + [tuple(map(float, p)) for p in path]
    route = np.array([pts[0]] + [p for a, p in zip(pts, pts[1:], strict=False)
                                 if math.dist(a, p) > 1e-3])
    limits = _Limits(w, o)
    bodies = {int(w.m.geom_bodyid[g]) for g in w.touching_furniture()}
    chairs = w.chair_positions()
    passed: list[Point] = [(start.x, start.y)]
    seen = np.zeros((0, 2))
    next_scan = w.d.time
    mark, mark_yaw, mark_t = (start.x, start.y), start.theta, w.d.time
    arrived = False
    k = 0
    while True:
        p = w.base_pose()
        if w.d.time >= next_scan:
            seen = w.lidar.scan(w.d, p)
            next_scan += 1.0 / w.lidar.o.rate_hz
        d_goal = math.dist((p.x, p.y), (goal.x, goal.y))
        arrived = arrived or d_goal <= o.xy_goal_tolerance_m
        if arrived and abs(limits.v) >= STILL_MPS:
            # Within tolerance but still rolling: brake so as to stop at the goal, not past
            # it, as a controller's approach does.
            ahead = (goal.x - p.x) * math.cos(p.theta) + (goal.y - p.y) * math.sin(p.theta)
            v_cmd, w_cmd = math.sqrt(2 * APPROACH * o.accel_mps2 * max(ahead, 0.0)), 0.0
        elif arrived:
            e = wrap_angle(goal.theta - p.theta)
            if abs(e) <= o.yaw_goal_tolerance_rad:
                v_cmd, w_cmd = 0.0, 0.0
                if abs(limits.w) < STILL_RADPS:
                    _stop(w, limits)
                    return Drive(True, _ended(w, passed), w.d.time - t0,
                                 seen=_points(seen))
            else:
                v_cmd, w_cmd = 0.0, _turn_rate(e, limits)
        else:
            k = _closest(route, (p.x, p.y), k)
            v_cmd, w_cmd = _pursue(route, k, p, limits)
            if v_cmd > 0:
                curvature = w_cmd / v_cmd
                free = _free_distance(seen, p, curvature, w.radius,
                                      limits.v_max * o.slow_horizon_s, o)
                allowed = free / o.slow_horizon_s
                if allowed < o.min_speed_mps:
                    _stop(w, limits)
                    # Nav2's recovery: back up, when the lidar sees room behind, so that
                    # the replan has space to turn away.
                    if _free_distance(seen, _behind(w.base_pose()), 0.0, w.radius,
                                      BACK_OFF_M, o) > BACK_OFF_M:
                        back_off(w, o)
                    return Drive(False, _ended(w, passed), w.d.time - t0, "blocked",
                                 f"stopped {free:.2f} m before an obstacle the lidar sees",
                                 _points(seen))
                v_cmd = min(v_cmd, allowed)
                w_cmd = curvature * v_cmd
        w.command_base(*limits.step(v_cmd, w_cmd))
        w.advance(limits.dt)
        q = w.base_pose()
        near = math.dist((start.x, start.y), (q.x, q.y)) < CLEAR_M
        note = w.collisions(ignore_bodies=tuple(bodies) if near else ())
        if note:
            # Where it touched is an obstacle too, for the replan: a bumper's report.
            touched = np.array(w.furniture_contact_points()).reshape(-1, 2)
            _stop(w, limits)
            moved = w.chair_moved(chairs)
            if moved:
                note += f" (pushed chair {moved[0]!r} {moved[1] * 100:.1f} cm)"
            back_off(w, o)
            return Drive(False, _ended(w, passed), w.d.time - t0, "contact", note,
                         _points(np.vstack([seen, touched])))
        if math.dist(passed[-1], (q.x, q.y)) > 0.05:
            passed.append((q.x, q.y))
        if (math.dist(mark, (q.x, q.y)) > PROGRESS_M
                or abs(wrap_angle(q.theta - mark_yaw)) > PROGRESS_RAD):
            mark, mark_yaw, mark_t = (q.x, q.y), q.theta, w.d.time
        stalled = w.d.time - mark_t > o.progress_timeout_s
        if stalled or w.d.time - t0 > time_limit_s:
            _stop(w, limits)
            why = "made no progress towards the goal" if stalled else \
                f"did not arrive within {time_limit_s:.0f} s"
            return Drive(False, _ended(w, passed), w.d.time - t0, "blocked", why,
                         _points(seen))


def back_off(w: World, o: BaseOptions) -> None:
    """Move a little away from the furniture the robot bumped: backwards when the contact
    is ahead of the base's centre, forwards when behind (backwards when it touches
    nothing)."""
    p = w.base_pose()
    sign = -1.0
    for cx, cy in w.furniture_contact_points():
        ahead = (cx - p.x) * math.cos(p.theta) + (cy - p.y) * math.sin(p.theta)
        sign = -1.0 if ahead > 0 else 1.0
        break
    limits = _Limits(w, o)
    n = max(1, math.ceil(BACK_OFF_M / BACK_OFF_MPS / limits.dt))
    for _ in range(n):
        w.command_base(*limits.step(sign * BACK_OFF_MPS, 0.0))
        w.advance(limits.dt)
    _stop(w, limits)


def _stop(w: World, limits: _Limits, limit_s: float = 1.0) -> None:
    """Brake at the acceleration limits until the base stands still."""
    for _ in range(max(1, round(limit_s / limits.dt))):
        w.command_base(*limits.step(0.0, 0.0))
        w.advance(limits.dt)
        v, turn = w.base_velocity()
        if limits.v == 0 and limits.w == 0 and abs(v) < STILL_MPS and abs(turn) < STILL_RADPS:
            break
    w.command_base(0.0, 0.0)


def _behind(p: Pose2D) -> Pose2D:
    """``p`` facing the other way."""
    return Pose2D(p.x, p.y, wrap_angle(p.theta + math.pi))


def _ended(w: World, passed: list[Point]) -> tuple[Point, ...]:
    p = w.base_pose()
    if math.dist(passed[-1], (p.x, p.y)) > 1e-3:
        passed.append((p.x, p.y))
    return tuple(passed)


def _points(seen: np.ndarray) -> tuple[Point, ...]:
    return tuple((float(x), float(y)) for x, y in seen)


def _turn_rate(error: float, limits: _Limits) -> float:
    """A turn rate that stops at ``error`` radians away, braking at the limit."""
    rate = math.sqrt(2 * limits.o.turn_accel_radps2 * abs(error))
    return math.copysign(min(limits.w_max, rate), error)


def _closest(route: np.ndarray, xy: Point, k: int) -> int:
    """The index of the route segment (from ``k`` on) nearest ``xy``."""
    best, best_d = k, math.inf
    for i in range(k, min(len(route) - 1, k + 3)):
        a, b = route[i], route[i + 1]
        ab = b - a
        t = float(np.clip(np.dot(np.array(xy) - a, ab) / max(np.dot(ab, ab), 1e-12), 0, 1))
        d = float(np.hypot(*(a + t * ab - xy)))
        if d < best_d - 1e-9:
            best, best_d = i, d
    return best


def _pursue(route: np.ndarray, k: int, p: Pose2D, limits: _Limits) -> tuple[float, float]:
    """Forward speed and turn rate towards the carrot on the route: ``lookahead_m`` ahead
    of the base along segment ``k``, but never past a sharp bend or the route's end."""
    o = limits.o
    a, b = route[k], route[k + 1] if k + 1 < len(route) else route[k]
    ab = b - a
    seg = float(np.hypot(*ab))
    here = np.array([p.x, p.y])
    t = float(np.dot(here - a, ab) / seg) if seg > 1e-9 else 0.0
    # Distance left to the next stop: the end, or a vertex where the route bends sharply.
    stop = k + 1
    while stop < len(route) - 1 and _bend(route, stop) <= SHARP_BEND_RAD:
        stop += 1
    remaining = max(seg - t, 0.0) + sum(float(np.hypot(*(route[i + 1] - route[i])))
                                        for i in range(k + 1, stop))
    carrot = _along(route, k, t + o.lookahead_m, stop)
    dx, dy = carrot - here
    heading = math.atan2(dy, dx) if math.hypot(dx, dy) > 1e-6 else p.theta
    alpha = wrap_angle(heading - p.theta)
    if abs(alpha) > o.rotate_to_heading_rad:
        return 0.0, _turn_rate(alpha, limits)
    v = min(limits.v_max, math.sqrt(2 * APPROACH * o.accel_mps2 * remaining) + STILL_MPS)
    dist = max(math.hypot(dx, dy), 1e-6)
    turn = v * 2 * math.sin(alpha) / dist
    if abs(turn) > limits.w_max:
        v *= limits.w_max / abs(turn)
        turn = math.copysign(limits.w_max, turn)
    return v, turn


def _bend(route: np.ndarray, i: int) -> float:
    """How far the route turns at vertex ``i``, radians."""
    u, v = route[i] - route[i - 1], route[i + 1] - route[i]
    return abs(wrap_angle(math.atan2(v[1], v[0]) - math.atan2(u[1], u[0])))


def _along(route: np.ndarray, k: int, s: float, stop: int) -> np.ndarray:
    """The point ``s`` metres along the route from vertex ``k``, clipped at vertex
    ``stop``."""
    while k < stop:
        seg = float(np.hypot(*(route[k + 1] - route[k])))
        if s <= seg:
            return route[k] + (route[k + 1] - route[k]) * (s / max(seg, 1e-9))
        s -= seg
        k += 1
    return route[stop]


def _free_distance(seen: np.ndarray, p: Pose2D, curvature: float, radius_m: float,
                   horizon_m: float, o: BaseOptions) -> float:
    """How far, metres, the footprint can travel along the arc of ``curvature`` (1/m)
    before it comes within ``stop_margin_m`` of a lidar return it is approaching (looking
    ``horizon_m`` metres ahead; ``inf`` when nothing is in the way)."""
    if not len(seen):
        return math.inf
    reach = radius_m + o.stop_margin_m
    horizon = horizon_m + reach
    c, s = math.cos(p.theta), math.sin(p.theta)
    dx, dy = seen[:, 0] - p.x, seen[:, 1] - p.y
    local = np.stack([c * dx + s * dy, -s * dx + c * dy], axis=1)
    d0 = np.hypot(local[:, 0], local[:, 1])
    near = d0 < horizon + reach
    if not near.any():
        return math.inf
    local, d0 = local[near], d0[near]
    arc = np.arange(1, int(horizon / ARC_STEP_M) + 1) * ARC_STEP_M
    if abs(curvature) < 1e-6:
        cx, cy = arc, np.zeros_like(arc)
    else:
        cx, cy = np.sin(curvature * arc) / curvature, (1 - np.cos(curvature * arc)) / curvature
    d = np.hypot(local[None, :, 0] - cx[:, None], local[None, :, 1] - cy[:, None])
    # A return already within the margin (the base stands close to it, at a goal or after
    # a stop) only blocks a move that would all but touch it, so the base can leave.
    limit = np.where(d0 >= reach, reach, radius_m + TOUCH_M)
    blocked = ((d < limit[None, :]) & (d < d0[None, :] - 1e-3)).any(axis=1)
    if not blocked.any():
        return math.inf
    return float(arc[int(np.argmax(blocked))] - ARC_STEP_M)
