"""A MuJoCo episode driven one action at a time (see
:class:`~llm_grop.simulation.base.Session`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from llm_grop.simulation.mujoco.episode import Episode, final_placements
from llm_grop.simulation.mujoco.render import View, picture
from llm_grop.world.arrangement import Placement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep


class MujocoSession:
    """One episode in the 3D world; every method runs physics until its action ends."""

    def __init__(self, episode: Episode, placements: Sequence[Placement]) -> None:
        self.episode = episode
        self.objects = {p.name: p for p in placements}

    @property
    def time_s(self) -> float:
        """Simulated seconds so far."""
        return float(self.episode.w.d.time)

    @property
    def held(self) -> str | None:
        """The object in the hand, if any."""
        return self.episode.w.held

    def robot_pose(self) -> Pose2D:
        """The base's pose (room frame)."""
        return self.episode.w.base_pose()

    def object_poses(self) -> dict[str, tuple[float, float, float, float]]:
        """Every object's bottom centre ``(x, y, z)`` and yaw (room frame, metres, radians)."""
        out = {}
        for name in self.objects:
            p = self.episode.w.object_pose(name)
            out[name] = (p.x, p.y, p.z, p.yaw)
        return out

    def navigate(self, goal: Pose2D) -> ExecutedStep:
        """One attempt to drive to ``goal`` along a path the robot plans itself."""
        e = self.episode
        path = e.path_to(goal, (), first=False)
        if not path:
            e.record(ExecutedStep("navigate", False, 0.0, None, goal, note="no path"))
        elif e.drive_to(goal, path, None, 1):
            e.goal = goal
        return e.out[-1]

    def pick(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name``."""
        if self.held is not None:
            self.episode.record(ExecutedStep("pick", False, 0.0, name,
                                             note=f"pick failed: the hand holds {self.held!r}"))
            return self.episode.out[-1]
        return self.episode.pick(name)

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        """One attempt to place ``name`` at ``(x, y, yaw)`` in the table frame (metres,
        radians), on the object ``on`` if that is on the table."""
        p = self.objects[name]
        return self.episode.place(replace(p, x=x, y=y, yaw=yaw, on=on))

    def final(self) -> tuple[Placement, ...]:
        """Every object on the target table, where it is (table frame)."""
        return final_placements(self.episode.w, self.episode.scene, tuple(self.objects.values()))

    def picture(self, view: View = "room", size: tuple[int, int] | None = None) -> np.ndarray:
        """An RGB image of the world now."""
        return picture(self.episode.w, view, size)
