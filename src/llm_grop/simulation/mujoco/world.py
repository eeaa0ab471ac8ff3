"""The running dining room: physics stepping, the base's path following, and reading where
things are.

Everything moves under control: the base's three joints and the arm's six track position
references through their actuators, and MuJoCo integrates the dynamics and contacts. Time
is simulated seconds (``data.time``). Manipulation lives in
:mod:`llm_grop.simulation.mujoco.manipulation`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from llm_grop.geometry.motion import wrap
from llm_grop.simulation.mujoco.arm import ARM_JOINTS, ArmIK
from llm_grop.simulation.mujoco.world_model import WorldModel
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import Point
from llm_grop.world.scene import Scene

#: Physics steps between two control updates (0.04 s at the default 4 ms time step).
CONTROL_STEPS = 10
#: How far, metres, the base moves before furniture it touched at the start counts again.
CLEAR_M = 0.3
#: A body is "on" a surface when its bottom is within this height of the surface, metres.
REST_TOL_M = 0.015


@dataclass(frozen=True)
class ObjectPose:
    """A body's pose: bottom centre ``(x, y, z)`` (metres, room frame), ``yaw`` about z and
    ``tilt`` of its z axis from vertical (radians)."""

    x: float
    y: float
    z: float
    yaw: float
    tilt: float


@dataclass(frozen=True)
class Drive:
    """How a drive along a path ended: ``ok``, the points the base passed (room frame),
    the seconds it took, and what stopped it (``note``)."""

    ok: bool
    path: tuple[Point, ...]
    duration_s: float
    note: str = ""


class World:
    """One episode's physics: the model, its data and the robot's controllers."""

    def __init__(self, wm: WorldModel, scene: Scene, ik: ArmIK, *, speed_mps: float,
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
        m = self.m
        self.base_qpos = [m.joint(n).qposadr[0] for n in ("base_x", "base_y", "base_yaw")]
        self.arm_qpos = np.array([m.joint(n).qposadr[0] for n in ARM_JOINTS])
        self.arm_ctrl = np.array([m.actuator(n).id for n in ARM_JOINTS])
        self.base_ctrl = [m.actuator(n).id for n in ("base_x", "base_y", "base_yaw")]
        self.finger_ctrl = [m.actuator(n).id for n in ("finger_left", "finger_right")]
        self.pads = {side: np.array([m.geom(f"finger_{side}").id, m.geom(f"pad_{side}").id])
                     for side in ("left", "right")}
        self.held: str | None = None
        #: Width, metres, of the object between the pads at the last grasp.
        self.grip_width = 0.05
        start = scene.robot_start
        self.d.qpos[self.base_qpos] = (start.x, start.y, start.theta)
        self.d.ctrl[self.base_ctrl] = (start.x, start.y, start.theta)
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
            self._frame()
            if check is not None:
                note = check()
                if note:
                    return note
        return ""

    def _frame(self) -> None:
        if self.on_frame is not None and self.d.time >= self._next_frame:
            self._next_frame = self.d.time + self.frame_dt
            self.on_frame(self)

    # -- where things are -------------------------------------------------------------
    def base_pose(self) -> Pose2D:
        """The base's pose in the room frame."""
        x, y, th = (float(v) for v in self.d.qpos[self.base_qpos])
        return Pose2D(x, y, wrap(th))

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
        n = self.d.ncon
        geoms = self.d.contact.geom[:n]
        wm = self.wm
        out = []
        for a, b in geoms:
            if wm.robot[a] and wm.furniture[b]:
                out.append(int(b))
            elif wm.robot[b] and wm.furniture[a]:
                out.append(int(a))
        return out

    # -- the base ---------------------------------------------------------------------
    def drive(self, path: Sequence[Point], heading: float, *, stop_on_contact: bool = True,
              holonomic: bool = False) -> Drive:
        """Follow ``path`` (room frame), turning in place between segments and to
        ``heading`` at the end (``holonomic``: sliding and turning at once, for short
        corrections); with ``stop_on_contact``, stop at the first contact with furniture
        (contacts present at the start are overlooked)."""
        t0 = self.d.time
        here = self.base_pose()
        yaw = float(self.d.qpos[self.base_qpos[2]])
        dt = self.m.opt.timestep * CONTROL_STEPS
        if holonomic:
            refs = _slide(here, yaw, path[-1], heading, self.speed, self.turn_speed, dt)
        else:
            refs = _references(here, yaw, path, heading, self.speed, self.turn_speed, dt)
        # Furniture the base already touches (after a bump, or resting against a table it
        # works at) is overlooked until the base has moved clear of it.
        bodies = {int(self.m.geom_bodyid[g]) for g in self.touching_furniture()}
        passed: list[Point] = [(here.x, here.y)]
        note = ""
        for ref in refs:
            self.d.ctrl[self.base_ctrl] = ref
            mujoco.mj_step(self.m, self.d, nstep=CONTROL_STEPS)
            self._frame()
            p = self.base_pose()
            if stop_on_contact:
                near = math.dist((here.x, here.y), (p.x, p.y)) < CLEAR_M
                note = self.collisions(ignore_bodies=tuple(bodies) if near else ())
                if note:
                    break
            if math.dist(passed[-1], (p.x, p.y)) > 0.05:
                passed.append((p.x, p.y))
        if note:
            p = self.base_pose()
            self.d.ctrl[self.base_ctrl] = (p.x, p.y, float(self.d.qpos[self.base_qpos[2]]))
        if not self._settle_base() and stop_on_contact and not note:
            note = "blocked short of its goal"
        p = self.base_pose()
        if math.dist(passed[-1], (p.x, p.y)) > 1e-3:
            passed.append((p.x, p.y))
        return Drive(not note, tuple(passed), self.d.time - t0, note)

    def _settle_base(self, limit_s: float = 2.0) -> bool:
        """Wait until the base has caught up with its reference (1 mm, 2 mrad); whether it
        came within 2 cm and 0.05 rad of it (else something holds it back)."""
        for _ in range(max(1, round(limit_s / (self.m.opt.timestep * CONTROL_STEPS)))):
            err = self.d.qpos[self.base_qpos] - self.d.ctrl[self.base_ctrl]
            if abs(err[0]) < 1e-3 and abs(err[1]) < 1e-3 and abs(err[2]) < 2e-3:
                return True
            mujoco.mj_step(self.m, self.d, nstep=CONTROL_STEPS)
            self._frame()
        err = self.d.qpos[self.base_qpos] - self.d.ctrl[self.base_ctrl]
        return bool(math.hypot(err[0], err[1]) < 0.02 and abs(err[2]) < 0.05)

    def back_off(self, distance_m: float = 0.08) -> None:
        """Move a little away from the furniture the robot bumped (straight back when it
        touches nothing any more), as a robot does after a bump."""
        p = self.base_pose()
        yaw = float(self.d.qpos[self.base_qpos[2]])
        away = (-math.cos(p.theta), -math.sin(p.theta))
        n = self.d.ncon
        for k in range(n):
            a, b = self.d.contact.geom[k]
            if (self.wm.robot[a] and self.wm.furniture[b]) or \
                    (self.wm.robot[b] and self.wm.furniture[a]):
                cx, cy = (float(v) for v in self.d.contact.pos[k][:2])
                norm = math.hypot(p.x - cx, p.y - cy)
                if norm > 1e-6:
                    away = ((p.x - cx) / norm, (p.y - cy) / norm)
                break
        self.d.ctrl[self.base_ctrl] = (p.x + distance_m * away[0],
                                       p.y + distance_m * away[1], yaw)
        self.advance(0.5)

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
            self._frame()
            note = self.collisions(arm_only=True, at_surface=at_surface, ignore=ignore)
            if note:
                self.d.ctrl[self.arm_ctrl] = self.arm_q()
                return note
        return self.advance(0.15, lambda: self.collisions(arm_only=True, at_surface=at_surface,
                                                          ignore=ignore))

    def set_fingers(self, opening_m: float, seconds: float = 0.3) -> None:
        """Command the pads to ``opening_m`` apart (0: squeeze shut) and wait."""
        q = min(max((opening_m - 0.004) / 2, 0.0), 0.07)
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


