"""A 2D kinematic simulator: the robot drives planned paths and its actions succeed or fail
with the simulator's own true probabilities (:mod:`llm_grop.simulation.outcomes`;
uncertainty as a black box, as in the paper).

* Navigation follows the path at the robot's speed, turning in place between segments.
  It succeeds with the true probability for the goal's true clearance (real chairs);
  a failed attempt stops part-way and the robot replans from where it stopped. After
  ``nav_attempts`` failures it tries the plan's next fallback standing position; when all
  fail, the object is abandoned.
* Arrival has Gaussian pose noise; picks and places succeed with their true probability
  for the real reach, retried up to ``manip_attempts`` times. A place that still fails
  is tried again from the plan's fallback standing positions for it, in turn (the robot
  drives there first), before the object is abandoned.
* A placed object lands at its target plus small Gaussian noise. An object whose support
  never arrived rests on the table. The final arrangement is read from where objects are.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from llm_grop.geometry.motion import leg_duration_s, path_length_m, path_prefix
from llm_grop.geometry.obstacles import Obstacles
from llm_grop.simulation.base import PathPlanner
from llm_grop.simulation.outcomes import Outcomes, ParametricOutcomes
from llm_grop.world.arrangement import Item, Placement, item_placement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, Execution, Plan, Point, Step
from llm_grop.world.scene import Scene

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Kinematic2DOptions:
    """The simulated world's truth: success probabilities, noise and retry settings.

    Attributes:
        outcomes: how often navigation, picks and places really succeed.
        nav_attempts: attempts per navigation goal (the authors used 3).
        manip_attempts: attempts per pick or place.
        nav_noise_std_m: standard deviation of the arrival position, per axis, metres.
        heading_noise_std_rad: standard deviation of the arrival heading, radians.
        place_noise_std_m: standard deviation of a placed object's position, metres.
        place_yaw_noise_std_rad: standard deviation of a placed object's yaw, radians.
        stop_fraction: a failed navigation stops this far along its path (uniform range).
    """

    nav_attempts: int = 3
    manip_attempts: int = 5
    nav_noise_std_m: float = 0.02
    heading_noise_std_rad: float = 0.03
    place_noise_std_m: float = 0.005
    place_yaw_noise_std_rad: float = 0.02
    stop_fraction: tuple[float, float] = (0.3, 0.9)
    outcomes: Outcomes = field(default_factory=ParametricOutcomes)


class Kinematic2D:
    """The 2D kinematic simulator (registered as ``kinematic2d``)."""

    name = "kinematic2d"

    def __init__(self, options: Kinematic2DOptions | None = None) -> None:
        self.options = options or Kinematic2DOptions()

    def session(self, scene: Scene, items: Sequence[Item], rng: np.random.Generator, *,
                replan: PathPlanner) -> Kinematic2DSession:
        """A new episode driven one action at a time (the Gymnasium environment uses it)."""
        return Kinematic2DSession(self.options, scene, items, rng, replan)

    def execute(self, plan: Plan, scene: Scene, rng: np.random.Generator, *,
                replan: PathPlanner) -> Execution:
        """Run ``plan`` in ``scene``; its chairs are the real ones."""
        run = Run(self.options, plan, scene, rng, replan)
        fallbacks: tuple[Pose2D, ...] = ()
        for step in plan.steps:
            if step.object in run.abandoned:
                continue
            if step.action == "navigate":
                run.navigate(step)
                fallbacks = step.alternatives
                continue
            run.manipulate(step)
            if step.action != "place":
                continue
            for goal in fallbacks:
                if step.object not in run.abandoned:
                    break
                # Step round the table and try the place from the next fallback position.
                run.abandoned.discard(step.object or "")
                run.navigate(Step("navigate", step.object, goal))
                if step.object not in run.abandoned:
                    run.manipulate(step)
        order = {p.name: i for i, p in enumerate(plan.configuration)}
        final = tuple(sorted(run.placed.values(), key=lambda p: order.get(p.name, 0)))
        unplaced = tuple(n for n in plan.order if n not in run.placed)
        return Execution(tuple(run.out), final, unplaced, run.time_s, run.pose)


class Run:
    """The state of one execution: where the robot and the objects are, and every attempt
    so far."""

    def __init__(self, options: Kinematic2DOptions, plan: Plan, scene: Scene,
                 rng: np.random.Generator, replan: PathPlanner) -> None:
        self.o, self.plan, self.scene, self.rng = options, plan, scene, rng
        self.replan, self.truth, self.robot = replan, options.outcomes, scene.robot
        self.obstacles = Obstacles(scene, include_chairs=True)
        self.pose = scene.robot_start
        self.time_s = 0.0
        self.out: list[ExecutedStep] = []
        self.placed: dict[str, Placement] = {}
        self.abandoned: set[str] = set()
        self.targets = {p.name: p for p in plan.configuration}
        self.legs = 0

    def _clearance(self, x: float, y: float) -> float:
        """Free distance, metres, from the base's footprint at ``(x, y)`` to any obstacle."""
        return float(self.obstacles.clearance(np.array([[x, y]]))[0]) - self.robot.base_radius_m

    def _path(self, goal: Pose2D, planned: tuple[Point, ...], first: bool) -> tuple[Point, ...]:
        here = (self.pose.x, self.pose.y)
        # After noisy arrival the robot is a few cm off the planned start: keep the plan
        # when the detour to its second point is free, as a local planner would.
        if first and len(planned) > 1 and math.dist(here, planned[0]) < 0.15 \
                and self.obstacles.segment_free(here, planned[1], self.robot.base_radius_m,
                                                tolerance_m=1e-6):
            return (here, *planned[1:])
        self.legs += 1
        seed = int(self.rng.integers(2**31))
        path = self.replan.plan(here, (goal.x, goal.y), seed=seed)
        return path if path is not None else ()

    def navigate(self, step: Step) -> None:
        assert step.goal is not None
        for k, goal in enumerate((step.goal, *step.alternatives)):
            p = self.truth.navigation(self._clearance(goal.x, goal.y))
            for attempt in range(1, self.o.nav_attempts + 1):
                path = self._path(goal, step.path, first=(k == 0 and attempt == 1))
                if not path:
                    self.record(ExecutedStep("navigate", False, 0.0, step.object, goal,
                                              attempt=attempt, note="no path"))
                    break
                length = path_length_m(path)
                if self.rng.random() < p:
                    duration = leg_duration_s(self.pose, goal, path, self.robot)
                    self.record(ExecutedStep("navigate", True, duration, step.object, goal,
                                              path, attempt=attempt))
                    self.pose = self._arrive(goal)
                    return
                frac = float(self.rng.uniform(*self.o.stop_fraction))
                driven = path_prefix(path, frac * length)
                self.record(ExecutedStep("navigate", False, frac * length / self.robot.speed_mps,
                                          step.object, goal, driven, attempt=attempt,
                                          note="navigation failed"))
                end = driven[-1]
                heading = math.atan2(end[1] - driven[-2][1], end[0] - driven[-2][0]) \
                    if len(driven) > 1 else self.pose.theta
                self.pose = Pose2D(end[0], end[1], heading)
        self.abandoned.add(step.object or "")

    def _arrive(self, goal: Pose2D) -> Pose2D:
        """Where the robot really stops: the goal plus noise, unless that collides."""
        dx, dy = self.rng.normal(0.0, self.o.nav_noise_std_m, 2)
        dth = float(self.rng.normal(0.0, self.o.heading_noise_std_rad))
        noisy = Pose2D(goal.x + float(dx), goal.y + float(dy), goal.theta + dth)
        return noisy if self._clearance(noisy.x, noisy.y) >= 0 else goal

    def manipulate(self, step: Step) -> None:
        name = step.object or ""
        if step.action == "pick":
            assert step.pose is not None
            xy = (step.pose[0], step.pose[1])
            duration = self.robot.pick_time_s
        else:
            t = self.targets[name]
            q = self.scene.table_to_room(t.x, t.y)
            xy, duration = (q.x, q.y), self.robot.place_time_s
        reach = math.hypot(xy[0] - self.pose.x, xy[1] - self.pose.y)
        p = self.truth.manipulation(reach, self.robot)
        standing = self.pose
        for attempt in range(1, self.o.manip_attempts + 1):
            ok = bool(self.rng.random() < p)
            landed = self._land(name) if ok and step.action == "place" else None
            self.record(ExecutedStep(
                step.action, ok, duration, name, standing=standing,
                pose=(landed.x, landed.y, landed.yaw) if landed else step.pose,
                attempt=attempt, note="" if ok else f"{step.action} failed (reach {reach:.2f} m)"))
            if ok:
                if landed is not None:
                    self.placed[name] = landed
                return
        self.abandoned.add(name)

    def _land(self, name: str) -> Placement:
        """The object as it lands: its target with noise, on its support if that is there."""
        t = self.targets[name]
        dx, dy = self.rng.normal(0.0, self.o.place_noise_std_m, 2)
        dyaw = float(self.rng.normal(0.0, self.o.place_yaw_noise_std_rad))
        on = t.on if t.on in self.placed else None
        return replace(t, x=t.x + float(dx), y=t.y + float(dy), yaw=t.yaw + dyaw, on=on)

    def record(self, step: ExecutedStep) -> None:
        log.debug("%s %s: %s (%.1f s)", step.action, step.object or "",
                  "ok" if step.ok else f"failed, {step.note}", step.duration_s)
        self.out.append(step)
        self.time_s += step.duration_s


