"""Picking and placing tableware with the arm, in physics.

A pick goes pre-grasp, grasp, close, lift, carry; a place goes pre-place, lower, release,
retreat, and physics settles the object. An attempt fails when no IK solution reaches the
pose (after the robot's ``ik_failure_s`` of planning), when the arm or what it holds
touches furniture, or when the pads do not squeeze it. Where a released object comes to
rest (upright or tipped, on its support or not) is for the executive to judge.

Holding follows Gazebo's grasp-fix plugin: after the fingers close, a weld between hand
and object switches on only when both pads press on the object with opposing forces
(each at least :data:`GRIP_FORCE_N`, directions at least 120 degrees apart) for
:data:`GRIP_CHECKS` control periods in a row; pads that merely touch, or press from one
side, miss the grasp. The weld switches off when the hand is commanded open to let go.
With the ``friction`` grasp (:attr:`MujocoOptions.grasp`) there is no weld: the squeezing
pads hold the object by contact friction alone, and an object is lost when the pads open
5 mm past where they gripped it (grasp-fix's release tolerance) or its gripped point slips
2 cm (a ``pick`` whose object slips while lifting misses its grasp; a drop in transit is
reported by the session's ``navigate``, ``fell``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from llm_grop.simulation.mujoco.tableware import MAX_OPENING_M
from llm_grop.simulation.mujoco.world import World
from llm_grop.simulation.mujoco.world_model import TRAY_TOP
from llm_grop.world.plan import Reason
from llm_grop.world.robot import GRIP_CLEARANCE_M

#: Height of the pre-grasp and pre-place poses above the grasp (metres).
APPROACH_M = 0.10
#: Height of the pre-grasp pose when the arm cannot reach :data:`APPROACH_M` above an
#: object it can grasp (the top of a tall pile on a high counter), metres.
LOW_APPROACH_M = 0.05
#: An object is released this high above its surface (metres).
DROP_M = 0.006
#: The grasp attaches when each pad presses with at least this force, newtons, ...
GRIP_FORCE_N = 2.0
#: ... the two pushes' directions differ by at least this angle, radians (120 degrees,
#: Gazebo grasp-fix's forces_angle_tolerance) ...
GRIP_ANGLE_RAD = math.radians(120.0)
#: ... for this many control periods in a row, after the fingers have closed.
GRIP_CHECKS = 5
#: Height of the hand over the tray between the carry posture and the tray, metres (base
#: frame): the arm swings round above the table it faces, not through it.
OVER_TRAY_Z_M = 0.8
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


def pick(w: World, name: str, *, from_tray: bool = False) -> Attempt:
    """Grasp tableware ``name`` from where it lies and lift it to the carry posture. The
    four grasps nearest the base are tried; ``from_tray``, every grasp, farthest first
    (on the base's own tray the arm reaches out, not in at its column)."""
    t0 = w.d.time
    _uncover(w, name)
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
    candidates.sort(key=lambda c: -c[0] if from_tray else c[0])
    plan = None
    for _, x, y, z, yaw, width in candidates if from_tray else candidates[:4]:
        target = _to_base(w, x, y, z)
        at = w.ik.solve(target, yaw, w.arm_q())
        above = w.ik.solve((target[0], target[1], z + APPROACH_M), yaw, at.q)
        if at.ok and not above.ok and not from_tray:
            above = w.ik.solve((target[0], target[1], z + LOW_APPROACH_M), yaw, at.q)
        # From the tray the arm swings round high over it, not through the table ahead.
        via = _over(w, target, yaw, above.q) if from_tray and above.ok else None
        if at.ok and above.ok and (via is not None or not from_tray):
            plan = (at.q, above.q, width, via)
            break
    if plan is None:
        return _no_ik(w, t0, candidates[0][0])
    q_at, q_above, width, via = plan
    w.grip_width = width
    w.set_fingers(min(width + 2 * GRIP_CLEARANCE_M, MAX_OPENING_M), 0.2)
    note = (w.move_arm(via) if via is not None else "") or w.move_arm(q_above) \
        or w.move_arm(q_at, speed_radps=0.6, at_surface=True)
    if note:
        return _abort(w, t0, note, via=via)
    w.set_fingers(0.0, 0.4)
    if not _grip(w, name):
        w.set_fingers(min(width + 2 * GRIP_CLEARANCE_M, MAX_OPENING_M), 0.2)
        return _abort(w, t0, "the pads do not squeeze it", "grasp_missed", via=via)
    w.hold(name)
    note = w.move_arm(q_above, speed_radps=0.6, at_surface=True) \
        or (w.move_arm(via) if via is not None else "") or w.move_arm(w.ik.carry())
    if note:
        # Put it back down: a failed pick never leaves the object in the hand.
        w.set_fingers(min(width + 2 * GRIP_CLEARANCE_M, MAX_OPENING_M), 0.2)
        return _abort(w, t0, note, via=via)
    if w.held != name:
        w.set_fingers(min(width + 2 * GRIP_CLEARANCE_M, MAX_OPENING_M), 0.2)
        return _abort(w, t0, "it slipped from the pads while lifting", "grasp_missed",
                      via=via)
    return Attempt(True, w.d.time - t0)


def _uncover(w: World, name: str) -> None:
    """Bring ``name`` to the top of the pile it lies in. A pile's objects are identical,
    so taking one from under the others stands for taking the top one, as in the 2D
    simulator: the arm gets the same object either way. The top one and ``name`` swap
    places (their free joints' positions and velocities), which changes nothing physical.
    Something else on ``name`` (another kind) stays, and the pick finds ``name`` covered."""
    top = name
    while True:
        above = next((o for o in w.wm.objects
                      if o not in (top, w.held) and w.support_of(o) == top), None)
        if above is None or replace(w.wm.objects[above], name=name) != w.wm.objects[name]:
            break
        top = above
    if top == name:
        return
    (qa, va), (qb, vb) = _free_joint(w, name), _free_joint(w, top)
    w.d.qpos[qa:qa + 7], w.d.qpos[qb:qb + 7] = w.d.qpos[qb:qb + 7].copy(), \
        w.d.qpos[qa:qa + 7].copy()
    w.d.qvel[va:va + 6], w.d.qvel[vb:vb + 6] = w.d.qvel[vb:vb + 6].copy(), \
        w.d.qvel[va:va + 6].copy()
    mujoco.mj_forward(w.m, w.d)


def _free_joint(w: World, name: str) -> tuple[int, int]:
    """Where tableware ``name``'s free joint starts in ``qpos`` and in ``qvel``."""
    j = int(w.m.body(name).jntadr[0])
    return int(w.m.jnt_qposadr[j]), int(w.m.jnt_dofadr[j])


def place(w: World, name: str, x: float, y: float, yaw: float, support: str) -> Attempt:
    """Put the held ``name`` down with its bottom centre at ``(x, y)`` (room frame,
    metres) turned ``yaw`` (radians), on ``support`` (a table name or tableware), release
    it and let it settle. ``ok`` when the hand let go there."""
    t0 = w.d.time
    plan = _place_ik(w, name, x, y, yaw, support)
    if plan is None:
        b = w.base_pose()
        return _no_ik(w, t0, math.hypot(x - b.x, y - b.y))
    return _put_down(w, t0, plan[0], plan[1])


def load(w: World, name: str, x: float, y: float, yaws: Sequence[float]) -> Attempt:
    """Put the held ``name`` down on the robot's tray with its bottom centre at ``(x, y)``
    (room frame, metres), turned the first of ``yaws`` (radians, room frame) the arm can
    reach, release it and let it settle."""
    t0 = w.d.time
    for yaw in yaws:
        plan = _place_ik(w, name, x, y, yaw, TRAY_TOP)
        if plan is not None:
            over = _over(w, plan[2], plan[3], plan[1])
            if over is not None:
                return _put_down(w, t0, plan[0], plan[1], via=over)
    b = w.base_pose()
    return _no_ik(w, t0, math.hypot(x - b.x, y - b.y))


def _over(w: World, target: tuple[float, float, float], yaw: float, start: np.ndarray
          ) -> np.ndarray | None:
    """Joint angles with the hand :data:`OVER_TRAY_Z_M` high over ``target`` (base frame,
    metres), its pads along ``yaw``; ``None`` when IK finds none."""
    over = w.ik.solve((target[0], target[1], OVER_TRAY_Z_M), yaw, start)
    return over.q if over.ok else None


def _place_ik(w: World, name: str, x: float, y: float, yaw: float, support: str
              ) -> tuple[np.ndarray, np.ndarray, tuple[float, float, float], float] | None:
    """The arm's joint angles (at the release pose, and above it) that put the held
    ``name`` at ``(x, y, yaw)`` (room frame) on ``support``, with the release pose's
    grasp point (base frame, metres) and the pads' direction (radians, base frame);
    ``None`` when IK finds none."""
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
        return None
    return at.q, above.q, tb, hand_yaw


def _put_down(w: World, t0: float, q_at: np.ndarray, q_above: np.ndarray,
              via: np.ndarray | None = None) -> Attempt:
    """Lower the held object through ``q_above`` to ``q_at``, let go, and return to the
    carry posture, passing ``via`` on the way there and back when given; the attempt
    since ``t0``."""
    note = (w.move_arm(via) if via is not None else "") or w.move_arm(q_above) \
        or w.move_arm(q_at, speed_radps=0.5, at_surface=True)
    if note:
        return _abort(w, t0, note, via=via)
    w.set_fingers(min(w.grip_width + 2 * GRIP_CLEARANCE_M, MAX_OPENING_M), 0.25)
    w.move_arm(q_above, speed_radps=0.6, at_surface=True)
    if via is not None:
        w.move_arm(via)
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
    w.set_fingers(min(w.grip_width + 2 * GRIP_CLEARANCE_M, MAX_OPENING_M), 0.3)
    w.move_arm(w.ik.carry(), at_surface=True)


def _no_ik(w: World, t0: float, reach_m: float) -> Attempt:
    """A failed attempt: no IK solution, found after the robot's planning time."""
    w.advance(w.scene.robot.ik_failure_s)
    return Attempt(False, w.d.time - t0, f"no IK solution (reach {reach_m:.2f} m)", "no_ik")


def _abort(w: World, t0: float, note: str, reason: Reason = "contact",
           via: np.ndarray | None = None) -> Attempt:
    """Back out of a failed attempt: straight up from where the hand stopped, then
    (through ``via``, when given) to the carry posture (contacts the arm already has are
    overlooked)."""
    p = w.d.site("grasp").xpos
    b = _to_base(w, float(p[0]), float(p[1]), float(p[2]) + APPROACH_M)
    up = w.ik.solve(b, _hand_yaw(w), w.arm_q(), elbow_up=False)
    if up.ok:
        w.move_arm(up.q, speed_radps=0.6, at_surface=True)
    if via is not None:
        w.move_arm(via, at_surface=True)
    w.move_arm(w.ik.carry(), at_surface=True)
    return Attempt(False, w.d.time - t0, note, reason)


def _hand_yaw(w: World) -> float:
    """The direction the pads close along, base frame (radians)."""
    x = w.d.body("hand").xmat.reshape(3, 3)[:, 0]
    return math.atan2(float(x[1]), float(x[0])) - w.base_pose().theta


def _grip(w: World, name: str) -> bool:
    """Whether the pads grip ``name``: for :data:`GRIP_CHECKS` control periods in a row,
    each pad presses on it with at least :data:`GRIP_FORCE_N` and the two pushes differ in
    direction by at least :data:`GRIP_ANGLE_RAD` (Gazebo grasp-fix's attach test)."""
    for _ in range(GRIP_CHECKS):
        w.advance(w.m.opt.timestep * w.control_steps)
        left, right = (_push(w, w.pads[side], name) for side in ("left", "right"))
        fl, fr = float(np.linalg.norm(left)), float(np.linalg.norm(right))
        if min(fl, fr) < GRIP_FORCE_N:
            return False
        if math.acos(max(-1.0, min(1.0, float(left @ right) / (fl * fr)))) < GRIP_ANGLE_RAD:
            return False
    return True


def _push(w: World, geoms: np.ndarray, name: str) -> np.ndarray:
    """The total normal force, newtons (room frame), that the geoms ``geoms`` exert on
    ``name`` through their contacts now."""
    total = np.zeros(3)
    owner = w.wm.owner
    wrench = np.zeros(6)
    for k in range(w.d.ncon):
        a, b = (int(g) for g in w.d.contact.geom[k])
        if a in geoms and owner[b] == name:
            sign = 1.0  # the normal points from the first geom (a pad) to the object
        elif b in geoms and owner[a] == name:
            sign = -1.0
        else:
            continue
        mujoco.mj_contactForce(w.m, w.d, k, wrench)
        total += sign * wrench[0] * w.d.contact.frame[k][:3]
    return total
