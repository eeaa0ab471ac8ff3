"""The simulator interface: primitives, one attempt at a time.

A simulator offers sessions. A session is one episode in a scene, driven one action at a
time: each navigate, pick or place is a single attempt that returns a typed
:class:`~llm_grop.world.plan.ExecutedStep`, and the session reports where every object
physically is (:class:`~llm_grop.world.plan.ObjectState`). It owns its ground truth: what
really happens when the robot drives, picks and places (its own success model or physics,
the true chairs). What to try next, when to give up and what counts as success belong to
the executive above it (:mod:`llm_grop.execution`), as in dm_control and robosuite, where
the physics offers state and actuation and the task logic lives above. The planner's
feasibility model is only a belief and never reaches a simulator. Backends are registered
in :mod:`llm_grop.simulation.registry`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from llm_grop.world.arrangement import Item
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, ObjectState, Point
from llm_grop.world.scene import Scene


class PathPlanner(Protocol):
    """The robot's own path planner, for replanning after a failed navigation: a
    collision-free path for the base from ``start`` to ``goal`` (room frame), around the
    known furniture and the ``obstacles`` the robot's sensors saw (room-frame points)."""

    def plan(self, start: Point, goal: Point, seed: int,
             obstacles: Sequence[Point] = ()) -> tuple[Point, ...] | None:
        """The path's points in metres, or ``None`` when there is none."""
        ...


class Session(Protocol):
    """One episode driven one attempt at a time.

    Poses are room frame unless said otherwise (metres, radians). A failed attempt's step
    says why in ``reason`` (:data:`~llm_grop.world.plan.REASONS`); its ``duration_s`` is
    the simulated time it took, a failed inverse kinematics attempt included.
    """

    @property
    def time_s(self) -> float:
        """Simulated seconds so far."""
        ...

    @property
    def held(self) -> str | None:
        """The object in the hand, if any."""
        ...

    def robot_pose(self) -> Pose2D:
        """The base's pose."""
        ...

    def objects(self) -> dict[str, ObjectState]:
        """Where every object of the episode physically is, after the physics settled."""
        ...

    def navigate(self, goal: Pose2D, path: Sequence[Point] = ()) -> ExecutedStep:
        """One attempt to drive to ``goal``: along ``path`` when given (the plan's), else
        along a path the robot plans itself from where it stands."""
        ...

    def pick(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` from where it lies, from where the robot stands."""
        ...

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        """One attempt to put the held ``name`` down at ``(x, y, yaw)`` in the target
        table's frame, on the object ``on`` (``None``: the table). ``ok`` means the hand
        let go there; where the object then came to rest is read from :meth:`objects`."""
        ...

    def release(self, name: str) -> float:
        """Give up ``name`` if the hand holds it: put it down away from the target table (on
        the floor). The simulated seconds it took."""
        ...

    def close(self) -> None:
        """End the episode (a video being recorded is finished)."""
        ...


class Simulator(Protocol):
    """Offers sessions. ``name`` is the name it is registered under (it goes into the run
    JSON); all randomness comes from the ``rng`` given to :meth:`session`."""

    name: str

    def session(self, scene: Scene, items: Sequence[Item], rng: np.random.Generator, *,
                replan: PathPlanner) -> Session:
        """A new episode in ``scene`` (its chairs are the true ones) with ``items`` at
        their starts."""
        ...
