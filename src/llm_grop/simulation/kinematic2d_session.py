"""A 2D kinematic episode driven one action at a time (see
:class:`~llm_grop.simulation.base.Session`): the same truth and noise as
:class:`~llm_grop.simulation.kinematic2d.Kinematic2D`, one attempt per action."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from llm_grop.simulation.base import PathPlanner
from llm_grop.simulation.kinematic2d import Kinematic2DOptions, _Run
from llm_grop.world.arrangement import Item, Placement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, Plan, Step
from llm_grop.world.scene import Scene

#: Height above the floor of an object in the hand, metres (for observations).
CARRY_Z_M = 1.1


class Kinematic2DSession:
    """One episode of the 2D simulator."""

    def __init__(self, options: Kinematic2DOptions, scene: Scene, items: Sequence[Item],
                 rng: np.random.Generator, replan: PathPlanner) -> None:
        self.items = {i.name: i for i in items}
        shapes = tuple(Placement(i.name, 0.0, 0.0, 0.0, i.spec.shape, i.spec.size, None,
                                 i.spec.name, i.spec.height) for i in items)
        plan = Plan((), (), shapes, 0, 0.0, 1.0, 0.0)
        self.run = _Run(replace(options, nav_attempts=1, manip_attempts=1), plan, scene, rng,
                        replan)
        self.scene = scene
        self.starts = {}
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
        for name, item in self.items.items():
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
            del item
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
            self.run._record(ExecutedStep("pick", False, 0.0, name, note=f"pick failed: {why}"))
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
            self.run._record(ExecutedStep("place", False, 0.0, name,
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
