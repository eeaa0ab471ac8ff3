"""A 2D kinematic simulator: the robot drives paths and its actions succeed or fail with
the simulator's own true probabilities (:mod:`llm_grop.simulation.outcomes`; uncertainty
as a black box, as in the paper). It offers primitives only; the executive
(:mod:`llm_grop.execution`) decides what to try next.

* **Navigation** follows the given path, or one the robot plans, at the robot's speed,
  turning in place between segments. It succeeds with the true probability for the
  goal's true clearance (real chairs); a failed attempt is a ``contact`` that stops the
  robot part-way. Arrival has Gaussian pose noise.
* **Picks and places** beyond the arm's reach fail as ``no_ik`` after the robot's
  ``ik_failure_s``; within reach they succeed with their true probability. A failed pick
  missed its grasp. A failed place is drawn from ``place_failures``: a ``contact`` keeps
  the object in the hand; otherwise the hand lets go and the object slides away, tips
  over or falls to the floor, and stays where it came to rest.
* A placed object lands at its target plus small Gaussian noise, on the object it was
  put on if that rests on the target table.
* **The tray** (:mod:`llm_grop.world.tray`, the 3D robot's): loading puts the held
  object in a free slot that fits it, unloading takes it back into the hand. They are a
  place and a pick at the arm's sure reach (the robot's ``reach_min_m``: the tray lies
  on the base), with a place's and a pick's true chances and the truth's load and
  unload durations (``load_time_s``, ``unload_time_s``; unstated: a place's and a
  pick's); a failed load
  goes as a failed place does (``contact``: still in the hand; ``slid``: elsewhere on the
  tray, which carries it as well; ``tipped``: on its side on the tray; ``fell``: to the
  floor). What rides on the tray moves with the base.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from llm_grop.geometry.motion import arrival_error, leg_duration_s, path_length_m, path_prefix
from llm_grop.geometry.obstacles import Obstacles
from llm_grop.simulation.base import PathPlanner, Simulator
from llm_grop.simulation.kinematic2d_options import Kinematic2DOptions
from llm_grop.simulation.outcomes import ParametricOutcomes
from llm_grop.world.arrangement import Item
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, ObjectState, Point
from llm_grop.world.scene import Scene
from llm_grop.world.tray import Tray, load_tray

log = logging.getLogger(__name__)

#: Height above the floor of an object in the hand, metres (for observations).
CARRY_Z_M = 1.1
#: Tilt of an object that tipped over onto its side, radians.
TIPPED_RAD = math.pi / 2
#: Where a given-up object falls: beside the base, this far to its left or right (metres),
#: clear of the tables, as the 3D arm lowers it.
DROP_SIDE_M = 0.5


class Kinematic2D(Simulator):
    """The 2D kinematic simulator (registered as ``kinematic2d``): no pictures of its own
    (the room's drawing stands in for them)."""

    name = "kinematic2d"
    Options = Kinematic2DOptions

    def __init__(self, options: Kinematic2DOptions | None = None) -> None:
        options = options or Kinematic2DOptions()
        if options.truth is not None:
            options = replace(options, outcomes=ParametricOutcomes.from_profile(options.truth))
        self.options = options

    def tray_capacity(self) -> int:
        """The tray's (the 3D robot's, :func:`~llm_grop.world.tray.load_tray`)."""
        return load_tray().capacity

    def fitted_profile(self) -> str:
        """The profile its outcomes are drawn from: ``truth``, else ``default`` (whose
        curves are the 2D simulator's own)."""
        return self.options.truth or "default"

    def session(self, scene: Scene, items: Sequence[Item], rng: np.random.Generator, *,
                replan: PathPlanner) -> Kinematic2DSession:
        """A new episode in ``scene`` with ``items`` at their starts."""
        return Kinematic2DSession(self.options, scene, items, rng, replan)


class Kinematic2DSession:
    """One episode of the 2D simulator (see :class:`~llm_grop.simulation.base.Session`)."""

    def __init__(self, options: Kinematic2DOptions, scene: Scene, items: Sequence[Item],
                 rng: np.random.Generator, replan: PathPlanner) -> None:
        self.o, self.scene, self.rng, self.replan = options, scene, rng, replan
        self.truth, self.robot = options.outcomes, scene.robot
        self.obstacles = Obstacles(scene, include_chairs=True)
        self.pose = scene.robot_start
        self._time_s = 0.0
        self.heights = {i.name: i.spec.height for i in items}
        self.footprints = {i.name: (i.spec.shape, i.spec.size) for i in items}
        self.states: dict[str, ObjectState] = {}
        for i in items:
            src = scene.source_for(i.name, i.spec.name)
            if src is not None:
                # In a pile, on the objects under it.
                self.states[i.name] = ObjectState(
                    i.name, src.x, src.y, scene.resting_z(i.name, i.spec.name, self.heights),
                    0.0, table=src.table, on=src.on if src.on in self.heights else None)
        #: The object in the hand.
        self.hand: str | None = None
        #: What rides on the tray: its slot, its yaw in the base's frame and its tilt
        #: (radians).
        self.on_tray: dict[str, tuple[int, float, float]] = {}
        self.tray: Tray = load_tray()

    # -- state ------------------------------------------------------------------------
    @property
    def time_s(self) -> float:
        """Simulated seconds so far."""
        return self._time_s

    @property
    def held(self) -> str | None:
        """The object in the hand."""
        return self.hand

    def robot_pose(self) -> Pose2D:
        """The base's pose (room frame)."""
        return self.pose

    def objects(self) -> dict[str, ObjectState]:
        """Where every object is (room frame); one in the hand rides with the base."""
        out = dict(self.states)
        p = self.pose
        c, s = math.cos(p.theta), math.sin(p.theta)
        for name, (k, yaw, tilt) in self.on_tray.items():
            slot = self.tray.slots[k]
            out[name] = ObjectState(name, p.x + c * slot.x - s * slot.y,
                                    p.y + s * slot.x + c * slot.y, self.tray.top_z_m,
                                    p.theta + yaw, tilt, tray=True)
        if self.hand is not None:
            out[self.hand] = ObjectState(self.hand, p.x, p.y, CARRY_Z_M, p.theta, held=True)
        return out

    def close(self) -> None:
        """Nothing to finish in 2D."""

    def _step(self, step: ExecutedStep) -> ExecutedStep:
        self._time_s += step.duration_s
        return step

    # -- navigation -------------------------------------------------------------------
    def _clearance(self, x: float, y: float) -> float:
        """Free distance, metres, from the base's footprint at ``(x, y)`` to any obstacle."""
        return float(self.obstacles.clearance(np.array([[x, y]]))[0]) - self.robot.base_radius_m

    def _path(self, goal: Pose2D, planned: Sequence[Point]) -> tuple[Point, ...]:
        here = (self.pose.x, self.pose.y)
        # After a noisy arrival the robot is a few cm off the planned start: keep the plan
        # when the detour to its second point is free, as a local planner would.
        if len(planned) > 1 and math.dist(here, planned[0]) < 0.15 \
                and self.obstacles.segment_free(here, planned[1], self.robot.base_radius_m,
                                                tolerance_m=1e-6):
            return (here, *planned[1:])
        path = self.replan.plan(here, (goal.x, goal.y), seed=int(self.rng.integers(2**31)))
        return path if path is not None else ()

    def navigate(self, goal: Pose2D, path: Sequence[Point] = ()) -> ExecutedStep:
        """One attempt to drive to ``goal``, along ``path`` when given."""
        route = self._path(goal, path)
        if not route:
            return self._step(ExecutedStep("navigate", False, 0.0, goal=goal, note="no path",
                                           reason="blocked"))
        p = self.truth.navigation(self._clearance(goal.x, goal.y))
        if self.rng.random() < p:
            duration = leg_duration_s(self.pose, goal, route, self.robot) \
                + float(self.truth.leg_overhead_s)
            self.pose = self._arrive(goal)
            error_m, error_rad = arrival_error(self.pose, goal)
            return self._step(ExecutedStep(
                "navigate", True, duration, goal=goal, path=route, arrival_error_m=error_m,
                arrival_yaw_error_rad=error_rad))
        length = path_length_m(route)
        frac = float(self.rng.uniform(*self.o.stop_fraction))
        driven = path_prefix(route, frac * length)
        end = driven[-1]
        heading = math.atan2(end[1] - driven[-2][1], end[0] - driven[-2][0]) \
            if len(driven) > 1 else self.pose.theta
        self.pose = Pose2D(end[0], end[1], heading)
        return self._step(ExecutedStep("navigate", False, frac * length / self.robot.speed_mps,
                                       goal=goal, path=driven, reason="contact",
                                       note="navigation failed: the base bumped into furniture"))

    def _arrive(self, goal: Pose2D) -> Pose2D:
        """Where the robot really stops: the goal plus noise, unless that collides."""
        dx, dy = self.rng.normal(0.0, self.o.nav_noise_std_m, 2)
        dth = float(self.rng.normal(0.0, self.o.heading_noise_std_rad))
        noisy = Pose2D(goal.x + float(dx), goal.y + float(dy), goal.theta + dth)
        return noisy if self._clearance(noisy.x, noisy.y) >= 0 else goal

    # -- manipulation -----------------------------------------------------------------
    def _out_of_reach(self, action: str, name: str, x: float, y: float
                      ) -> tuple[float, ExecutedStep | None]:
        """The reach to ``(x, y)`` (room frame, metres), and the failed step when the arm
        cannot reach it."""
        reach = math.hypot(x - self.pose.x, y - self.pose.y)
        limit = self.truth.reach_limit_m(self.robot)
        if self.robot.reach_min_m <= reach < limit:
            return reach, None
        return reach, self._step(ExecutedStep(
            action, False, self.robot.ik_failure_s, name, standing=self.pose,
            reason="no_ik", note=f"no IK solution (reach {reach:.2f} m)"))

    def pick(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` where it lies."""
        st = self.states.get(name)
        if st is None or self.hand is not None:
            why = f"no object {name!r}" if st is None else "the hand is full"
            return ExecutedStep("pick", False, 0.0, name, note=f"pick refused: {why}")
        reach, failed = self._out_of_reach("pick", name, st.x, st.y)
        if failed is not None:
            return failed
        standing, start = self.pose, (round(st.x, 4), round(st.y, 4), 0.0)
        p = self.truth.manipulation(reach, self.robot)
        if st.table is None or st.tilt_rad > TIPPED_RAD / 2:
            p = 0.0  # lying on its side or on the floor: the gripper cannot close on it
        if self.rng.random() < p:
            self._lift(name)
            self.hand = name
            return self._step(ExecutedStep("pick", True, self._seconds("pick"), name,
                                           standing=standing, pose=start))
        return self._step(ExecutedStep("pick", False, self._seconds("pick"), name,
                                       standing=standing, pose=start, reason="grasp_missed",
                                       note=f"the grasp missed (reach {reach:.2f} m)"))

    def _lift(self, name: str) -> None:
        """``name`` leaves where it lies; what rested on it settles onto what it rested on.
        A pile's objects are of one kind, so taking one from the middle stands for taking
        the top one: the arm gets the same object either way."""
        st = self.states.pop(name)
        drop = self.heights.get(name, 0.0)
        above = next((o for o in self.states.values() if o.on == name), None)
        if above is not None:
            self.states[above.name] = replace(above, on=st.on)
        while above is not None:
            self.states[above.name] = replace(self.states[above.name], z=above.z - drop)
            above = next((o for o in self.states.values() if o.on == above.name), None)

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        """One attempt to put the held ``name`` at ``(x, y, yaw)`` (table frame)."""
        if name != self.hand:
            return ExecutedStep("place", False, 0.0, name,
                                note=f"place refused: the hand does not hold {name!r}")
        q = self.scene.table_to_room(x, y, yaw)
        reach, failed = self._out_of_reach("place", name, q.x, q.y)
        if failed is not None:
            return failed
        standing, seconds = self.pose, self._seconds("place")
        if self.rng.random() < self.truth.placing(reach, self.robot):
            dx, dy = self.rng.normal(0.0, self.o.place_noise_std_m, 2)
            dyaw = float(self.rng.normal(0.0, self.o.place_yaw_noise_std_rad))
            self._land(name, q.x + float(dx), q.y + float(dy), q.theta + dyaw, on)
            return self._step(ExecutedStep("place", True, seconds, name, standing=standing))
        reasons = [r for r, _ in self.o.place_failures]
        weights = np.array([w for _, w in self.o.place_failures], dtype=float)
        why = reasons[int(self.rng.choice(len(reasons), p=weights / weights.sum()))]
        if why == "slid":
            a = float(self.rng.uniform(-math.pi, math.pi))
            d = float(self.rng.uniform(*self.o.slide_m))
            self._land(name, q.x + d * math.cos(a), q.y + d * math.sin(a), q.theta, None)
        elif why == "tipped":
            self._land(name, q.x, q.y, q.theta, None, tilt_rad=TIPPED_RAD)
        elif why == "fell":
            self._drop(name)
        else:
            return self._step(ExecutedStep("place", False, self._seconds("place"),
                                           name, standing=standing, reason=why,
                                           note=f"place failed: {why}"))
        # Let go, but not where it was meant to go: the executive judges where it lies.
        return self._step(ExecutedStep("place", True, seconds, name, standing=standing))

    def _seconds(self, action: str) -> float:
        """How long a pick, place, load or unload attempt takes (the truth's
        declaration)."""
        return self.truth.attempt_time_s(action, self.robot)

    def _land(self, name: str, x: float, y: float, yaw: float, on: str | None,
              tilt_rad: float = 0.0) -> None:
        """``name`` comes to rest at ``(x, y)`` (room frame): on ``on`` when that lies on
        the target table, on the table under it otherwise, or on the floor."""
        self.hand = None
        target = self.scene.target_table
        under = self.states.get(on or "")
        if under is not None and under.table == target.name and under.tilt_rad == 0.0:
            z = under.z + self.heights.get(under.name, 0.0)
            self.states[name] = ObjectState(name, x, y, z, yaw, tilt_rad, target.name, on)
        elif target.contains(x, y):
            self.states[name] = ObjectState(name, x, y, target.height, yaw, tilt_rad,
                                            target.name)
        else:
            self.states[name] = ObjectState(name, x, y, 0.0, yaw, TIPPED_RAD)

    def _drop(self, name: str) -> None:
        """``name`` falls to the floor beside the base, on the first side clear of the
        tables (under the base when neither is)."""
        self.hand = None
        p = self.pose
        x, y = p.x, p.y
        for side in (1.0, -1.0):
            sx = p.x - side * DROP_SIDE_M * math.sin(p.theta)
            sy = p.y + side * DROP_SIDE_M * math.cos(p.theta)
            if not any(t.contains(sx, sy) for t in self.scene.tables):
                x, y = sx, sy
                break
        self.states[name] = ObjectState(name, x, y, 0.0, p.theta, TIPPED_RAD)

    def release(self, name: str) -> float:
        """Put ``name`` down on the floor in front of the base if it is carried (no time in
        2D)."""
        if name == self.hand:
            self._drop(name)
        return 0.0

    # -- the tray ---------------------------------------------------------------------
    def fits_tray(self, names: Sequence[str]) -> bool:
        """Whether ``names`` fit on the tray together, besides what rides on it."""
        taken = [k for k, _, _ in self.on_tray.values()]
        return self.tray.assign([self.footprints[n] for n in names], taken) is not None

    def load(self, name: str) -> ExecutedStep:
        """One attempt to put the held ``name`` on the tray, in the smallest free slot
        that fits it."""
        taken = [k for k, _, _ in self.on_tray.values()]
        slots = self.tray.assign([self.footprints.get(name, ("circle", (0.0, 0.0)))], taken)
        if name != self.hand or slots is None:
            why = f"the hand does not hold {name!r}" if name != self.hand \
                else "no free slot on the tray fits it"
            return ExecutedStep("place", False, 0.0, name, note=f"load refused: {why}",
                                tray=True)
        k = slots[0]
        yaw = self.tray.slots[k].yaw(*self.footprints[name]) or 0.0
        standing, seconds = self.pose, self._seconds("load")
        if self.rng.random() >= self.truth.placing(self.robot.reach_min_m, self.robot):
            reasons = [r for r, _ in self.o.place_failures]
            weights = np.array([w for _, w in self.o.place_failures], dtype=float)
            why = reasons[int(self.rng.choice(len(reasons), p=weights / weights.sum()))]
            if why == "contact":
                return self._step(ExecutedStep("place", False, seconds, name,
                                               standing=standing, reason=why, tray=True,
                                               note="load failed: contact"))
            if why == "fell":
                self._drop(name)
                return self._step(ExecutedStep("place", True, seconds, name,
                                               standing=standing, tray=True))
            # Slid: elsewhere on the tray, which carries it as well; tipped: on its side.
            self.on_tray[name] = (k, yaw, TIPPED_RAD if why == "tipped" else 0.0)
        else:
            self.on_tray[name] = (k, yaw, 0.0)
        self.hand = None
        return self._step(ExecutedStep("place", True, seconds, name, standing=standing,
                                       tray=True))

    def unload(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` from the tray."""
        if name not in self.on_tray or self.hand is not None:
            why = f"{name!r} is not on the tray" if name not in self.on_tray \
                else "the hand is full"
            return ExecutedStep("pick", False, 0.0, name, note=f"unload refused: {why}",
                                tray=True)
        standing, seconds = self.pose, self._seconds("unload")
        tipped = self.on_tray[name][2] > TIPPED_RAD / 2
        p = 0.0 if tipped else self.truth.manipulation(self.robot.reach_min_m, self.robot)
        if self.rng.random() < p:
            del self.on_tray[name]
            self.hand = name
            return self._step(ExecutedStep("pick", True, seconds, name, standing=standing,
                                           tray=True))
        return self._step(ExecutedStep("pick", False, seconds, name, standing=standing,
                                       reason="grasp_missed", tray=True,
                                       note="the grasp on the tray missed"))
