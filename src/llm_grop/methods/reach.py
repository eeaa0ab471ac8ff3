"""What the planner believes the robot can reach, told to the arrangement (issue 41): when
every configuration the LLM's relations allow puts an object where no standing position
reaches it, the feedback loop tells the LLM so before planning fails.

The arrangement sits below planning, so the methods layer, above both, hands it a
:class:`~llm_grop.arrangement.options.Reach` made from the planner's own context.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from llm_grop.planning.utility import PlanningContext
from llm_grop.world.arrangement import Placement


@dataclass(frozen=True)
class PlannerReach:
    """GROP's own test of a configuration, in words: an object that no standing position
    the robot can drive to places with a chance above 0 under the belief of ``ctx``."""

    ctx: PlanningContext

    def __call__(self, placements: Sequence[Placement]) -> tuple[str, str] | None:
        rank = {it.name: k for k, it in enumerate(self.ctx.items)}
        ordered = sorted(placements, key=lambda p: rank[p.name])
        p = self.ctx.cand_nav_p[None, :] * self.ctx.place_manipulation(ordered)
        for j, placement in enumerate(ordered):
            if p[j].max() > 0:
                continue
            (xy,) = self.ctx.targets_room([placement])
            nearest = self.ctx.nearest_stand_m(xy)
            reach_m = self.ctx.scene.robot.reach_max_m
            far = f"the nearest is {nearest:.2f} m from it" if math.isfinite(nearest) \
                else "there is none"
            return placement.name, (f"no place beside the table where the robot can stand is "
                                    f"within its arm's reach of it ({reach_m:.2f} m): {far}")
        return None
