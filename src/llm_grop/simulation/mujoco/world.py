"""The running dining room: physics stepping, the robot's actuators and sensors, and
reading where things are.

Everything moves under control: the base's three planar joints track velocity commands
(a differential drive, within the wheels' traction), the arm's six joints and the two
fingers track position references, and MuJoCo integrates the dynamics and contacts. Time
is simulated seconds (``data.time``). Driving lives in
:mod:`llm_grop.simulation.mujoco.drive`, manipulation in
:mod:`llm_grop.simulation.mujoco.manipulation`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from llm_grop.simulation.mujoco.arm import ARM_JOINTS, ArmIK
from llm_grop.simulation.mujoco.lidar import Lidar
from llm_grop.simulation.mujoco.options import Grasp, LidarOptions
from llm_grop.simulation.mujoco.world_model import WorldModel
from llm_grop.world.angles import wrap_angle
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.scene import Scene

#: Physics steps between two control updates (0.04 s at the default 4 ms time step).
CONTROL_STEPS = 10
#: The pads' gap with the fingers shut, metres.
PAD_GAP_M = 0.004
#: The hand lets go when the pads open this much past where they gripped, metres
#: (Gazebo grasp-fix's release_tolerance).
RELEASE_TOLERANCE_M = 0.005
#: Held by friction, an object has slipped once the point the pads gripped moved this far
#: from between them, metres.
SLIP_M = 0.02
#: Contact dimensions of the pads with the friction grasp: sliding, torsional and rolling
#: friction (MuJoCo's condim 6) ...
FRICTION_CONDIM = 6
#: ... and their coefficients: sliding; torsional and rolling, metres (about half the
#: pad's 24 mm face).
PAD_FRICTION = (1.5, 0.012, 0.012)
#: MuJoCo's impratio with the friction grasp (1 otherwise).
FRICTION_IMPRATIO = 10.0
#: With the friction grasp, each finger squeezes shut with this force plus its position
#: servo's pull, newtons (a force-limited gripper's grip force; 60 N at most).
FRICTION_SQUEEZE_N = 20.0
#: ... and a finger's reflected inertia, kg (the transmission's armature; 0.01 otherwise).
FRICTION_FINGER_ARMATURE = 0.2


@dataclass(frozen=True)
class ObjectPose:
    """A body's pose: bottom centre ``(x, y, z)`` (metres, room frame), ``yaw`` about z and
    ``tilt`` of its z axis from vertical (radians)."""

    x: float
    y: float
    z: float
    yaw: float
    tilt: float


class World:
    """One episode's physics: the model, its data and the robot's controllers."""

    def __init__(self, wm: WorldModel, scene: Scene, ik: ArmIK, *, lidar: LidarOptions,
                 speed_mps: float, grasp: Grasp = "fix",
                 turn_speed_radps: float,
                 on_frame: Callable[[World], None] | None = None, frame_dt_s: float = 0.2
                 ) -> None:
        self.wm, self.scene, self.ik = wm, scene, ik
        self.m = wm.model
        self.d = mujoco.MjData(self.m)
        self.speed, self.turn_speed = speed_mps, turn_speed_radps
        self.on_frame: Callable[[World], None] | None = None
        self.frame_dt = frame_dt_s
        self._next_frame = 0.0
        #: Called with the world every :attr:`observe_dt` simulated seconds (an episode's
        #: observer, :mod:`~llm_grop.simulation.mujoco.reporting`).
        self.observe: Callable[[World], None] | None = None
        self.observe_dt = 0.2
        self._next_observe = 0.0
        m = self.m
        self.base_qpos = [m.joint(n).qposadr[0] for n in ("base_x", "base_y", "base_yaw")]
        self.arm_qpos = np.array([m.joint(n).qposadr[0] for n in ARM_JOINTS])
        self.arm_ctrl = np.array([m.actuator(n).id for n in ARM_JOINTS])
        self.base_dof = [m.joint(n).dofadr[0] for n in ("base_x", "base_y", "base_yaw")]
        self.base_ctrl = [m.actuator(n).id for n in ("base_x", "base_y", "base_yaw")]
        #: The base's footprint radius, metres.
        self.radius = scene.robot.base_radius_m
        #: Physics steps per control period.
        self.control_steps = CONTROL_STEPS
        self.lidar = Lidar(m, lidar, m.body("base").id)
        self.finger_ctrl = [m.actuator(n).id for n in ("finger_left", "finger_right")]
        self.finger_qpos = [m.joint(n).qposadr[0] for n in ("finger_left", "finger_right")]
        self.pads = {side: np.array([m.geom(f"finger_{side}").id, m.geom(f"pad_{side}").id])
                     for side in ("left", "right")}
        self.held: str | None = None
        #: How the hand holds: ``fix`` (a weld on a squeezing grip) or ``friction``.
        self.grasp: Grasp = grasp
        #: The object the hand lost since the flag was last cleared, if any.
        self.dropped: str | None = None
        #: At the grasp: the object's position in the hand frame, the point of the object
        #: between the pads in the object's frame, and the fingers' opening (metres),
        #: against which slips and openings are judged.
        self.grip_rel = np.zeros(3)
        self.grip_point = np.zeros(3)
        self.grip_opening = 0.0
        if grasp == "friction":
            # Torsional and rolling friction too: a pad's 24 mm face resists an object
            # that would spin or pivot in it (a plate hanging from its rim), which a
            # point contact would not.
            for side in ("left", "right"):
                self.m.geom_condim[self.pads[side]] = FRICTION_CONDIM
                self.m.geom_friction[self.pads[side]] = PAD_FRICTION
            # Soft friction cones let a squeezed object creep under a steady load; a high
            # ratio of frictional to normal impedance stops the creep, as MuJoCo's
            # documentation advises for grasping.
            self.m.opt.impratio = FRICTION_IMPRATIO
            # Without the weld the squeeze alone holds, so it must not depend on how wide
            # the object is (a position servo pulls a 3 cm plate rim with 8 N, a mug with
            # 26 N); and a finger as light as the default chatters against the stiff pad
            # contact, so the squeeze flickers and the grip test fails.
            self.m.actuator_ctrlrange[self.finger_ctrl, 0] = -1.0
            self.m.dof_armature[[m.joint(n).dofadr[0] for n in ("finger_left", "finger_right")]] \
                = FRICTION_FINGER_ARMATURE
        #: Width, metres, of the object between the pads at the last grasp.
        self.grip_width = 0.05
        start = scene.robot_start
        self.d.qpos[self.base_qpos] = (start.x, start.y, start.theta)
        self.d.ctrl[self.base_ctrl] = 0.0
        carry = ik.carry()
        self.d.qpos[self.arm_qpos] = carry
        self.d.ctrl[self.arm_ctrl] = carry
        self.d.ctrl[self.finger_ctrl] = 0.03
        mujoco.mj_forward(self.m, self.d)
        # Let the tableware come to rest on its tables before the clock starts.
        self.advance(0.5)
        self.d.time = 0.0
        self.on_frame = on_frame

    # -- time -------------------------------------------------------------------------
    def advance(self, seconds: float, check: Callable[[], str] | None = None) -> str:
        """Step physics for ``seconds`` with the current references; stop early and return
        the note when ``check`` reports a problem."""
        n = max(1, round(seconds / (self.m.opt.timestep * CONTROL_STEPS)))
        for _ in range(n):
            mujoco.mj_step(self.m, self.d, nstep=CONTROL_STEPS)
            self.frame()
            if check is not None:
                note = check()
                if note:
                    return note
        return ""

    def frame(self) -> None:
        """Watch the grip, and call the frame hook when a frame is due (every control
        period)."""
        if self.held is not None:
            self._watch_grip()
        if self.on_frame is not None and self.d.time >= self._next_frame:
            self._next_frame = self.d.time + self.frame_dt
            self.on_frame(self)
        if self.observe is not None and self.d.time >= self._next_observe:
            # Half a control period early, so that rounding never skips a period.
            self._next_observe = self.d.time + self.observe_dt \
                - 0.5 * self.m.opt.timestep * CONTROL_STEPS
            self.observe(self)

    # -- the grip ---------------------------------------------------------------------
    def finger_opening(self) -> float:
        """How far apart the pads are now, metres."""
        return float(2 * self.d.qpos[self.finger_qpos].mean() + PAD_GAP_M)

    def hold(self, name: str | None) -> None:
        """Start holding ``name`` (after a grip), or stop holding (``None``): with the
        ``fix`` grasp the weld between hand and object switches on or off."""
        if self.held is not None and self.grasp == "fix":
            self.d.eq_active[self.wm.welds[self.held]] = 0
        self.held = name
        if name is None:
            return
        hand, obj = self.d.body("hand"), self.d.body(name)
        r_hand = hand.xmat.reshape(3, 3)
        site = self.d.site("grasp").xpos
        self.grip_rel = r_hand.T @ (obj.xpos - hand.xpos)
        self.grip_point = obj.xmat.reshape(3, 3).T @ (site - obj.xpos)
        self.grip_opening = self.finger_opening()
        if self.grasp == "fix":
            eq = self.wm.welds[name]
            q_hand_inv, rel_quat = np.zeros(4), np.zeros(4)
            mujoco.mju_negQuat(q_hand_inv, hand.xquat)
            mujoco.mju_mulQuat(rel_quat, q_hand_inv, obj.xquat)
            self.m.eq_data[eq, 0:3] = 0.0
            self.m.eq_data[eq, 3:6] = self.grip_rel
            self.m.eq_data[eq, 6:10] = rel_quat
            self.m.eq_data[eq, 10] = 1.0
            self.d.eq_active[eq] = 1

    def _watch_grip(self) -> None:
        """Held by friction, lose the object when the pads opened more than
        :data:`RELEASE_TOLERANCE_M` past where they gripped it or it slipped
        :data:`SLIP_M` in the hand. (The weld of the ``fix`` grasp lets go when the hand
        is commanded open, :meth:`set_fingers`: its soft pads yield a few millimetres under
        a welded plate's rim without letting go.)"""
        assert self.held is not None
        if self.grasp != "friction":
            return
        lost = self.finger_opening() > self.grip_opening + RELEASE_TOLERANCE_M
        if not lost:
            obj = self.d.body(self.held)
            gripped = obj.xpos + obj.xmat.reshape(3, 3) @ self.grip_point
            lost = float(np.linalg.norm(gripped - self.d.site("grasp").xpos)) > SLIP_M
        if lost:
            self.dropped = self.held
            self.hold(None)

    # -- where things are -------------------------------------------------------------
    def base_pose(self) -> Pose2D:
        """The base's pose in the room frame."""
        x, y, th = (float(v) for v in self.d.qpos[self.base_qpos])
        return Pose2D(x, y, wrap_angle(th))

    def object_pose(self, name: str) -> ObjectPose:
        """Where tableware ``name`` is."""
        body = self.d.body(name)
        x, y, z = (float(v) for v in body.xpos)
        mat = body.xmat.reshape(3, 3)
        return ObjectPose(x, y, z, math.atan2(mat[1, 0], mat[0, 0]),
                          math.acos(max(-1.0, min(1.0, float(mat[2, 2])))))

    def top_z(self, name: str) -> float:
        """Height of the top face of a table (by table name) or a piece of tableware."""
        if name in self.wm.tops:
            g = self.wm.tops[name]
            # A box's half height is its third size, a (round top's) cylinder's its second.
            half = 1 if self.m.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER else 2
            return float(self.d.geom_xpos[g][2] + self.m.geom_size[g][half])
        return self.object_pose(name).z + self.wm.objects[name].height

    def support_of(self, name: str) -> str | None:
        """The tableware ``name`` rests on (``None``: a table, the floor, or the hand),
        from contact: the highest object below it that it touches through a contact whose
        normal is near vertical."""
        if name == self.held:
            return None
        n = self.d.ncon
        owner = self.wm.owner
        z = self.object_pose(name).z
        best: tuple[float, str] | None = None
        for k in range(n):
            a, b = self.d.contact.geom[k]
            oa, ob = owner[a], owner[b]
            if name not in (oa, ob) or oa == ob:
                continue
            other = ob if oa == name else oa
            if not other or other == self.held or abs(self.d.contact.frame[k][2]) < 0.7:
                continue
            top = self.top_z(other)
            if self.object_pose(other).z < z - 1e-3 and (best is None or top > best[0]):
                best = (top, other)
        return best[1] if best else None

    # -- contacts ---------------------------------------------------------------------
    def collisions(self, *, arm_only: bool = False, at_surface: bool = False,
                   ignore: Sequence[int] = (), ignore_bodies: Sequence[int] = ()) -> str:
        """A description of the first contact between the robot (or what it holds) and
        furniture, else ``""``. With ``arm_only`` the base does not count (it stands
        still while the arm works, perhaps against a table); with ``at_surface`` neither
        do the fingers and the held object (they work at a table top); ``ignore`` lists
        furniture geoms, ``ignore_bodies`` furniture bodies, to overlook."""
        n = self.d.ncon
        if n == 0:
            return ""
        geoms = self.d.contact.geom[:n]
        wm = self.wm
        held = wm.parts[self.held] if self.held else np.zeros(len(wm.owner), bool)
        mover = (wm.arm if arm_only else wm.robot) | held
        if at_surface:
            mover = mover & ~wm.fingers & ~held
        hit = (mover[geoms[:, 0]] & wm.furniture[geoms[:, 1]]) | \
              (mover[geoms[:, 1]] & wm.furniture[geoms[:, 0]])
        for k in np.flatnonzero(hit):
            a, b = (int(g) for g in geoms[k])
            f = b if wm.furniture[b] else a
            if f in ignore or int(self.m.geom_bodyid[f]) in ignore_bodies:
                continue
            return f"contact with {_furniture_label(self.m.geom(f).name)}"
        return ""

    def touching_furniture(self) -> list[int]:
        """Furniture geoms the robot touches now."""
        return [g for g, _ in self._furniture_contacts()]

    def furniture_contact_points(self) -> list[tuple[float, float]]:
        """Where the robot touches furniture now (room frame, metres)."""
        return [xy for _, xy in self._furniture_contacts()]

    def _furniture_contacts(self) -> list[tuple[int, tuple[float, float]]]:
        """Each contact between the robot and furniture now: the furniture geom and where
        (room frame, metres)."""
        wm, out = self.wm, []
        for k in range(self.d.ncon):
            a, b = (int(g) for g in self.d.contact.geom[k])
            if wm.robot[a] and wm.furniture[b] or wm.robot[b] and wm.furniture[a]:
                pos = self.d.contact.pos[k]
                out.append((b if wm.furniture[b] else a, (float(pos[0]), float(pos[1]))))
        return out

    # -- the base ---------------------------------------------------------------------
    def command_base(self, v_mps: float, turn_radps: float) -> None:
        """Command the base to move forward at ``v_mps`` and turn at ``turn_radps`` (a
        differential drive: never sideways)."""
        th = float(self.d.qpos[self.base_qpos[2]])
        self.d.ctrl[self.base_ctrl] = (v_mps * math.cos(th), v_mps * math.sin(th), turn_radps)

    def base_velocity(self) -> tuple[float, float]:
        """The base's forward speed (metres per second) and turn rate (radians per
        second) now."""
        vx, vy, turn = (float(v) for v in self.d.qvel[self.base_dof])
        th = float(self.d.qpos[self.base_qpos[2]])
        return vx * math.cos(th) + vy * math.sin(th), turn

    def chair_positions(self) -> dict[str, tuple[float, float]]:
        """Where each chair stands now (room frame, metres)."""
        return {n: (float(self.d.xpos[b][0]), float(self.d.xpos[b][1]))
                for n, b in self.wm.chairs.items()}

    def chair_moved(self, before: dict[str, tuple[float, float]]
                    ) -> tuple[str, float] | None:
        """The chair that moved farthest since ``before`` and how far (metres), if any
        moved more than a millimetre."""
        now = self.chair_positions()
        moved = max(((n, math.dist(before[n], now[n])) for n in before),
                    key=lambda m: m[1], default=None)
        return moved if moved is not None and moved[1] > 1e-3 else None

    # -- the arm ----------------------------------------------------------------------
    def arm_q(self) -> np.ndarray:
        """The arm's joint angles now (radians)."""
        return self.d.qpos[self.arm_qpos].copy()

    def move_arm(self, goal: np.ndarray, *, speed_radps: float = 1.2, at_surface: bool
                 = False, min_s: float = 0.3) -> str:
        """Move the arm to ``goal`` along a straight line in joint space; stop at a new
        collision with furniture and return its description (contacts the robot already
        had, such as a base resting against a table, are overlooked)."""
        start = self.d.ctrl[self.arm_ctrl].copy()
        ignore = self.touching_furniture()
        span = float(np.max(np.abs(goal - start)))
        dt = self.m.opt.timestep * CONTROL_STEPS
        n = max(1, math.ceil(max(span / speed_radps, min_s) / dt))
        for k in range(1, n + 1):
            s = k / n
            s = s * s * (3 - 2 * s)
            self.d.ctrl[self.arm_ctrl] = start + s * (goal - start)
            mujoco.mj_step(self.m, self.d, nstep=CONTROL_STEPS)
            self.frame()
            note = self.collisions(arm_only=True, at_surface=at_surface, ignore=ignore)
            if note:
                self.d.ctrl[self.arm_ctrl] = self.arm_q()
                return note
        return self.advance(0.15, lambda: self.collisions(arm_only=True, at_surface=at_surface,
                                                          ignore=ignore))

    def set_fingers(self, opening_m: float, seconds: float = 0.3) -> None:
        """Command the pads to ``opening_m`` apart (0: squeeze shut) and wait; opening the
        hand lets go of what it holds."""
        if self.held is not None and opening_m > self.grip_opening:
            self.hold(None)
        q = min(max((opening_m - PAD_GAP_M) / 2, 0.0), 0.07)
        if q == 0.0 and self.grasp == "friction":
            q = -FRICTION_SQUEEZE_N / float(self.m.actuator_gainprm[self.finger_ctrl[0], 0])
        self.d.ctrl[self.finger_ctrl] = q
        self.advance(seconds)


def _furniture_label(geom: str) -> str:
    kind, _, rest = geom.partition(":")
    name = rest.split(":")[0]
    if kind in ("seat", "back", "chair leg"):
        return f"chair {name!r}"
    if kind in ("top", "leg"):
        return f"table {name!r}"
    return geom

