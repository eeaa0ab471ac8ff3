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

Named profiles of the parametric model live in ``data/feasibility.yaml``
(:mod:`llm_grop.files.profiles`): ``default`` (assumed, the paper's black box) and
``mujoco`` (fitted to episodes run through the executive in the 3D world by
``benchmarks/fit_profile.py``), with the actions' expected durations. Choose one with
``--feasibility NAME``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from llm_grop.files.profiles import Curves, load_profile, profile_names
from llm_grop.world.robot import Robot

__all__ = ["DEFAULT_FEASIBILITY", "ActionTimes", "FeasibilityModel",
           "ParametricFeasibility", "action_times", "feasibility_profile", "placing",
           "profile_names"]

Floats = NDArray[np.float64]


class FeasibilityModel(Protocol):
    """Success probabilities and expected durations of the robot's actions: what a
    belief (a packaged profile, or a learned model of a user's) declares."""

    def navigation(self, clearance_m: ArrayLike) -> Floats:
        """Probability that navigating to goals with these clearances (metres) succeeds."""
        ...

    def manipulation(self, reach_m: ArrayLike, robot: Robot) -> Floats:
        """Probability that a pick at these reach distances (metres) succeeds."""
        ...

    def placing(self, reach_m: ArrayLike, robot: Robot) -> Floats:
        """Probability that a place at these reach distances (metres) succeeds (a model
        that does not tell picks and places apart returns :meth:`manipulation`'s)."""
        ...

    def action_times(self, robot: Robot) -> ActionTimes:
        """The seconds it believes the robot's actions take (a model that states none
        returns the robot's own, with no overhead)."""
        ...


@dataclass(frozen=True)
class ParametricFeasibility(Curves):
    """The documented parametric model (see the module docstring and
    :class:`~llm_grop.files.profiles.Curves`, which holds its numbers)."""

    def navigation(self, clearance_m: ArrayLike) -> Floats:
        return self.navigation_p(clearance_m)

    def manipulation(self, reach_m: ArrayLike, robot: Robot) -> Floats:
        return self.manipulation_p(reach_m, robot)

    def placing(self, reach_m: ArrayLike, robot: Robot) -> Floats:
        """Probability that a place at these reach distances (metres) succeeds."""
        return self.manipulation_p(reach_m, robot, place=True)

    def action_times(self, robot: Robot) -> ActionTimes:
        """The profile's times, the robot's own where it states none."""
        return ActionTimes(self.action_time_s("pick", robot),
                           self.action_time_s("place", robot), self.leg_overhead_s,
                           self.failed_attempt_s, self.action_time_s("load", robot),
                           self.action_time_s("unload", robot))


#: The model every planner and the simulator use unless given another.
DEFAULT_FEASIBILITY = ParametricFeasibility()


@dataclass(frozen=True)
class ActionTimes:
    """Expected seconds of the robot's actions under a belief: a successful pick and
    place, a drive's overhead beyond its path and turns, a failed attempt, and a
    successful load onto the tray and unload from it (``None``: a place's and a
    pick's)."""

    pick_s: float
    place_s: float
    leg_overhead_s: float
    failed_attempt_s: float
    stated_load_s: float | None = None
    stated_unload_s: float | None = None

    @property
    def load_s(self) -> float:
        """Seconds of a load onto the tray (a place's unless stated)."""
        return self.place_s if self.stated_load_s is None else self.stated_load_s

    @property
    def unload_s(self) -> float:
        """Seconds of an unload from the tray (a pick's unless stated)."""
        return self.pick_s if self.stated_unload_s is None else self.stated_unload_s


def action_times(model: FeasibilityModel, robot: Robot) -> ActionTimes:
    """The times ``model`` believes in (:meth:`FeasibilityModel.action_times`)."""
    return model.action_times(robot)


def feasibility_profile(name: str) -> ParametricFeasibility:
    """The packaged profile called ``name`` as a belief; :class:`BadInput` for an unknown
    one."""
    return ParametricFeasibility(**asdict(load_profile(name).curves))


#: Success probabilities below this count as this in a plan's expected retries (a plan
#: never chooses a step it believes impossible).
MIN_RETRY_P = 0.05


def expected_failures(p: float) -> float:
    """Expected failed attempts before an action of success probability ``p`` succeeds,
    ``1/p - 1``, with ``p`` counted down to :data:`MIN_RETRY_P`."""
    return 1.0 / max(p, MIN_RETRY_P) - 1.0


def placing(model: FeasibilityModel, reach_m: ArrayLike, robot: Robot) -> Floats:
    """Probability that a place at these reaches succeeds
    (:meth:`FeasibilityModel.placing`)."""
    return model.placing(reach_m, robot)