#: Height above the floor of an object in the hand, metres (for observations).
CARRY_Z_M = 1.1


class Kinematic2DSession:
    """One episode of the 2D simulator driven one action at a time (see
    :class:`~llm_grop.simulation.base.Session`): the same truth and noise as
    :class:`Kinematic2D`, one attempt per action."""

    def __init__(self, options: Kinematic2DOptions, scene: Scene, items: Sequence[Item],
                 rng: np.random.Generator, replan: PathPlanner) -> None:
        self.items = {i.name: i for i in items}
        shapes = tuple(item_placement(i) for i in items)
        plan = Plan((), (), shapes, 0, 0.0, 1.0, 0.0)
        self.run = Run(replace(options, nav_attempts=1, manip_attempts=1), plan, scene, rng,
                        replan)
        self.scene = scene
        self.starts: dict[str, tuple[float, float, float]] = {}
        for i in items:
            src = scene.source_for(i.name, i.spec.name)
            if src is not None:
                self.starts[i.name] = (src.x, src.y, scene.table(src.table).height)
        self._held: str | None = None

    @property
    def time_s(self) -> float:
        """Simulated seconds so far."""
        return self.run.time_s

    @property
    def held(self) -> str | None:
        """The object in the hand, if any."""
        return self._held

    def robot_pose(self) -> Pose2D:
        """The base's pose (room frame)."""
        return self.run.pose

    def object_poses(self) -> dict[str, tuple[float, float, float, float]]:
        """Every object's bottom centre ``(x, y, z)`` and yaw (room frame)."""
        top = self.scene.target_table.height
        out = {}
        for name in self.items:
            if name == self._held:
                p = self.run.pose
                out[name] = (p.x, p.y, CARRY_Z_M, p.theta)
            elif name in self.run.placed:
                pl = self.run.placed[name]
                q = self.scene.table_to_room(pl.x, pl.y, pl.yaw)
                under = self.run.placed.get(pl.on or "")
                out[name] = (q.x, q.y, top + (under.height if under else 0.0), q.theta)
            else:
                x, y, z = self.starts.get(name, (math.nan, math.nan, 0.0))
                out[name] = (x, y, z, 0.0)
        return out

    def _last(self) -> ExecutedStep:
        self.run.abandoned.clear()
        return self.run.out[-1]

    def navigate(self, goal: Pose2D) -> ExecutedStep:
        """One attempt to drive to ``goal`` along a path the robot plans itself."""
        self.run.navigate(Step("navigate", None, goal))
        return self._last()

    def pick(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` where it lies."""
        if self._held is not None or name not in self.items:
            why = f"the hand holds {self._held!r}" if self._held else f"no object {name!r}"
            self.run.record(ExecutedStep("pick", False, 0.0, name, note=f"pick failed: {why}"))
            return self._last()
        x, y, _, _ = self.object_poses()[name]
        self.run.manipulate(Step("pick", name, pose=(x, y, 0.0)))
        step = self._last()
        if step.ok:
            self._held = name
            self.run.placed.pop(name, None)
        return step

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        """One attempt to put the held ``name`` at ``(x, y, yaw)`` (table frame)."""
        if self._held != name:
            self.run.record(ExecutedStep("place", False, 0.0, name,
                                          note=f"place failed: the hand does not hold {name!r}"))
            return self._last()
        shape = self.run.targets[name]
        self.run.targets[name] = replace(shape, x=x, y=y, yaw=yaw, on=on)
        self.run.manipulate(Step("place", name))
        step = self._last()
        if step.ok:
            self._held = None
        return step

    def final(self) -> tuple[Placement, ...]:
        """Every object on the target table (table frame)."""
        return tuple(self.run.placed.values())
