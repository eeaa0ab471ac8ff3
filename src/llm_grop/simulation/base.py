"""The simulator interface.

A simulator executes a :class:`~llm_grop.world.plan.Plan` in a scene and reports an
:class:`~llm_grop.world.plan.Execution`. The planner never sees which backend runs its
plan, so a 3D physics backend can be registered beside the 2D kinematic one.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from llm_grop.planning.feasibility import FeasibilityModel
from llm_grop.world.plan import Execution, Plan, Point
from llm_grop.world.scene import Scene


class PathPlanner(Protocol):
    """Plans a collision-free path for the base from ``start`` to ``goal`` (room frame)."""

    def plan(self, start: Point, goal: Point, seed: int) -> tuple[Point, ...] | None:
        """The path's points in metres, or ``None`` when there is none."""
        ...


class Simulator(Protocol):
    """Executes plans; outcomes are drawn from ``model`` with ``rng`` (a black box)."""

    name: str

    def execute(self, plan: Plan, scene: Scene, rng: np.random.Generator, *,
                replan: PathPlanner, model: FeasibilityModel) -> Execution:
        """Run ``plan`` in ``scene`` (its chairs are the true ones) and report what happened."""
        ...
