"""The feedback loop's physical part (issue 41): when the executive would give up an object
it still holds (a spot the arm cannot reach, a standing position it cannot drive to), the
LLM is told what failed and why, its revised relations for that object are checked by
clingo, and the object gets another spot on the table, one that keeps them with the
objects already placed and that the belief says the robot can reach.

The executive only calls the :class:`Rescuer` it is given
(:class:`~llm_grop.execution.rescue.Rescue`); the rescuer, above planning and execution,
asks the LLM (:class:`~llm_grop.arrangement.revision.Feedback`) and picks the spot with
the planner's belief (:class:`~llm_grop.planning.utility.PlanningContext`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from llm_grop import seeds
from llm_grop.arrangement import consistency, revision
from llm_grop.arrangement.diners import violations_at_table
from llm_grop.execution.judge import final_placements
from llm_grop.execution.rescue import NewSpot
from llm_grop.planning.feasibility import FeasibilityModel
from llm_grop.planning.utility import GropOptions, PlanningContext
from llm_grop.world.arrangement import Configuration, Item, Placement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ObjectState, Reason, Step
from llm_grop.world.relation import STACKING, Relation
from llm_grop.world.scene import Scene
from llm_grop.world.table import Table

#: Spots drawn on the table for the rescued object, before the relations and the belief
#: choose among them.
DRAWS = 400
#: A new spot lies at least this far, metres, from the one that failed.
AWAY_M = 0.05
#: Standing positions the robot could not drive to are not chosen again when within this
#: distance, metres, of one tried.
TRIED_M = 0.05
#: Navigation reasons: a standing position that failed so is not tried again.
_DRIVE = frozenset({"blocked"})
#: A spot is not chosen from a standing position this much less far from it, metres, than
#: the nearest reach the arm failed at: the belief that planned the failed place was wrong
#: about that reach, and a spot it rates just as well there would fail the same way.
REACH_MARGIN_M = 0.05


@dataclass
class Rescuer:
    """The rescue of one episode: the LLM's loop (``feedback``, its budget shared with the
    arrangement's revisions), the requested ``items``, the ``relations`` planned (updated
    as revisions are taken), the ``targets`` planned (table frame; updated: a new spot
    keeps its relations with the objects on the table and with the targets of those still
    to come, and overlaps none of them), the table, the
    episode's scene, the planner's belief and options, and the random stream its spots are
    drawn from (stage ``rescue``)."""

    feedback: revision.Feedback
    items: tuple[Item, ...]
    relations: list[Relation]
    targets: dict[str, Placement]
    table: Table
    scene: Scene
    belief: FeasibilityModel
    planner: GropOptions
    rng: np.random.Generator
    _ctx: PlanningContext | None = field(default=None, repr=False)

    def __call__(self, name: str, reason: Reason, states: Mapping[str, ObjectState],
                 pose: Pose2D, tried: Sequence[Pose2D]) -> NewSpot | None:
        if self.feedback.left <= 0 or name not in self.targets:
            return None
        old = self.targets[name]
        told = revision.physical_failure(name, reason, old.x, old.y, self.relations,
                                         f"the {self.table.label}")
        revised = self.feedback.revise(self.items, self.relations, told)
        if revised is None:
            return None
        mine = [r for r in revised if name in (r.subject, r.reference)]
        kept = [r for r in self.relations if name not in (r.subject, r.reference)]
        conflict = consistency.check([*kept, *mine]).conflict
        if conflict:
            self.feedback.warnings.append(
                f"the revised relations of the {name} contradict those kept: "
                + "; ".join(r.sentence() for r in conflict))
            return None
        # The others where they lie on the table, else where they are still to go.
        lying = {p.name: p for p in final_placements(states, tuple(self.targets.values()),
                                                     self.scene)}
        others = [lying.get(n, t) for n, t in self.targets.items() if n != name]
        spot = self._spot(old, mine, others, pose, tried if reason in _DRIVE else (),
                          self._failed_reach(old, tried) if reason == "no_ik" else None)
        if spot is None:
            self.feedback.warnings.append(
                f"no spot on the {self.table.label} keeps the revised relations of the "
                f"{name} within the robot's reach; it is given up")
            return None
        self.relations = [*kept, *mine]
        self.targets[name] = spot.target
        return spot

    def context(self, name: str) -> PlanningContext:
        """The planner's view of the room: its standing positions round the target table,
        their chances under the belief and the drives between them (made for ``name`` the
        first time; none of that depends on the object)."""
        if self._ctx is None:
            item = next(it for it in self.items if it.name == name)
            self._ctx = PlanningContext(self.scene, (item,), self.belief, self.planner)
        return self._ctx

    def _failed_reach(self, old: Placement, tried: Sequence[Pose2D]) -> float | None:
        """The nearest of the standing positions ``tried`` to ``old``'s spot, metres: a
        reach the arm failed at (``None``: none was tried)."""
        if not tried:
            return None
        (x, y), = self.context(old.name).targets_room([old]).reshape(-1, 2)
        return min(math.hypot(t.x - x, t.y - y) for t in tried)

    def _spot(self, old: Placement, mine: Sequence[Relation], others: Sequence[Placement],
              pose: Pose2D, tried: Sequence[Pose2D], failed_reach_m: float | None = None
              ) -> NewSpot | None:
        """The best spot for ``old``'s object that keeps ``mine`` with ``others``, by the
        planner's utility: the belief's chance of placing it, less the seconds of driving
        there and of straying from the objects it relates to. When the arm failed to reach
        ``failed_reach_m`` (metres), only a standing position at least
        :data:`REACH_MARGIN_M` nearer to the spot counts."""
        name = old.name
        by_name = {p.name: p for p in others}
        support = next((by_name.get(r.reference or "") for r in mine
                        if r.subject == name and r.relation in STACKING), None)
        if support is not None:
            xy = np.array([[support.x, support.y]])
        else:
            hw, hd = self.table.width / 2, self.table.depth / 2
            xy = np.column_stack([self.rng.uniform(-hw, hw, DRAWS),
                                  self.rng.uniform(-hd, hd, DRAWS)])
            xy = xy[np.hypot(xy[:, 0] - old.x, xy[:, 1] - old.y) >= AWAY_M]
        before = set(violations_at_table(Configuration(tuple(others)), [], self.table))
        spots = []
        for x, y in xy:
            cand = replace(old, x=float(x), y=float(y),
                           on=support.name if support is not None else None)
            config = Configuration((*others, cand))
            if set(violations_at_table(config, mine, self.table)) <= before:
                spots.append(cand)
        if not spots:
            return None
        ctx = self.context(name)
        p = ctx.cand_nav_p[None, :] * ctx.place_manipulation(spots)
        if failed_reach_m is not None:
            pts = ctx.targets_room(spots).reshape(-1, 2)
            reach = np.hypot(pts[:, None, 0] - ctx.cand_xy[None, :, 0],
                             pts[:, None, 1] - ctx.cand_xy[None, :, 1])
            p[reach > failed_reach_m - REACH_MARGIN_M] = 0.0
        if tried:
            near = np.array([[t.x, t.y] for t in tried])
            gone = (np.hypot(ctx.cand_xy[:, None, 0] - near[None, :, 0],
                             ctx.cand_xy[:, None, 1] - near[None, :, 1]) < TRIED_M).any(axis=1)
            p[:, gone] = 0.0
        drive_m = ctx.graph.fields([(pose.x, pose.y)])[0].cost_at(ctx.cand_xy)
        drive_s = np.where(np.isfinite(drive_m), drive_m, np.inf) / ctx.speed
        refs = [by_name[n] for r in mine for n in (r.subject, r.reference)
                if n is not None and n != name and n in by_name]
        stray = np.array([sum(math.hypot(s.x - q.x, s.y - q.y) for q in refs) for s in spots])
        score = self.planner.w * p - drive_s[None, :] \
            - 100 * self.planner.fidelity_w_s_per_cm * stray[:, None]
        k, s = np.unravel_index(int(np.argmax(score)), score.shape)
        if not np.isfinite(score[k, s]) or p[k, s] <= 0:
            return None
        ranked = [int(j) for j in np.argsort(-score[k]) if p[k, j] > 0 and j != s][:2]
        stand = [ctx.candidates[j].pose for j in (int(s), *ranked)]
        leg = Step("navigate", object=name, goal=stand[0], alternatives=tuple(stand[1:]),
                   success_p=float(p[k, s]))
        return NewSpot(spots[int(k)], leg)


def rescuer(feedback: revision.Feedback, items: Sequence[Item], relations: Sequence[Relation],
            targets: Sequence[Placement], table: Table, scene: Scene,
            belief: FeasibilityModel, planner: GropOptions, seed: int) -> Rescuer:
    """The rescue of an episode seeded ``seed``."""
    return Rescuer(feedback, tuple(items), list(relations), {p.name: p for p in targets},
                   table, scene, belief, planner, seeds.stream(seed, "rescue"))