def _slide(start: Pose2D, yaw: float, goal: Point, heading: float, speed: float,
           turn_speed: float, dt: float) -> list[tuple[float, float, float]]:
    """Base references sliding straight to ``goal`` while turning to ``heading``."""
    end = yaw + wrap(heading - yaw)
    seconds = max(math.dist((start.x, start.y), goal) / speed, abs(end - yaw) / turn_speed)
    n = max(1, math.ceil(seconds / dt))
    return [(start.x + (goal[0] - start.x) * k / n, start.y + (goal[1] - start.y) * k / n,
             yaw + (end - yaw) * k / n) for k in range(1, n + 1)]


def _references(start: Pose2D, yaw: float, path: Sequence[Point], heading: float,
                speed: float, turn_speed: float, dt: float) -> list[tuple[float, float, float]]:
    """Base references every ``dt`` seconds: turn in place towards each segment, drive it,
    then turn to ``heading``. Yaw is kept continuous (unwrapped) from ``yaw``."""
    refs: list[tuple[float, float, float]] = []
    x, y = start.x, start.y

    def turn_to(target: float) -> None:
        nonlocal yaw
        goal = yaw + wrap(target - yaw)
        n = math.ceil(abs(goal - yaw) / (turn_speed * dt))
        refs.extend((x, y, yaw + (goal - yaw) * k / n) for k in range(1, n + 1))
        yaw = goal

    for px, py in path:
        length = math.hypot(px - x, py - y)
        if length < 1e-3:
            continue
        turn_to(math.atan2(py - y, px - x))
        n = math.ceil(length / (speed * dt))
        refs.extend((x + (px - x) * k / n, y + (py - y) * k / n, yaw) for k in range(1, n + 1))
        x, y = px, py
    turn_to(heading)
    return refs
