"""One episode in the MuJoCo world: navigation legs and picks and places, each attempt
recorded as an :class:`~llm_grop.world.plan.ExecutedStep`, and the final arrangement read
from the settled bodies. Used by the simulator (a whole plan) and by sessions (one action
at a time)."""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from llm_grop.simulation.base import PathPlanner
from llm_grop.simulation.mujoco import manipulation
from llm_grop.simulation.mujoco.options import MujocoOptions
from llm_grop.simulation.mujoco.world import World
from llm_grop.world.arrangement import Placement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, Step
from llm_grop.world.scene import Scene

log = logging.getLogger(__name__)


def final_placements(w: World, scene: Scene, placements: Sequence[Placement]
                     ) -> tuple[Placement, ...]:
    """Every object resting on the target table, where it is (table frame)."""
    table = scene.target_table
    top = w.top_z(scene.target)
    out = []
    for p in placements:
        if p.name == w.held:
            continue
        pose = w.object_pose(p.name)
        inside = table.contains(pose.x, pose.y)
        if not (inside and top - 0.01 <= pose.z <= top + 0.5):
            continue
        x, y, yaw = scene.room_to_table(pose.x, pose.y, pose.yaw)
        out.append(replace(p, x=round(x, 4), y=round(y, 4), yaw=round(yaw, 4),
                           on=w.support_of(p.name)))
    return tuple(out)


class Episode:
    """One episode in the world: what has been done, with every attempt recorded."""

    def __init__(self, options: MujocoOptions, scene: Scene, rng: np.random.Generator,
                 replan: PathPlanner, world: World) -> None:
        self.o, self.scene, self.rng = options, scene, rng
        self.replan, self.w = replan, world
        self.out: list[ExecutedStep] = []
        self.abandoned: set[str] = set()
        self.placed: set[str] = set()
        self.last_unreachable = False
        self.goal: Pose2D | None = None
        self.mark = float(world.d.time)

    def record(self, step: ExecutedStep) -> None:
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

    def drive_to(self, goal: Pose2D, path: tuple[tuple[float, float], ...], name: str | None,
                 attempt: int) -> bool:
        """Drive ``path`` to ``goal`` and on to a noisy final pose; record the leg."""
        drive = self.w.drive(path, goal.theta)
        if not drive.ok:
            self.w.back_off()
            self.record(ExecutedStep("navigate", False, drive.duration_s, name, goal,
                                      drive.path, attempt=attempt,
                                      note=f"navigation failed: {drive.note}"))
            return False
        std = math.sqrt(self.o.nav_noise_var_m2)
        dx, dy = (float(v) for v in self.rng.normal(0.0, std, 2))
        dth = float(self.rng.normal(0.0, self.o.heading_noise_std_rad))
        here = self.w.base_pose()
        settle = self.w.drive([(here.x + dx, here.y + dy)], goal.theta + dth, holonomic=True)
        if not settle.ok:
            self.w.back_off()
        self.record(ExecutedStep("navigate", settle.ok, 0.0, name, goal,
                                  drive.path + settle.path[1:], attempt=attempt,
                                  note="" if settle.ok else
                                  f"navigation failed on arrival: {settle.note}"))
        return settle.ok

    def path_to(self, goal: Pose2D, planned: tuple[tuple[float, float], ...], first: bool
                ) -> tuple[tuple[float, float], ...]:
        """The points to drive through to ``goal``: the planned path on a first attempt
        (from a noisy arrival the base first hops to its start), else a new one. When the
        base stands where the planner cannot start (against furniture), the path starts
        at the nearest free spot around it, up to 30 cm away."""
        if first and planned:
            return planned
        here = self.w.base_pose()
        seed = int(self.rng.integers(2**31))
        for radius in (0.0, 0.1, 0.2, 0.3):
            for k in range(8 if radius else 1):
                a = 2 * math.pi * k / 8
                start = (here.x + radius * math.cos(a), here.y + radius * math.sin(a))
                path = self.replan.plan(start, (goal.x, goal.y), seed=seed)
                if path:
                    return path if radius else path[1:]
        return ()

    def navigate(self, step: Step) -> None:
        assert step.goal is not None
        name = step.object or ""
        for k, goal in enumerate((step.goal, *step.alternatives)):
            for attempt in range(1, self.o.nav_attempts + 1):
                path = self.path_to(goal, step.path, first=(k == 0 and attempt == 1))
                if not path:
                    self.record(ExecutedStep("navigate", False, 0.0, name, goal,
                                              attempt=attempt, note="no path"))
                    break
                if self.drive_to(goal, path, name, attempt):
                    self.goal = goal
                    return
        self.abandoned.add(name)
        manipulation.release(self.w)
        self.absorb()

    def _reapproach(self, name: str) -> None:
        """Drive back to the current standing goal, with fresh arrival noise."""
        if self.goal is None:
            return
        path = self.path_to(self.goal, (), first=False)
        if path:
            self.drive_to(self.goal, path, name, 1)

    def pick(self, name: str, attempt: int = 1, pose: tuple[float, float, float] | None = None
             ) -> ExecutedStep:
        """One attempt to pick ``name``."""
        standing = self.w.base_pose()
        result = manipulation.pick(self.w, name)
        self.last_unreachable = result.unreachable
        self.record(ExecutedStep("pick", result.ok, result.duration_s, name, standing=standing,
                                 pose=pose, attempt=attempt,
                                 note="" if result.ok else f"pick failed: {result.note}"))
        return self.out[-1]

    def place(self, target: Placement, attempt: int = 1) -> ExecutedStep:
        """One attempt to place the held object at ``target`` (table frame), on its
        support if that has been placed, else on the table."""
        name = target.name
        standing = self.w.base_pose()
        q = self.scene.table_to_room(target.x, target.y, target.yaw)
        support = target.on if target.on in self.placed else self.scene.target
        if self.w.held != name:
            result = manipulation.Attempt(False, 0.0, f"the hand does not hold {name!r}")
        else:
            result = manipulation.place(self.w, name, q.x, q.y, q.theta, support)
        self.last_unreachable = result.unreachable
        p = self.w.object_pose(name)
        # Where it landed, table frame; nothing while the hand still holds it.
        pose = None if self.w.held == name else \
            tuple(round(v, 4) for v in self.scene.room_to_table(p.x, p.y, p.yaw))
        self.record(ExecutedStep("place", result.ok, result.duration_s, name,
                                 standing=standing, pose=pose,  # type: ignore[arg-type]
                                 attempt=attempt,
                                 note="" if result.ok else f"place failed: {result.note}"))
        if result.ok:
            self.placed.add(name)
        return self.out[-1]

    def manipulate(self, step: Step, target: Placement) -> None:
        """A planned pick or place, retried as the options allow."""
        name = step.object or ""
        for attempt in range(1, self.o.manip_attempts + 1):
            done = self.pick(name, attempt, step.pose) if step.action == "pick" \
                else self.place(target, attempt)
            if done.ok:
                return
            if step.action == "place" and self.w.held != name:
                return  # released: it lies where physics left it
            if self.last_unreachable:
                self._reapproach(name)
        self.abandoned.add(name)
        manipulation.release(self.w)
        self.absorb()
