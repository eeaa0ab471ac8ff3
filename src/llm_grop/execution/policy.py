"""The executive's policy: attempt counts and the tolerances of a successful place."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from llm_grop.errors import BadInput
from llm_grop.settings import DEFAULTS
from llm_grop.world.arrangement import UPRIGHT_TILT_RAD

#: Attempts per navigation goal, as in the authors' experiment.
NAV_ATTEMPTS = DEFAULTS.nav_attempts
#: Attempts per pick and per place for LLM-GROP, as in the authors' experiment.
LLM_GROP_MANIP_ATTEMPTS = 20
#: Attempts per pick and per place for the baselines, as in the authors' experiment.
BASELINE_MANIP_ATTEMPTS = 10


@dataclass(frozen=True)
class ExecutionPolicy:
    """How the executive runs a plan.

    Attributes:
        nav_attempts: attempts per navigation goal before the next fallback goal.
        manip_attempts: attempts per pick and per place of one object, re-grasps and
            re-places included; ``None``: the method's own count
            (:data:`LLM_GROP_MANIP_ATTEMPTS` or :data:`BASELINE_MANIP_ATTEMPTS`).
        max_tilt_rad: largest tilt of a placed object's up axis from the vertical,
            radians.
        max_offset_m: largest horizontal distance of a placed object from its target,
            metres.
        rest_m: largest height of an object's base above its support's top, metres
            (an object leaning on something is not resting on the table).
    """

    nav_attempts: int = NAV_ATTEMPTS
    manip_attempts: int | None = None
    max_tilt_rad: float = UPRIGHT_TILT_RAD
    max_offset_m: float = 0.03
    rest_m: float = 0.015

    def __post_init__(self) -> None:
        for name in ("nav_attempts", "manip_attempts"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int)
                                      or value < 1):
                raise BadInput(f"{name}: must be a whole number of at least 1, got {value!r}")
        for name in ("max_tilt_rad", "max_offset_m", "rest_m"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not math.isfinite(value) or value < 0:
                raise BadInput(f"{name}: must be a finite number, not negative, got {value!r}")

    def for_method(self, manip_attempts: int) -> ExecutionPolicy:
        """This policy with ``manip_attempts`` filled in when it was left to the method."""
        if self.manip_attempts is not None:
            return self
        return replace(self, manip_attempts=manip_attempts)
