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

Named profiles of the parametric model live in ``planning/feasibility.yaml``: ``default``
(assumed, the paper's black box) and ``mujoco`` (fitted to measurements in the 3D world by
``benchmarks/calibrate_mujoco.py``). Choose one with ``--feasibility NAME``.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, RootModel

from llm_grop.errors import BadInput
from llm_grop.world.datafile import load_yaml_model
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
        reach_max_m: reach, metres, at which manipulation stops succeeding (``None``: the
            robot's ``reach_max_m``).
    """

    nav_max: float = 0.98
    nav_mid_m: float = 0.02
    nav_scale_m: float = 0.02
    manip_max: float = 0.97
    knee: float = 0.7
    reach_max_m: float | None = None

    def navigation(self, clearance_m: ArrayLike) -> Floats:
        c = np.asarray(clearance_m, dtype=float)
        p = self.nav_max / (1.0 + np.exp(-(c - self.nav_mid_m) / self.nav_scale_m))
        return np.where(c < 0, 0.0, p)

    def manipulation(self, reach_m: ArrayLike, robot: Robot) -> Floats:
        r = np.asarray(reach_m, dtype=float)
        reach = self.reach_max_m or robot.reach_max_m
        knee = self.knee * reach
        t = np.clip((r - knee) / (reach - knee), 0.0, 1.0)
        p = self.manip_max * 0.5 * (1.0 + np.cos(np.pi * t))
        return np.where((r < robot.reach_min_m) | (r >= reach), 0.0, p)


#: The model every planner and the simulator use unless given another.
DEFAULT_FEASIBILITY = ParametricFeasibility()


class _ProfileModel(BaseModel):
    model_config = ConfigDict(extra="forbid")

    description: str = ""
    nav_max: float = Field(gt=0, le=1)
    nav_mid_m: float
    nav_scale_m: float = Field(gt=0)
    manip_max: float = Field(gt=0, le=1)
    knee: float = Field(gt=0, lt=1)
    reach_max_m: float | None = Field(None, gt=0)


class _ProfilesModel(RootModel[dict[str, _ProfileModel]]):
    pass


def _profiles() -> dict[str, _ProfileModel]:
    text = resources.files("llm_grop.planning").joinpath("feasibility.yaml").read_text(
        encoding="utf-8")
    return load_yaml_model(text, "feasibility.yaml", _ProfilesModel, "", "").root


def profile_names() -> list[str]:
    """Names of the packaged feasibility profiles."""
    return sorted(_profiles())


def feasibility_profile(name: str) -> ParametricFeasibility:
    """The packaged profile called ``name``; :class:`BadInput` for an unknown one."""
    profiles = _profiles()
    if name not in profiles:
        raise BadInput(f"--feasibility: unknown profile {name!r}; choose from "
                       f"{', '.join(sorted(profiles))}")
    p = profiles[name]
    return ParametricFeasibility(p.nav_max, p.nav_mid_m, p.nav_scale_m, p.manip_max, p.knee,
                                 p.reach_max_m)
