"""The mobile manipulator's parameters (a UR5e-class arm on a round mobile base)."""

from __future__ import annotations

from dataclasses import dataclass

from llm_grop.errors import BadInput

#: How far each of the gripper's pads opens past the side of the object it grasps, metres:
#: the hand opens to the object's width plus twice this.
GRIP_CLEARANCE_M = 0.015
#: A finger's thickness with its pad, metres (``simulation/mujoco/assets/robot.xml``).
FINGER_THICKNESS_M = 0.02


@dataclass(frozen=True)
class Robot:
    """A mobile manipulator.

    Attributes:
        base_radius_m: radius of the base's circular footprint, metres.
        reach_min_m: closest horizontal distance, base centre to an object, at which the arm
            can still grasp or place it, metres.
        reach_max_m: farthest such distance (the arm's reach envelope), metres; beyond it
            manipulation is impossible.
        speed_mps: navigation speed along a path, metres per second.
        turn_speed_radps: turning speed in place, radians per second.
        pick_time_s: time for one pick attempt, seconds.
        place_time_s: time for one place attempt, seconds.
        ik_failure_s: time the arm's motion planner spends before it reports that no
            inverse kinematics solution reaches a pose, seconds.
        capacity: how many objects it carries at once.
    """

    base_radius_m: float = 0.30
    reach_min_m: float = 0.25
    reach_max_m: float = 0.85
    speed_mps: float = 0.5
    turn_speed_radps: float = 1.0
    pick_time_s: float = 8.0
    place_time_s: float = 8.0
    ik_failure_s: float = 2.0
    capacity: int = 1

    def __post_init__(self) -> None:
        for name in ("base_radius_m", "reach_max_m", "speed_mps", "turn_speed_radps"):
            if not getattr(self, name) > 0:
                raise BadInput(f"robot.{name}: must be positive, got {getattr(self, name)}")
        if not 0 <= self.reach_min_m < self.reach_max_m:
            raise BadInput(
                f"robot.reach_min_m: must be in [0, reach_max_m), got {self.reach_min_m}")
        if self.pick_time_s < 0 or self.place_time_s < 0 or self.ik_failure_s < 0:
            raise BadInput("robot.pick_time_s/place_time_s/ik_failure_s: must not be negative")
        if self.capacity < 1:
            raise BadInput(f"robot.capacity: must be at least 1, got {self.capacity}")
