"""Named success-and-time profiles of the robot's actions, from ``data/feasibility.yaml``.

A profile is numbers only (:class:`Curves`): how often navigation and manipulation succeed
and how long the actions take. The planner
reads one as its belief (``--feasibility NAME``); the 2D simulator reads one as its truth
(``--truth NAME``), so that with the same fitted profile 2D draws what 3D physics does.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, RootModel

from llm_grop.datafile import load_yaml_model
from llm_grop.errors import BadInput
from llm_grop.world.robot import Robot

Floats = NDArray[np.float64]


@dataclass(frozen=True)
class Curves:
    """How often the robot's actions succeed and how long they take (probabilities 0-1,
    metres, seconds); the defaults are the paper's assumed black box.

    Navigation to a goal of clearance ``c`` succeeds with
    ``nav_max * sigmoid((c - nav_mid_m) / nav_scale_m)``, never in collision. A pick at
    reach ``r`` succeeds with ``manip_max`` up to ``knee * reach_max_m``, falling as a
    half cosine to 0 at ``reach_max_m``, never below the robot's minimum reach; a place
    follows the same curve with ``place_max`` on top.

    Attributes:
        nav_max: navigation's success probability with ample clearance.
        nav_mid_m: clearance, metres, at which navigation succeeds half as often.
        nav_scale_m: width of the navigation sigmoid, metres.
        manip_max: a pick's success probability well within reach.
        knee: fraction of the reach beyond which manipulation gets harder.
        reach_max_m: reach, metres, at which manipulation stops succeeding (``None``: the
            robot's ``reach_max_m``).
        pick_time_s, place_time_s: seconds of a pick and a place (``None``: the robot's).
        leg_overhead_s: seconds a drive takes beyond its path at full speed and its turns
            at full turning speed (accelerating, braking, the goal checker).
        failed_attempt_s: what a failed attempt costs with its recovery, seconds; a plan's
            expected duration adds it for every expected retry.
        place_max: a place's ``manip_max`` (``None``: the same as a pick's; after release
            an object can still slide or tip).
        load_time_s, unload_time_s: seconds of one attempt to put an object on the
            robot's tray and to pick it from there (``None``: a place's and a pick's).
    """

    nav_max: float = 0.98
    nav_mid_m: float = 0.02
    nav_scale_m: float = 0.02
    manip_max: float = 0.97
    knee: float = 0.7
    reach_max_m: float | None = None
    pick_time_s: float | None = None
    place_time_s: float | None = None
    leg_overhead_s: float = 0.0
    failed_attempt_s: float = 0.0
    place_max: float | None = None
    load_time_s: float | None = None
    unload_time_s: float | None = None

    def action_time_s(self, action: str, robot: Robot) -> float:
        """Seconds of one ``pick``, ``place``, ``load`` (onto the tray) or ``unload``
        (from it) attempt: the profile's, else (a load) a place's and (an unload) a
        pick's, else the robot's."""
        own = {"pick": self.pick_time_s, "place": self.place_time_s,
               "load": self.load_time_s, "unload": self.unload_time_s}[action]
        if own is not None:
            return float(own)
        if action in ("load", "unload"):
            return self.action_time_s("place" if action == "load" else "pick", robot)
        return float(robot.pick_time_s if action == "pick" else robot.place_time_s)

    def navigation_p(self, clearance_m: ArrayLike) -> Floats:
        """Navigation's success probability at these clearances (metres)."""
        c = np.asarray(clearance_m, dtype=float)
        p = self.nav_max / (1.0 + np.exp(-(c - self.nav_mid_m) / self.nav_scale_m))
        return np.where(c < 0, 0.0, p)

    def reach_m(self, robot: Robot) -> float:
        """Reach, metres, at which manipulation stops succeeding."""
        return self.reach_max_m or robot.reach_max_m

    def manipulation_p(self, reach_m: ArrayLike, robot: Robot, place: bool = False) -> Floats:
        """A pick's (or a ``place``'s) success probability at these reaches (metres)."""
        top = self.place_max if place and self.place_max is not None else self.manip_max
        r = np.asarray(reach_m, dtype=float)
        reach = self.reach_m(robot)
        knee = self.knee * reach
        t = np.clip((r - knee) / (reach - knee), 0.0, 1.0)
        p = top * 0.5 * (1.0 + np.cos(np.pi * t))
        return np.where((r < robot.reach_min_m) | (r >= reach), 0.0, p)


@dataclass(frozen=True)
class Profile:
    """One named profile of the file: its ``name``, where its numbers come from
    (``description``) and its :class:`Curves`."""

    name: str
    description: str
    curves: Curves


class _ProfileModel(BaseModel):
    model_config = ConfigDict(extra="forbid")

    description: str = ""
    nav_max: float = Field(gt=0, le=1)
    nav_mid_m: float
    nav_scale_m: float = Field(gt=0)
    manip_max: float = Field(gt=0, le=1)
    knee: float = Field(gt=0, lt=1)
    reach_max_m: float | None = Field(None, gt=0)
    place_max: float | None = Field(None, gt=0, le=1)
    pick_time_s: float | None = Field(None, ge=0)
    place_time_s: float | None = Field(None, ge=0)
    load_time_s: float | None = Field(None, ge=0)
    unload_time_s: float | None = Field(None, ge=0)
    leg_overhead_s: float = Field(0.0, ge=0)
    failed_attempt_s: float = Field(0.0, ge=0)


class _ProfilesModel(RootModel[dict[str, _ProfileModel]]):
    pass


def _profiles() -> dict[str, _ProfileModel]:
    text = resources.files("llm_grop").joinpath("data/feasibility.yaml").read_text(
        encoding="utf-8")
    return load_yaml_model(text, "feasibility.yaml", _ProfilesModel, "", "").root


def profile_names() -> list[str]:
    """Names of the packaged profiles."""
    return sorted(_profiles())


def load_profile(name: str, param: str = "feasibility") -> Profile:
    """The packaged profile called ``name``; :class:`BadInput` naming the API parameter
    ``param`` for an unknown one."""
    profiles = _profiles()
    if name not in profiles:
        raise BadInput(f"unknown profile {name!r}; choose from "
                       f"{', '.join(sorted(profiles))}", param=param)
    fields = profiles[name].model_dump()
    description = fields.pop("description")
    return Profile(name, description, Curves(**fields))
