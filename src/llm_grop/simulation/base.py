"""The simulator interface.

A simulator executes a :class:`~llm_grop.world.plan.Plan` in a scene and reports an
:class:`~llm_grop.world.plan.Execution`. It owns its ground truth: what really happens
when the robot drives, picks and places (its own success model or physics, the true
chairs). The planner's feasibility model is only a belief and never reaches it, and the
planner never learns which simulator runs its plan. Backends are registered in
:mod:`llm_grop.simulation.registry`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from llm_grop.world.arrangement import Item, Placement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, Execution, Plan, Point
from llm_grop.world.scene import Scene


class PathPlanner(Protocol):
    """The robot's own path planner, for replanning after a failed navigation: a
    collision-free path for the base from ``start`` to ``goal`` (room frame)."""

    def plan(self, start: Point, goal: Point, seed: int) -> tuple[Point, ...] | None:
        """The path's points in metres, or ``None`` when there is none."""
        ...


class Simulator(Protocol):
    """Executes plans. ``name`` is the name it is registered under (it goes into the run
    JSON); all randomness comes from the ``rng`` given to :meth:`execute`."""

    name: str

    def execute(self, plan: Plan, scene: Scene, rng: np.random.Generator, *,
                replan: PathPlanner) -> Execution:
        """Run ``plan`` in ``scene`` (its chairs are the true ones) and report what happened.

        ``final`` holds every object that reached the table where it really ended up
        (table frame), and each successful ``place`` step's ``pose`` is where it landed.
        """
        ...


class SessionSimulator(Protocol):
    """A simulator that can also be driven one action at a time."""

    name: str

    def session(self, scene: Scene, items: Sequence[Item], rng: np.random.Generator, *,
                replan: PathPlanner) -> Session:
        """A new episode in ``scene`` with ``items`` at their starts."""
        ...


class Session(Protocol):
    """One episode driven one action at a time, for agents that choose their own actions
    (the Gymnasium environment). A simulator that offers it has a method
    ``session(scene, items, rng, *, replan) -> Session``.

    Poses are room frame unless said otherwise (metres, radians); each action returns the
    :class:`~llm_grop.world.plan.ExecutedStep` it produced.
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

    def object_poses(self) -> dict[str, tuple[float, float, float, float]]:
        """Every object's bottom centre ``(x, y, z)`` and yaw."""
        ...

    def navigate(self, goal: Pose2D) -> ExecutedStep:
        """One attempt to drive to ``goal`` along a path the robot plans itself."""
        ...

    def pick(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` from where the robot stands."""
        ...

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        """One attempt to put the held ``name`` at ``(x, y, yaw)`` in the table frame, on
        the object ``on`` (``None``: the table)."""
        ...

    def final(self) -> tuple[Placement, ...]:
        """Every object on the target table, where it is (table frame)."""
        ...
