"""Inverse kinematics for the arm, with ``mink`` on MuJoCo's own model of the robot.

IK runs on the robot's MJCF alone with the base and finger joints removed, so targets are
in the base frame (metres, x forward, z up from the floor) and the answer is the six arm
joint angles (radians). The hand always points straight down; ``yaw`` turns the direction
its pads close along.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mink
import mujoco
import numpy as np

from llm_grop.simulation.mujoco.world_model import robot_xml

#: The arm's joints, in actuator order.
ARM_JOINTS = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
#: A comfortable elbow-up posture that reaches forward and down (radians); IK is pulled
#: gently towards it so that solutions stay on one branch.
READY = np.array([0.0, 0.8, 1.4, -0.6, -math.pi / 2, 0.0])
#: Where the pads carry an object while the base drives: above the base's front edge,
#: higher than any table or chair back (base frame, metres).
CARRY_TARGET = (0.25, 0.0, 1.10)


@dataclass(frozen=True)
class IKResult:
    """An IK answer: arm joint angles ``q`` (radians) and the remaining position and
    orientation errors (metres, radians); ``ok`` when both are within tolerance."""

    q: np.ndarray
    position_error_m: float
    orientation_error_rad: float
    ok: bool


class ArmIK:
    """Differential IK (mink, QP solver daqp) for the ``grasp`` site, within joint limits."""

    def __init__(self, *, position_tol_m: float = 2e-3, orientation_tol_rad: float = 2e-2,
                 iterations: int = 150) -> None:
        spec = mujoco.MjSpec.from_file(robot_xml())
        for act in list(spec.actuators):
            spec.delete(act)
        for joint in list(spec.joints):
            if joint.name not in ARM_JOINTS:
                spec.delete(joint)
        self.model = spec.compile()
        self.configuration = mink.Configuration(self.model)
        self.task = mink.FrameTask("grasp", "site", position_cost=1.0, orientation_cost=0.5)
        self.posture = mink.PostureTask(self.model, cost=1e-3)
        self.posture.set_target(READY)
        self.limits = [mink.ConfigurationLimit(self.model)]
        self.position_tol_m = position_tol_m
        self.orientation_tol_rad = orientation_tol_rad
        self.iterations = iterations
        self._carry: np.ndarray | None = None

    def solve(self, target: tuple[float, float, float], yaw: float,
              start: np.ndarray | None = None, *, elbow_up: bool = True) -> IKResult:
        """Joint angles putting the grasp site at ``target`` (base frame, metres), the hand
        pointing down and its pads closing along ``yaw`` (radians, base frame); with
        ``elbow_up`` only answers whose elbow is above the wrist count (an elbow-down arm
        sweeps the table)."""
        c, s = math.cos(yaw), math.sin(yaw)
        rotation = np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])
        self.task.set_target(mink.SE3.from_rotation_and_translation(
            mink.SO3.from_matrix(rotation), np.asarray(target, float)))
        best: IKResult | None = None
        for seed in (READY,) if start is None else (READY, start):
            self.configuration.update(np.asarray(seed, float).copy())
            for _ in range(self.iterations):
                v = mink.solve_ik(self.configuration, [self.task, self.posture], 0.1, "daqp",
                                  damping=1e-3, limits=self.limits)
                self.configuration.integrate_inplace(v, 0.1)
                err = self.task.compute_error(self.configuration)
                ep, eo = float(np.linalg.norm(err[:3])), float(np.linalg.norm(err[3:]))
                if ep < self.position_tol_m / 4 and eo < self.orientation_tol_rad / 4:
                    break
            ok = ep < self.position_tol_m and eo < self.orientation_tol_rad \
                and (not elbow_up or self._elbow_up())
            result = IKResult(self.configuration.q.copy(), ep, eo, ok)
            if ok:
                return result
            if best is None or ep < best.position_error_m:
                best = result
        assert best is not None
        return best

    def _elbow_up(self) -> bool:
        """Whether the elbow is above the wrist."""
        data = self.configuration.data
        return bool(data.body("forearm").xpos[2] > data.body("wrist_1").xpos[2])

    def carry(self) -> np.ndarray:
        """The arm's carrying posture (radians)."""
        if self._carry is None:
            result = self.solve(CARRY_TARGET, 0.0, elbow_up=False)
            assert result.ok, "the carry posture must be reachable"
            self._carry = result.q
        return self._carry
