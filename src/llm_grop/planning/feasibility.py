"""The feasibility model: how likely navigation and manipulation succeed (paper §III-C).

As in the paper, uncertainty is a black box: a planner asks for success probabilities
and the simulator draws outcomes from the same model. Both functions live here, behind
the :class:`FeasibilityModel` protocol, so a learned model can replace them.

* **Navigation** to a goal succeeds with probability
  ``p_nav(c) = nav_max * sigmoid((c - nav_mid_m) / nav_scale_m)`` where ``c`` is the
  goal's clearance: the free distance, metres, from the base's footprint to the nearest
  table, wall or chair. A goal in collision (``c < 0``) has probability 0. With the
  defaults, 2 cm of clearance gives 0.49, 5 cm 0.80, 10 cm and more about 0.98.
* **Manipulation** (a pick or a place) at horizontal reach ``r`` (base centre to object,
  metres) succeeds with probability ``manip_max`` for ``reach_min <= r <= knee * reach_max``,
  falls smoothly (cosine) to 0 at ``reach_max``, and is 0 beyond it or below ``reach_min``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from llm_grop.world.robot import Robot

Floats = NDArray[np.float64]


class FeasibilityModel(Protocol):
    """Success probabilities of the robot's actions."""

    def navigation(self, clearance_m: ArrayLike) -> Floats:
        """Probability that navigating to goals with these clearances (metres) succeeds."""
        ...

    def manipulation(self, reach_m: ArrayLike, robot: Robot) -> Floats:
        """Probability that a pick or place at these reach distances (metres) succeeds."""
        ...


@dataclass(frozen=True)
class ParametricFeasibility:
    """The documented parametric model (see the module docstring).

    Attributes:
        nav_max: success probability of navigation with ample clearance.
        nav_mid_m: clearance, metres, at which navigation succeeds half as often.
        nav_scale_m: width of the navigation sigmoid, metres.
        manip_max: success probability of a pick or place well within reach.
        knee: fraction of the arm's reach beyond which manipulation gets harder.
    """

    nav_max: float = 0.98
    nav_mid_m: float = 0.02
    nav_scale_m: float = 0.02
    manip_max: float = 0.97
    knee: float = 0.7

    def navigation(self, clearance_m: ArrayLike) -> Floats:
        c = np.asarray(clearance_m, dtype=float)
        p = self.nav_max / (1.0 + np.exp(-(c - self.nav_mid_m) / self.nav_scale_m))
        return np.where(c < 0, 0.0, p)

    def manipulation(self, reach_m: ArrayLike, robot: Robot) -> Floats:
        r = np.asarray(reach_m, dtype=float)
        knee = self.knee * robot.reach_max_m
        t = np.clip((r - knee) / (robot.reach_max_m - knee), 0.0, 1.0)
        p = self.manip_max * 0.5 * (1.0 + np.cos(np.pi * t))
        return np.where((r < robot.reach_min_m) | (r >= robot.reach_max_m), 0.0, p)


#: The model every planner and the simulator use unless given another.
DEFAULT_FEASIBILITY = ParametricFeasibility()
