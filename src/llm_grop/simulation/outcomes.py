"""The 2D kinematic simulator's ground truth: how often the robot's actions really succeed.

The planner has its own belief (:mod:`llm_grop.planning.feasibility`); the simulator never
sees it. By default the truth has the same shape and numbers as the planner's default
belief, as in the paper, where uncertainty is a black box the planner models well; give
:class:`~llm_grop.simulation.kinematic2d.Kinematic2DOptions` other outcomes to study a
planner whose belief is wrong.

* Navigation to a goal with clearance ``c`` (metres, from the base's footprint to the
  nearest obstacle, real chairs included) succeeds with
  ``nav_max / (1 + exp(-(c - nav_mid_m) / nav_scale_m))``, and never in collision.
* A pick or a place at horizontal reach ``r`` (metres, base centre to object) succeeds with
  ``manip_max`` up to ``knee`` of the arm's reach, falling as a half cosine to 0 at full
  reach; never closer than the arm's minimum reach or beyond its full reach.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from llm_grop.world.robot import Robot


class Outcomes(Protocol):
    """The true success probabilities of the robot's actions, one action at a time."""

    def navigation(self, clearance_m: float) -> float:
        """Probability that navigating to a goal with this clearance (metres) succeeds."""
        ...

    def manipulation(self, reach_m: float, robot: Robot) -> float:
        """Probability that a pick or a place at this reach (metres) succeeds."""
        ...


@dataclass(frozen=True)
class ParametricOutcomes:
    """The parametric truth described in the module docstring (probabilities 0-1, metres)."""

    nav_max: float = 0.98
    nav_mid_m: float = 0.02
    nav_scale_m: float = 0.02
    manip_max: float = 0.97
    knee: float = 0.7

    def navigation(self, clearance_m: float) -> float:
        if clearance_m < 0:
            return 0.0
        return self.nav_max / (1.0 + math.exp(-(clearance_m - self.nav_mid_m)
                                              / self.nav_scale_m))

    def manipulation(self, reach_m: float, robot: Robot) -> float:
        if not robot.reach_min_m <= reach_m < robot.reach_max_m:
            return 0.0
        knee_m = self.knee * robot.reach_max_m
        t = min(max((reach_m - knee_m) / (robot.reach_max_m - knee_m), 0.0), 1.0)
        return self.manip_max * 0.5 * (1.0 + math.cos(math.pi * t))
