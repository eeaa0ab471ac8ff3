"""Picking and placing tableware with the arm, in physics.

A pick goes pre-grasp, grasp, close, lift, carry; a place goes pre-place, lower, release,
retreat, and physics settles the object. An attempt fails when no IK solution reaches the
pose (after the robot's ``ik_failure_s`` of planning), when the arm or what it holds
touches furniture, or when the pads close on nothing. Where a released object comes to
rest (upright or tipped, on its support or not) is for the executive to judge.

Holding uses a contact-triggered weld: when both pads touch the object after closing, a
weld between hand and object switches on, and it switches off at release. Thin cutlery and
plate rims are too small for MuJoCo's soft contacts to hold through a drive across the room,
so every object is held this way; the pads must still reach and touch it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from llm_grop.simulation.mujoco.tableware import MAX_OPENING_M
from llm_grop.simulation.mujoco.world import World
from llm_grop.world.plan import Reason

#: Height of the pre-grasp and pre-place poses above the grasp (metres).
APPROACH_M = 0.10
#: An object is released this high above its surface (metres).
DROP_M = 0.006
#: Where the hand lets go of an abandoned object: beside the base, left then right, below
#: any table top and clear of the table the robot faces (base frame, metres).
DROP_POINTS = ((0.0, 0.5, 0.4), (0.0, -0.5, 0.4))


@dataclass(frozen=True)
class Attempt:
    """How one pick or place went: ``ok``, the simulated ``duration_s``, and for a failure
    its ``reason`` and a ``note``."""

    ok: bool
    duration_s: float
    note: str = ""
    reason: Reason | None = None


def _to_base(w: World, x: float, y: float, z: float) -> tuple[float, float, float]:
    b = w.base_pose()
    c, s = math.cos(b.theta), math.sin(b.theta)
    dx, dy = x - b.x, y - b.y
    return (c * dx + s * dy, -s * dx + c * dy, z)


def pick(w: World, name: str) -> Attempt:
    """Grasp tableware ``name`` from where it lies and lift it to the carry posture."""
    t0 = w.d.time
    item = w.wm.objects[name]
    pose = w.object_pose(name)
    base = w.base_pose()
    candidates = []
    for g in item.grasps():
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        gx, gy, gz = g.point
        x, y = pose.x + c * gx - s * gy, pose.y + s * gx + c * gy
        candidates.append((math.hypot(x - base.x, y - base.y), x, y, pose.z + gz,
                           pose.yaw + g.axis_yaw - base.theta, g.width))
    candidates.sort(key=lambda c: c[0])
    plan = None
    for _, x, y, z, yaw, width in candidates[:4]:
        target = _to_base(w, x, y, z)
        at = w.ik.solve(target, yaw, w.arm_q())
        above = w.ik.solve((target[0], target[1], z + APPROACH_M), yaw, at.q)
        if at.ok and above.ok:
            plan = (at.q, above.q, width)
            break
    if plan is None:
        return _no_ik(w, t0, candidates[0][0])
    q_at, q_above, width = plan
    w.grip_width = width
    w.set_fingers(min(width + 0.03, MAX_OPENING_M), 0.2)
    note = w.move_arm(q_above) or w.move_arm(q_at, speed_radps=0.6, at_surface=True)
    if note:
        return _abort(w, t0, note)
    w.set_fingers(0.0, 0.4)
    if not all(_touches(w, w.pads[side], name) for side in ("left", "right")):
        w.set_fingers(min(width + 0.03, MAX_OPENING_M), 0.2)
        return _abort(w, t0, "the pads closed on nothing", "grasp_missed")
    _weld(w, name, True)
    note = w.move_arm(q_above, speed_radps=0.6, at_surface=True) \
        or w.move_arm(w.ik.carry())
    if note:
        # Put it back down: a failed pick never leaves the object in the hand.
        _weld(w, name, False)
        w.set_fingers(min(width + 0.03, MAX_OPENING_M), 0.2)
        return _abort(w, t0, note)
    return Attempt(True, w.d.time - t0)


def place(w: World, name: str, x: float, y: float, yaw: float, support: str) -> Attempt:
    """Put the held ``name`` down with its bottom centre at ``(x, y)`` (room frame,
    metres) turned ``yaw`` (radians), on ``support`` (a table name or tableware), release
    it and let it settle. ``ok`` when the hand let go there."""
    t0 = w.d.time
    z = w.top_z(support)
    hand = w.d.body("hand")
    obj = w.d.body(name)
    # The grasp site in the object's frame, and the hand's x axis there: the held pose.
    r_obj = obj.xmat.reshape(3, 3)
    site = w.d.site("grasp")
    site_in_obj = r_obj.T @ (site.xpos - obj.xpos)
    x_in_obj = r_obj.T @ hand.xmat.reshape(3, 3)[:, 0]
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    target = np.array([x, y, z + DROP_M]) + rot @ site_in_obj
    hand_x = rot @ x_in_obj
    b = w.base_pose()
    hand_yaw = math.atan2(hand_x[1], hand_x[0]) - b.theta
    tb = _to_base(w, *target)
    at = w.ik.solve(tb, hand_yaw, w.arm_q())
    above = w.ik.solve((tb[0], tb[1], tb[2] + APPROACH_M), hand_yaw, at.q)
    if not (at.ok and above.ok):
        return _no_ik(w, t0, math.hypot(x - b.x, y - b.y))
    note = w.move_arm(above.q) or w.move_arm(at.q, speed_radps=0.5, at_surface=True)
    if note:
        return _abort(w, t0, note)
    _weld(w, name, False)
    w.set_fingers(min(w.grip_width + 0.03, MAX_OPENING_M), 0.25)
    w.move_arm(above.q, speed_radps=0.6, at_surface=True)
    w.move_arm(w.ik.carry())
    w.advance(0.2)
    return Attempt(True, w.d.time - t0)


def release(w: World) -> None:
    """Give up what the hand holds: lower it beside the base, below table height, and let
    go (it falls to the floor, not onto the table the robot faces)."""
    if w.held is None:
        return
    for point in DROP_POINTS:
        low = w.ik.solve(point, _hand_yaw(w), w.arm_q(), elbow_up=False)
        if low.ok:
            w.move_arm(low.q, at_surface=True)
            break
    _weld(w, w.held, False)
    w.set_fingers(min(w.grip_width + 0.03, MAX_OPENING_M), 0.3)
    w.move_arm(w.ik.carry(), at_surface=True)


def _no_ik(w: World, t0: float, reach_m: float) -> Attempt:
    """A failed attempt: no IK solution, found after the robot's planning time."""
    w.advance(w.scene.robot.ik_failure_s)
    return Attempt(False, w.d.time - t0, f"no IK solution (reach {reach_m:.2f} m)", "no_ik")


