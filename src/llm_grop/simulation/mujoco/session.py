"""A MuJoCo episode driven one attempt at a time (see
:class:`~llm_grop.simulation.base.Session`): the base's navigation legs and the arm's picks
and places, each recorded with all the simulated time it took."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from llm_grop.geometry.motion import arrival_error
from llm_grop.recording.stream import SensorObserver
from llm_grop.simulation.base import PathPlanner
from llm_grop.simulation.mujoco import drive, manipulation
from llm_grop.simulation.mujoco.options import MujocoOptions
from llm_grop.simulation.mujoco.render import View, picture
from llm_grop.simulation.mujoco.reporting import Reporter
from llm_grop.simulation.mujoco.world import World
from llm_grop.simulation.mujoco.world_model import TRAY_TOP
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, ObjectState, Point
from llm_grop.world.scene import Scene
from llm_grop.world.tray import load_tray

log = logging.getLogger(__name__)

#: Radii, metres, searched round the base for a free start when it stands where the path
#: planner cannot start (against furniture after a bump).
START_SEARCH_M = (0.0, 0.1, 0.2, 0.3)
#: A body lies on a table when its bottom is at most this far below the top (metres).
ON_TABLE_BELOW_M = 0.05
#: ... and at most this far above it (metres).
ON_TABLE_ABOVE_M = 0.5
#: A body rides on the tray when its bottom is within this height band of the tray's top,
#: metres (a tipped cup lies with its bottom's centre up to half its height above) ...
ON_TRAY_Z_M = (-0.02, 0.08)
#: ... and its centre within this distance of the tray's centre beyond the rim's inside
#: (metres; a tipped object may lean over the rim).
ON_TRAY_BEYOND_M = 0.05


class MujocoSession:
    """One episode in the 3D world; every method runs physics until its attempt ends."""

    def __init__(self, options: MujocoOptions, scene: Scene, rng: np.random.Generator,
                 replan: PathPlanner, world: World, names: Sequence[str],
                 on_close: Callable[[], None] | None = None) -> None:
        self.o, self.scene, self.rng, self.replan, self.w = options, scene, rng, replan, world
        self.names = tuple(names)
        self.mark = float(world.d.time)
        self.on_close = on_close
        self.tray = load_tray()
        #: The slot each object loaded onto the tray was put in.
        self.slots: dict[str, int] = {}
        #: What the lidar saw at the end of the last drive (room frame, metres).
        self.seen: tuple[Point, ...] = ()
        self.reporter: Reporter | None = None

    def watch(self, observer: SensorObserver) -> None:
        """Report the base, the objects, the arm, the lidar and camera frames to
        ``observer`` while attempts run (see
        :mod:`~llm_grop.simulation.mujoco.reporting`)."""
        self.reporter = Reporter(self.w, self.names, self.o, observer)
        self.w.observe, self.w.observe_dt = self.reporter, self.o.record_dt_s

    # -- state ------------------------------------------------------------------------
    @property
    def time_s(self) -> float:
        """Simulated seconds so far."""
        return float(self.w.d.time)

    @property
    def held(self) -> str | None:
        """The object in the hand, if any."""
        return self.w.held

    def robot_pose(self) -> Pose2D:
        """The base's pose (room frame)."""
        return self.w.base_pose()

    def objects(self) -> dict[str, ObjectState]:
        """Where every object is (room frame), its support read from contact."""
        out = {}
        for name in self.names:
            p = self.w.object_pose(name)
            x, y, z, tilt = p.x, p.y, p.z, p.tilt
            item = self.w.wm.objects[name]
            if item.style == "berry":
                # A berry has no up axis: any way up is upright, and where it lies is its
                # centre, whichever way it rolled.
                body = self.w.d.body(name)
                c = body.xpos + body.xmat.reshape(3, 3) @ np.array([0.0, 0.0, item.height / 2])
                x, y, z, tilt = float(c[0]), float(c[1]), float(c[2]) - item.height / 2, 0.0
            held = name == self.w.held
            table = None
            for t in self.scene.tables:
                top = self.w.top_z(t.name)
                if not held and t.contains(x, y) \
                        and top - ON_TABLE_BELOW_M <= z <= top + ON_TABLE_ABOVE_M:
                    table = t.name
                    break
            out[name] = ObjectState(name, x, y, z, p.yaw, tilt, table,
                                    self.w.support_of(name), held=held,
                                    tray=not held and table is None and self._on_tray(x, y, z))
        return out

    def _on_tray(self, x: float, y: float, z: float) -> bool:
        """Whether a body whose bottom centre is at ``(x, y, z)`` (room frame) rides on the
        robot's tray."""
        if TRAY_TOP not in self.w.wm.tops:
            return False
        b = self.w.base_pose()
        top = self.w.top_z(TRAY_TOP)
        return math.hypot(x - b.x, y - b.y) <= self.tray.radius_m + ON_TRAY_BEYOND_M \
            and top + ON_TRAY_Z_M[0] <= z <= top + ON_TRAY_Z_M[1]

    def picture(self, view: View = "room", size: tuple[int, int] | None = None,
                camera: str | None = None) -> np.ndarray:
        """An RGB image of the world now, from ``camera`` (``None``: the view's default;
        see :func:`~llm_grop.simulation.mujoco.render.picture`)."""
        return picture(self.w, view, size, camera)

    def close(self) -> None:
        """Finish the episode's video, if one is being recorded, and stop reporting."""
        if self.reporter is not None:
            self.w.observe = None
            self.reporter.close()
            self.reporter = None
        if self.on_close is not None:
            self.on_close()
            self.on_close = None

    def _step(self, step: ExecutedStep) -> ExecutedStep:
        """``step`` with all simulated time since the last attempt as its duration."""
        now = float(self.w.d.time)
        step = replace(step, duration_s=round(now - self.mark, 6))
        self.mark = now
        return step

    # -- navigation -------------------------------------------------------------------
    def navigate(self, goal: Pose2D, path: Sequence[Point] = ()) -> ExecutedStep:
        """One attempt to drive to ``goal`` with the base's navigation stack (see
        :mod:`~llm_grop.simulation.mujoco.drive`), along ``path`` when given, else along a
        path planned around the furniture and what the lidar saw last. With
        ``nav_noise_var_m2`` the base then drives on to a sampled offset (the authors'
        setting). The step records the arrival error the controller achieved."""
        self.w.dropped = None
        route = tuple(path) or self._path_to(goal)
        if not route:
            return self._step(ExecutedStep("navigate", False, 0.0, goal=goal, note="no path",
                                           reason="blocked"))
        d = drive.follow(self.w, route, goal, self.o.base)
        self.seen = d.seen
        passed = d.path
        if d.ok and self.o.nav_noise_var_m2 > 0:
            std = math.sqrt(self.o.nav_noise_var_m2)
            dx, dy = (float(v) for v in self.rng.normal(0.0, std, 2))
            dth = float(self.rng.normal(0.0, self.o.heading_noise_std_rad))
            here = self.w.base_pose()
            offset = Pose2D(here.x + dx, here.y + dy, goal.theta + dth)
            d = drive.follow(self.w, [(offset.x, offset.y)], offset, self.o.base)
            passed = passed + d.path[1:]
            self.seen = self.seen + d.seen
        error_m, error_rad = arrival_error(self.w.base_pose(), goal)
        ok, reason, note = d.ok, d.reason, "" if d.ok else f"navigation failed: {d.note}"
        if self.w.dropped is not None:
            ok, reason = False, "fell"
            note = f"dropped {self.w.dropped!r} in transit" + (f"; {note}" if note else "")
        return self._step(ExecutedStep(
            "navigate", ok, 0.0, goal=goal, path=passed, reason=reason, note=note,
            arrival_error_m=error_m, arrival_yaw_error_rad=error_rad))

    def _path_to(self, goal: Pose2D) -> tuple[Point, ...]:
        """A new path to ``goal`` from where the base stands; when the planner cannot start
        there (against furniture), from the nearest free spot around it."""
        here = self.w.base_pose()
        seed = int(self.rng.integers(2**31))
        for radius in START_SEARCH_M:
            for k in range(8 if radius else 1):
                a = 2 * math.pi * k / 8
                start = (here.x + radius * math.cos(a), here.y + radius * math.sin(a))
                path = self.replan.plan(start, (goal.x, goal.y), seed=seed,
                                        obstacles=self.seen)
                if path:
                    return path if radius else path[1:]
        return ()

    # -- manipulation -----------------------------------------------------------------
    def pick(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` where it lies."""
        if self.w.held is not None:
            return ExecutedStep("pick", False, 0.0, name,
                                note=f"pick refused: the hand holds {self.w.held!r}")
        standing = self.w.base_pose()
        p = self.w.object_pose(name)
        result = manipulation.pick(self.w, name)
        return self._step(ExecutedStep(
            "pick", result.ok, 0.0, name, standing=standing,
            pose=(round(p.x, 4), round(p.y, 4), 0.0), reason=result.reason,
            note="" if result.ok else f"pick failed: {result.note}"))

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        """One attempt to put the held ``name`` at ``(x, y, yaw)`` in the table frame
        (metres, radians), on ``on`` (``None``: the table), let go and let it settle."""
        if self.w.held != name:
            return ExecutedStep("place", False, 0.0, name,
                                note=f"place refused: the hand does not hold {name!r}")
        standing = self.w.base_pose()
        q = self.scene.table_to_room(x, y, yaw)
        result = manipulation.place(self.w, name, q.x, q.y, q.theta, on or self.scene.target)
        return self._step(ExecutedStep(
            "place", result.ok, 0.0, name, standing=standing, reason=result.reason,
            note="" if result.ok else f"place failed: {result.note}"))

    # -- the tray ---------------------------------------------------------------------
    def _footprint(self, name: str) -> tuple[str, tuple[float, float]]:
        item = self.w.wm.objects[name]
        return item.shape, (float(item.size[0]), float(item.size[1]))

    def _taken(self, besides: Sequence[str]) -> list[int]:
        """The slots of what rides on the tray now, ``besides`` left out."""
        riding = [n for n in self.slots if n not in besides]
        if not riding:
            return []
        states = self.objects()
        return [self.slots[n] for n in riding if states[n].tray]

    def fits_tray(self, names: Sequence[str]) -> bool:
        """Whether ``names`` fit on the tray together, besides what rides on it."""
        taken = self._taken(names)
        return self.tray.assign([self._footprint(n) for n in names], taken) is not None

    def load(self, name: str) -> ExecutedStep:
        """One attempt to put the held ``name`` on the tray, in the smallest free slot
        that fits it, turned as the slot wants it (a round object: whichever way the arm
        reaches), release it and let it settle. When the arm touches something on the way
        (``contact``, before letting go, the object still in the hand) or cannot reach
        the slot (``no_ik``), the other free slots that fit it are tried, smallest first:
        they take the elbow to other sides of the base (a wall beside the robot blocks
        the left-hand slots, not the others). All of them failing is a ``contact`` if
        any one's was."""
        taken = self._taken([name])
        slots = self.tray.assign([self._footprint(name)], taken) \
            if name in self.w.wm.objects else None
        if self.w.held != name or TRAY_TOP not in self.w.wm.tops or slots is None:
            why = f"the hand does not hold {name!r}" if self.w.held != name \
                else "no free slot on the tray fits it"
            return ExecutedStep("place", False, 0.0, name, note=f"load refused: {why}",
                                tray=True)
        shape, size = self._footprint(name)
        others = [k for k in sorted(range(len(self.tray.slots)),
                                    key=lambda k: self.tray.slots[k].area_m2)
                  if k != slots[0] and k not in taken
                  and self.tray.slots[k].yaw(shape, size) is not None]
        b, missed = self.w.base_pose(), []
        for k in (slots[0], *others):
            self.slots[name] = k
            result = self._load_into(name, k, b)
            if result.ok or result.reason not in ("contact", "no_ik") or self.w.held != name:
                break
            missed.append((k, result))
        if result.ok:
            note = "loaded into slot {} after {}".format(
                k, "; ".join(f"slot {j}: {a.note}" for j, a in missed)) if missed else ""
        elif len(missed) > 1 and missed[-1][1] is result:
            # Every slot that fits failed before the hand let go: a contact if any slot's
            # did (the hand still holds it, a retry may pass), else out of reach.
            reasons = {a.reason for _, a in missed}
            result = replace(result, reason="contact" if "contact" in reasons else "no_ik")
            note = "load failed: " + "; ".join(f"slot {j}: {a.note}" for j, a in missed)
        else:
            note = f"load failed: {result.note}"
        return self._step(ExecutedStep(
            "place", result.ok, 0.0, name, standing=b, reason=result.reason, tray=True,
            note=note))

    def _load_into(self, name: str, k: int, b: Pose2D) -> manipulation.Attempt:
        """One try to put the held ``name`` in the tray's slot ``k``, the base at ``b``."""
        slot = self.tray.slots[k]
        c, s = math.cos(b.theta), math.sin(b.theta)
        x, y = b.x + c * slot.x - s * slot.y, b.y + s * slot.x + c * slot.y
        shape, size = self._footprint(name)
        along = b.theta + (slot.yaw(shape, size) or 0.0)
        # A long object in a slot it fits either way (the large, square one) may also
        # lie across it, should the arm reach neither way along.
        across = shape != "circle" and max(size) / 2 <= min(slot.half_x, slot.half_y) + 1e-9
        turns = (0.0, math.pi, math.pi / 2, -math.pi / 2) if across else \
            (0.0, math.pi) if shape != "circle" else \
            tuple(math.pi * j / 4 for j in (0, 4, 2, -2, 1, -1, 3, -3))
        return manipulation.load(self.w, name, x, y, [along + t for t in turns])

    def unload(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` from the tray."""
        if self.w.held is not None:
            return ExecutedStep("pick", False, 0.0, name, tray=True,
                                note=f"unload refused: the hand holds {self.w.held!r}")
        standing = self.w.base_pose()
        result = manipulation.pick(self.w, name, from_tray=True)
        if result.ok:
            self.slots.pop(name, None)
        return self._step(ExecutedStep(
            "pick", result.ok, 0.0, name, standing=standing, reason=result.reason, tray=True,
            note="" if result.ok else f"unload failed: {result.note}"))

    def release(self, name: str) -> float:
        """Lower ``name``, if the hand holds it, in front of the base and let it fall to
        the floor; the simulated seconds it took."""
        if self.w.held == name:
            manipulation.release(self.w)
        now = float(self.w.d.time)
        spent, self.mark = now - self.mark, now
        return round(spent, 6)

