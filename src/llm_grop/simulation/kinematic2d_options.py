"""The 2D kinematic simulator's options: its truth (how often actions really succeed) and
its noise, what ``--sim-option`` sets for ``kinematic2d``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pydantic import ConfigDict, SkipValidation

from llm_grop.errors import BadInput
from llm_grop.simulation.outcomes import Outcomes, ParametricOutcomes
from llm_grop.world.plan import Reason


@dataclass(frozen=True)
class Kinematic2DOptions:
    """The simulated world's truth: success probabilities and noise.

    Attributes:
        outcomes: how often navigation, picks and places really succeed.
        truth: a packaged feasibility profile whose curves the outcomes are drawn from
            instead (``mujoco``: what the 3D world was measured to do; ``None``:
            ``outcomes``).
        nav_noise_std_m: standard deviation of the arrival position, per axis, metres.
        heading_noise_std_rad: standard deviation of the arrival heading, radians.
        place_noise_std_m: standard deviation of a placed object's position, metres.
        place_yaw_noise_std_rad: standard deviation of a placed object's yaw, radians.
        stop_fraction: a failed navigation stops this far along its path (uniform range).
        place_failures: how a failed place goes, as ``(reason, weight)`` pairs: a
            ``contact`` before release, or after release the object ``slid``, ``tipped``
            or ``fell``.
        slide_m: how far a sliding object ends from its target (uniform range, metres).
    """

    nav_noise_std_m: float = 0.02
    heading_noise_std_rad: float = 0.03
    place_noise_std_m: float = 0.005
    place_yaw_noise_std_rad: float = 0.02
    stop_fraction: tuple[float, float] = (0.3, 0.9)
    place_failures: tuple[tuple[Reason, float], ...] = (
        ("contact", 0.5), ("slid", 0.35), ("tipped", 0.1), ("fell", 0.05))
    slide_m: tuple[float, float] = (0.04, 0.10)
    outcomes: SkipValidation[Outcomes] = field(default_factory=ParametricOutcomes)
    truth: str | None = None

    # The front doors check a user's options with pydantic (unknown keys refused; the
    # outcomes, an object, are given in Python only).
    __pydantic_config__ = ConfigDict(extra="forbid", arbitrary_types_allowed=True)

    def __post_init__(self) -> None:
        kinds = ("contact", "slid", "tipped", "fell")
        for reason, weight in self.place_failures:
            if reason not in kinds:
                raise BadInput(f"place_failures: {reason!r} is not a way a place fails in 2D; "
                               f"use {', '.join(kinds)}")
            if not (isinstance(weight, int | float) and math.isfinite(weight) and weight >= 0):
                raise BadInput(f"place_failures: the weight of {reason!r} must be a finite "
                               f"number, not negative, got {weight!r}")
        if not sum(w for _, w in self.place_failures) > 0:
            raise BadInput("place_failures: needs at least one positive weight")
