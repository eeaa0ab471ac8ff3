"""The MuJoCo simulator (registered as ``mujoco``): the plan executed by a mobile
manipulator in 3D physics.

* Navigation: the base follows the planned path under position control, turning in place
  between segments. Contact with furniture (a chair the planner did not expect, a table)
  stops it: a navigation failure; the robot backs off, replans from where it stopped and
  tries again, ``nav_attempts`` times per goal, then the plan's fallback goals. On arrival
  the base drives on to a noisy final pose (the authors' variance, 0.03 m² per axis);
  contact on that last stretch only stops it.
* Manipulation (:mod:`~llm_grop.simulation.mujoco.manipulation`): IK, pre-grasp, grasp,
  close, lift, carry; pre-place, lower, release, settle. A pick or a place that fails
  before release is retried ``manip_attempts`` times, re-approaching the standing pose
  (fresh noise) when the arm could not reach. An object that tips, slides or falls after
  release stays where physics left it.
* Truth: the final arrangement is read from the settled bodies (table frame); ``on`` is
  the tableware an object's bottom rests on.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from llm_grop.errors import BadInput
from llm_grop.simulation.base import PathPlanner
from llm_grop.simulation.mujoco import manipulation
from llm_grop.simulation.mujoco.arm import ArmIK
from llm_grop.simulation.mujoco.render import VideoRecorder, View, picture
from llm_grop.simulation.mujoco.tableware import Tableware, tableware
from llm_grop.simulation.mujoco.world import World
from llm_grop.simulation.mujoco.world_model import ObjectStart, build, check_scene
from llm_grop.world.arrangement import Item, Placement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, Execution, Plan, Step
from llm_grop.world.scene import Scene

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class MujocoOptions:
    """Settings of the 3D world.

    Attributes:
        nav_attempts: attempts per navigation goal (the authors used 3).
        manip_attempts: attempts per pick or place.
        nav_noise_var_m2: variance of the final base position, per axis, square metres.
        heading_noise_std_rad: standard deviation of the final heading, radians.
        timestep_s: physics time step, seconds.
        image_size: width and height of offscreen renders, pixels.
        video_path: where to write an MP4 video of the episode (``None``: no video).
        video_frame_s: simulated seconds between two video frames.
        video_fps: frames per second of the video.
    """

    nav_attempts: int = 3
    manip_attempts: int = 5
    nav_noise_var_m2: float = 0.03
    heading_noise_std_rad: float = 0.03
    timestep_s: float = 0.004
    image_size: tuple[int, int] = (640, 480)
    video_path: str | None = None
    video_frame_s: float = 0.2
    video_fps: int = 25


class MujocoSimulator:
    """Executes plans in MuJoCo. After :meth:`execute`, :attr:`world` holds the settled
    episode and :meth:`picture` renders it. ``on_frame`` is called with the world every
    ``options.video_frame_s`` simulated seconds (a video recorder, a viewer)."""

    name = "mujoco"

    def __init__(self, options: MujocoOptions | None = None, *,
                 on_frame: Callable[[World], None] | None = None) -> None:
        self.options = options or MujocoOptions()
        self.on_frame = on_frame
        self.world: World | None = None
        self._ik: ArmIK | None = None

    def picture(self, view: View = "table", size: tuple[int, int] | None = None
                ) -> np.ndarray:
        """An RGB image of the last episode as it ended (see
        :func:`~llm_grop.simulation.mujoco.render.picture`)."""
        if self.world is None:
            raise RuntimeError("nothing executed yet")
        return picture(self.world, view, size)

    def check(self, scene: Scene, items: Sequence[Item] = ()) -> None:
        """:class:`BadInput` when this scene or these objects cannot be simulated (called
        before planning, so bad input costs no work)."""
        check_scene(scene)
        for item in items:
            s = item.spec
            tableware(Placement(item.name, 0.0, 0.0, 0.0, s.shape, s.size, None, s.name,
                                s.height))

    def execute(self, plan: Plan, scene: Scene, rng: np.random.Generator, *,
                replan: PathPlanner) -> Execution:
        """Run ``plan`` in ``scene`` (its chairs are the real ones)."""
        if self._ik is None:
            self._ik = ArmIK()
        starts = []
        items = {p.name: tableware(p) for p in plan.configuration}
        for name, item in items.items():
            src = scene.source_for(name, item.kind)
            if src is None:
                raise BadInput(f"scene {scene.name!r}: no start for object {name!r}")
            starts.append(ObjectStart(item, src.x, src.y, scene.table(src.table).height))
        wm = build(scene, starts, timestep_s=self.options.timestep_s,
                   image_size=self.options.image_size)
        robot = scene.robot
        o = self.options
        recorder = VideoRecorder(o.video_path, fps=o.video_fps, size=o.image_size) \
            if o.video_path else None
        hooks = [h for h in (self.on_frame, recorder) if h is not None]
        world = World(wm, scene, self._ik, speed_mps=robot.speed_mps,
                      turn_speed_radps=robot.turn_speed_radps,
                      on_frame=(lambda w: [h(w) for h in hooks]) if hooks else None,
                      frame_dt_s=o.video_frame_s)
        self.world = world
        run = _Run(o, plan, scene, rng, replan, world)
        try:
            for step in plan.steps:
                if step.object in run.abandoned:
                    continue
                if step.action == "navigate":
                    run.navigate(step)
                else:
                    run.manipulate(step)
        finally:
            if recorder is not None:
                recorder.close()
        final = _final(world, scene, plan, items)
        placed = {p.name for p in final}
        unplaced = tuple(n for n in plan.order if n not in placed)
        run.absorb()
        return Execution(tuple(run.out), final, unplaced,
                         round(sum(s.duration_s for s in run.out), 6), world.base_pose())


def _final(w: World, scene: Scene, plan: Plan, items: dict[str, Tableware]
           ) -> tuple[Placement, ...]:
    """Every object resting on the target table, where it is (table frame)."""
    box = scene.target_table.box
    top = w.top_z(scene.target)
    out = []
    for p in plan.configuration:
        if p.name == w.held:
            continue
        pose = w.object_pose(p.name)
        inside = box.contains(pose.x, pose.y)
        if not (inside and top - 0.01 <= pose.z <= top + 0.5):
            continue
        x, y, yaw = scene.room_to_table(pose.x, pose.y, pose.yaw)
        out.append(Placement(p.name, round(x, 4), round(y, 4), round(yaw, 4), p.shape, p.size,
                             w.support_of(p.name), p.kind, p.height))
    return tuple(out)


class _Run:
    """The state of one execution."""

    def __init__(self, options: MujocoOptions, plan: Plan, scene: Scene,
                 rng: np.random.Generator, replan: PathPlanner, world: World) -> None:
        self.o, self.plan, self.scene, self.rng = options, plan, scene, rng
        self.replan, self.w = replan, world
        self.out: list[ExecutedStep] = []
        self.abandoned: set[str] = set()
        self.placed: set[str] = set()
        self.targets = {p.name: p for p in plan.configuration}
        self.goal: Pose2D | None = None
        self.mark = float(world.d.time)

    def _record(self, step: ExecutedStep) -> None:
        """Record ``step``; its duration is all simulated time since the last record."""
        step = replace(step, duration_s=round(float(self.w.d.time) - self.mark, 6))
        self.mark = float(self.w.d.time)
        log.debug("%s %s: %s (%.1f s)", step.action, step.object or "",
                  "ok" if step.ok else f"failed, {step.note}", step.duration_s)
        self.out.append(step)

    def absorb(self) -> None:
        """Add time spent since the last record (letting go of an abandoned object) to
        the last step, so that the steps account for every simulated second."""
        if self.out and self.w.d.time > self.mark:
            last = self.out[-1]
            self.out[-1] = replace(last, duration_s=round(
                last.duration_s + float(self.w.d.time) - self.mark, 6))
            self.mark = float(self.w.d.time)

    def _drive_to(self, goal: Pose2D, path: tuple[tuple[float, float], ...], name: str,
                  attempt: int) -> bool:
        """Drive ``path`` to ``goal`` and on to a noisy final pose; record the leg."""
        drive = self.w.drive(path, goal.theta)
        if not drive.ok:
            self.w.back_off()
            self._record(ExecutedStep("navigate", False, drive.duration_s, name, goal,
                                      drive.path, attempt=attempt,
                                      note=f"navigation failed: {drive.note}"))
            return False
        std = math.sqrt(self.o.nav_noise_var_m2)
        dx, dy = (float(v) for v in self.rng.normal(0.0, std, 2))
        dth = float(self.rng.normal(0.0, self.o.heading_noise_std_rad))
        here = self.w.base_pose()
        settle = self.w.drive([(here.x + dx, here.y + dy)], goal.theta + dth)
        self._record(ExecutedStep("navigate", True, drive.duration_s + settle.duration_s, name,
                                  goal, drive.path + settle.path[1:], attempt=attempt))
        return True

    def _path(self, goal: Pose2D, planned: tuple[tuple[float, float], ...], first: bool
              ) -> tuple[tuple[float, float], ...]:
        """The points to drive through to ``goal``: the planned path on a first attempt
        (from a noisy arrival the base first hops to its start), else a new one; when the
        base stands where the planner cannot start, via the last standing goal."""
        if first and planned:
            return planned
        here = self.w.base_pose()
        seed = int(self.rng.integers(2**31))
        path = self.replan.plan((here.x, here.y), (goal.x, goal.y), seed=seed)
        if path:
            return path[1:]
        last = self.goal
        if last is None or math.dist((last.x, last.y), (here.x, here.y)) < 1e-6:
            return ()
        path = self.replan.plan((last.x, last.y), (goal.x, goal.y), seed=seed)
        return path if path else ()

    def navigate(self, step: Step) -> None:
        assert step.goal is not None
        name = step.object or ""
        for k, goal in enumerate((step.goal, *step.alternatives)):
            for attempt in range(1, self.o.nav_attempts + 1):
                path = self._path(goal, step.path, first=(k == 0 and attempt == 1))
                if not path:
                    self._record(ExecutedStep("navigate", False, 0.0, name, goal,
                                              attempt=attempt, note="no path"))
                    break
                if self._drive_to(goal, path, name, attempt):
                    self.goal = goal
                    return
        self.abandoned.add(name)
        manipulation.release(self.w)
        self.absorb()

    def _reapproach(self, name: str) -> None:
        """Drive back to the current standing goal, with fresh arrival noise."""
        if self.goal is None:
            return
        path = self._path(self.goal, (), first=False)
        if path:
            self._drive_to(self.goal, path, name, 1)

    def manipulate(self, step: Step) -> None:
        name = step.object or ""
        standing = self.w.base_pose()
        for attempt in range(1, self.o.manip_attempts + 1):
            if step.action == "pick":
                result = manipulation.pick(self.w, name)
                pose = step.pose
            else:
                t = self.targets[name]
                q = self.scene.table_to_room(t.x, t.y, t.yaw)
                support = t.on if t.on in self.placed else self.scene.target
                result = manipulation.place(self.w, name, q.x, q.y, q.theta, support)
                p = self.w.object_pose(name)
                pose = tuple(round(v, 4) for v in self.scene.room_to_table(p.x, p.y, p.yaw))
            self._record(ExecutedStep(step.action, result.ok, result.duration_s, name,
                                      standing=standing, pose=pose, attempt=attempt,
                                      note="" if result.ok else
                                      f"{step.action} failed: {result.note}"))
            if result.ok:
                if step.action == "place":
                    self.placed.add(name)
                return
            if step.action == "place" and self.w.held != name:
                return  # released: it lies where physics left it
            if result.note.startswith("no IK solution"):
                self._reapproach(name)
                standing = self.w.base_pose()
        self.abandoned.add(name)
        manipulation.release(self.w)
        self.absorb()