def _abort(w: World, t0: float, note: str, reason: Reason = "contact") -> Attempt:
    """Back out of a failed attempt: straight up from where the hand stopped, then to the
    carry posture (contacts the arm already has are overlooked)."""
    p = w.d.site("grasp").xpos
    b = _to_base(w, float(p[0]), float(p[1]), float(p[2]) + APPROACH_M)
    up = w.ik.solve(b, _hand_yaw(w), w.arm_q(), elbow_up=False)
    if up.ok:
        w.move_arm(up.q, speed_radps=0.6, at_surface=True)
    w.move_arm(w.ik.carry(), at_surface=True)
    return Attempt(False, w.d.time - t0, note, reason)


def _hand_yaw(w: World) -> float:
    """The direction the pads close along, base frame (radians)."""
    x = w.d.body("hand").xmat.reshape(3, 3)[:, 0]
    return math.atan2(float(x[1]), float(x[0])) - w.base_pose().theta


def _touches(w: World, geoms: np.ndarray, name: str) -> bool:
    n = w.d.ncon
    if n == 0:
        return False
    pairs = w.d.contact.geom[:n]
    owner = w.wm.owner
    return any((a in geoms and owner[b] == name) or (b in geoms and owner[a] == name)
               for a, b in pairs)


def _weld(w: World, name: str, on: bool) -> None:
    """Switch the weld between hand and ``name`` on (holding its current relative pose)
    or off."""
    eq = w.wm.welds[name]
    if on:
        hand, obj = w.d.body("hand"), w.d.body(name)
        r_hand = hand.xmat.reshape(3, 3)
        rel_pos = r_hand.T @ (obj.xpos - hand.xpos)
        q_hand_inv = np.zeros(4)
        mujoco.mju_negQuat(q_hand_inv, hand.xquat)
        rel_quat = np.zeros(4)
        mujoco.mju_mulQuat(rel_quat, q_hand_inv, obj.xquat)
        w.m.eq_data[eq, 0:3] = 0.0
        w.m.eq_data[eq, 3:6] = rel_pos
        w.m.eq_data[eq, 6:10] = rel_quat
        w.m.eq_data[eq, 10] = 1.0
        w.held = name
    else:
        w.held = None
    w.d.eq_active[eq] = int(on)
