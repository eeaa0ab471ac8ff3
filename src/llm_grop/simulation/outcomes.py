"""The 2D kinematic simulator's ground truth: how often the robot's actions really succeed.

The planner has its own belief (:mod:`llm_grop.planning.feasibility`); the simulator never
sees it. By default the truth has the same shape and numbers as the planner's default
belief, as in the paper, where uncertainty is a black box the planner models well; give
:class:`~llm_grop.simulation.kinematic2d.Kinematic2DOptions` other outcomes to study a
planner whose belief is wrong, or a packaged profile's (``--truth mujoco``: what the 3D
world was measured to do, so that 2D is a fast stand-in for it).

* Navigation to a goal with clearance ``c`` (metres, from the base's footprint to the
  nearest obstacle, real chairs included) succeeds with
  ``nav_max / (1 + exp(-(c - nav_mid_m) / nav_scale_m))``, and never in collision.
* A pick or a place at horizontal reach ``r`` (metres, base centre to object) succeeds with
  ``manip_max`` up to ``knee`` of the arm's reach, falling as a half cosine to 0 at full
  reach; never closer than the arm's minimum reach or beyond its full reach.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Protocol

from llm_grop.files.profiles import Curves, load_profile
from llm_grop.world.robot import Robot


class Outcomes(Protocol):
    """The true success probabilities and durations of the robot's actions, one action at
    a time: what a truth declares (:class:`BaseOutcomes` gives the defaults of a truth
    that states only probabilities)."""

    #: Seconds added to every drive beyond its path at full speed and its turns.
    leg_overhead_s: float

    def navigation(self, clearance_m: float) -> float:
        """Probability that navigating to a goal with this clearance (metres) succeeds."""
        ...

    def manipulation(self, reach_m: float, robot: Robot) -> float:
        """Probability that a pick at this reach (metres) succeeds."""
        ...

    def placing(self, reach_m: float, robot: Robot) -> float:
        """Probability that a place at this reach (metres) succeeds."""
        ...

    def reach_limit_m(self, robot: Robot) -> float:
        """The reach (metres) at and beyond which the arm cannot pick or place."""
        ...

    def attempt_time_s(self, action: str, robot: Robot) -> float:
        """Seconds one ``pick``, ``place``, ``load`` (onto the tray) or ``unload`` (from
        it) attempt takes, whether it succeeds or not."""
        ...


class BaseOutcomes:
    """The defaults of a truth that states only :meth:`navigation` and
    :meth:`manipulation`: places succeed as picks do, the arm reaches as far as the
    robot's, attempts take the robot's times and drives no overhead."""

    leg_overhead_s: float = 0.0

    def manipulation(self, reach_m: float, robot: Robot) -> float:
        """Probability that a pick at this reach (metres) succeeds."""
        raise NotImplementedError

    def placing(self, reach_m: float, robot: Robot) -> float:
        """Probability that a place at this reach succeeds: a pick's."""
        return self.manipulation(reach_m, robot)

    def reach_limit_m(self, robot: Robot) -> float:
        """The robot's full reach, metres."""
        return robot.reach_max_m

    def attempt_time_s(self, action: str, robot: Robot) -> float:
        """The robot's own seconds for ``action`` (a load takes a place's, an unload a
        pick's)."""
        return robot.pick_time_s if action in ("pick", "unload") else robot.place_time_s


@dataclass(frozen=True)
class ParametricOutcomes(Curves):
    """The parametric truth described in the module docstring, one action at a time; its
    numbers (:class:`~llm_grop.files.profiles.Curves`) include how long actions take: a
    pick or place attempt takes ``pick_time_s`` or ``place_time_s`` (``None``: the
    robot's) whether it succeeds or not, a load onto the tray or an unload from it
    ``load_time_s`` or ``unload_time_s`` (``None``: a place's or a pick's), and
    ``leg_overhead_s`` is added to every drive.
    (``failed_attempt_s``, what the planner expects a failure to cost with its recovery,
    is the 2D simulator's to produce, not to draw.)
    """

    @classmethod
    def from_profile(cls, name: str) -> ParametricOutcomes:
        """The truth of the packaged profile ``name`` (:mod:`llm_grop.files.profiles`);
        :class:`~llm_grop.errors.BadInput` for an unknown one."""
        return cls(**asdict(load_profile(name, "truth").curves))

    def navigation(self, clearance_m: float) -> float:
        return float(self.navigation_p(clearance_m))

    def manipulation(self, reach_m: float, robot: Robot) -> float:
        return float(self.manipulation_p(reach_m, robot))

    def placing(self, reach_m: float, robot: Robot) -> float:
        """Probability that a place at this reach (metres) succeeds."""
        return float(self.manipulation_p(reach_m, robot, place=True))

    def reach_limit_m(self, robot: Robot) -> float:
        """The profile's full reach, else the robot's, metres."""
        return self.reach_max_m or robot.reach_max_m

    def attempt_time_s(self, action: str, robot: Robot) -> float:
        """The profile's seconds for ``action`` (:meth:`Curves.action_time_s`)."""
        return self.action_time_s(action, robot)
