"""What GROP evaluates for every configuration: feasibility, cost and utility (paper §III-C).

An episode's :class:`PlanningContext` is built once: the standing positions around the
target table (``loc``), each object's pickup pose at its supply table, and one cost-to-go
field per pickup pose, so evaluating M configurations never calls a sampling planner.

For capacity 1 the robot's legs are ``start -> pickup(o1) -> stand(o1) -> pickup(o2) ...``.
Object ``j``'s standing position affects only the leg into it and the leg out of it, and
the leg out of it depends only on *where the next object is picked up*. So with

    A[j, s] = w * feas[j, s] - d(pickup_j, s) / v
    edge(j, k) = max_s A[j, s] - d(s, pickup_k) / v

the best standing position for ``j`` given its successor is exact, and choosing the order
is an asymmetric path problem over ``edge`` with precedence (supports first), solved in
:mod:`llm_grop.planning.sequencing`. Utility is in seconds: ``w`` seconds per unit of
success probability (the authors used ``w = 40``) minus the expected duration.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from llm_grop.errors import BadInput, Infeasible
from llm_grop.planning.feasibility import (
    DEFAULT_FEASIBILITY,
    FeasibilityModel,
    action_times,
    placing,
)
from llm_grop.planning.navigation import PATH_TIME_LIMIT_S, NavGraph
from llm_grop.planning.occupancy import build_grid
from llm_grop.planning.standing import (
    blocked_reason,
    candidate_standing_poses,
    pickup_pose,
)
from llm_grop.settings import DEFAULTS
from llm_grop.world.arrangement import Item, Placement
from llm_grop.world.plan import StandingPose
from llm_grop.world.scene import ObjectSource, Scene

Floats = NDArray[np.float64]


@dataclass(frozen=True)
class GropOptions:
    """Settings of the task-motion planner.

    Attributes:
        w: utility weight of feasibility, seconds per unit of success probability.
        spacing_m: spacing of candidate standing positions along the table, metres.
        standoffs_m: distances from the table's edge to the base's footprint, metres.
        grid_resolution_m: cell size of the cost-to-go fields, metres.
        alternatives: fallback standing positions kept per object.
        path_time_limit_s: OMPL's time limit for one navigation path, seconds: a safety
            net only, as a path ends on its iterations (see
            :data:`~llm_grop.planning.navigation.PATH_TIME_LIMIT_S`).
        fidelity_w_s_per_cm: seconds of utility that one centimetre of infidelity costs
            (a configuration's summed gap errors plus its origin's shift; see
            :attr:`~llm_grop.world.fidelity.Fidelity.infidelity_m`). 0 ignores fidelity.
    """

    w: float = DEFAULTS.weight
    spacing_m: float = 0.10
    standoffs_m: tuple[float, ...] = (0.05, 0.10, 0.15, 0.25)
    grid_resolution_m: float = 0.05
    alternatives: int = 3
    path_time_limit_s: float = PATH_TIME_LIMIT_S
    fidelity_w_s_per_cm: float = DEFAULTS.fidelity_weight

    def __post_init__(self) -> None:
        if self.w < 0:
            raise BadInput(f"must not be negative, got {self.w}", param="weight")
        if not self.fidelity_w_s_per_cm >= 0 or self.fidelity_w_s_per_cm == float("inf"):
            raise BadInput(f"must be a finite number >= 0 (seconds per centimetre), got "
                           f"{self.fidelity_w_s_per_cm:g}", param="fidelity_weight")
        if self.spacing_m <= 0 or not self.standoffs_m or min(self.standoffs_m) < 0:
            raise BadInput("planner: spacing_m must be positive and standoffs_m non-negative")


@dataclass(frozen=True)
class Pickup:
    """Where the robot picks ``item`` up: its ``source``, the ``standing`` pose, the pick's
    success probability ``success_p`` (navigation times manipulation) and ``field``, the
    index of its cost-to-go field."""

    item: str
    source: ObjectSource
    standing: StandingPose
    success_p: float
    field: int


class PlanningContext:
    """Everything GROP needs that does not depend on the configuration.

    Attributes:
        scene: the episode's scene; its chairs are the sensed ones.
        items: the requested objects.
        candidates: standing positions around the target table.
        cand_xy: their positions, shape ``(P, 2)``, metres.
        cand_nav_p: navigation success probability of each, shape ``(P,)``.
        cand_gap_m: distance between each two of them, ``(P, P)``, metres.
        pickups: one per item, in item order.
        dist_m: path length from each candidate to each pickup field's source, ``(P, K)``.
        start_dist_m: path length from the robot's start to each pickup, ``(K,)``.
        pickup_dist_m: path length between pickups, ``(K, K)``.
    """

    def __init__(self, scene: Scene, items: Sequence[Item],
                 model: FeasibilityModel = DEFAULT_FEASIBILITY,
                 options: GropOptions | None = None) -> None:
        self.scene, self.items, self.model = scene, tuple(items), model
        self.options = options or GropOptions()
        robot = scene.robot
        self.candidates = candidate_standing_poses(
            scene, scene.target, robot, spacing_m=self.options.spacing_m,
            standoffs_m=self.options.standoffs_m)
        if not self.candidates:
            raise Infeasible(blocked_reason(scene, scene.target, robot))
        self.cand_xy = np.array([[c.pose.x, c.pose.y] for c in self.candidates])
        self.cand_gap_m = np.hypot(self.cand_xy[:, None, 0] - self.cand_xy[None, :, 0],
                                   self.cand_xy[:, None, 1] - self.cand_xy[None, :, 1])
        self.cand_nav_p = np.asarray(
            model.navigation(np.array([c.clearance_m for c in self.candidates])), dtype=float)
        grid = build_grid(scene, resolution_m=self.options.grid_resolution_m)
        self.graph = NavGraph(grid, robot.base_radius_m)
        start = np.array([[scene.robot_start.x, scene.robot_start.y]])
        from_start = self.graph.fields([(scene.robot_start.x, scene.robot_start.y)])[0]
        keys: dict[tuple[float, float], int] = {}
        pickups = []
        around: dict[str, tuple[StandingPose, ...]] = {}
        for item in self.items:
            source = scene.source_for(item.name, item.kind)
            if source is None:
                raise BadInput(f"scene: no start location for {item.name!r}")
            if source.table not in around:
                near = candidate_standing_poses(
                    scene, source.table, robot, spacing_m=self.options.spacing_m,
                    standoffs_m=self.options.standoffs_m)
                xy = np.array([[c.pose.x, c.pose.y] for c in near]).reshape(-1, 2)
                # A stance in a pocket the robot cannot drive into is no stance at all.
                ok = np.isfinite(from_start.cost_at(xy)) if len(near) else np.array([], bool)
                around[source.table] = tuple(c for c, k in zip(near, ok, strict=True) if k)
                if near and not around[source.table]:
                    raise Infeasible(f"no standing position next to table {source.table!r} "
                                     "can be reached from the robot's start")
            stand = pickup_pose(scene, source, robot, model, around[source.table])
            p = float(model.navigation(np.array([stand.clearance_m]))[0]
                      * model.manipulation(np.array([_dist(stand, source)]), robot)[0])
            key = (round(stand.pose.x, 6), round(stand.pose.y, 6))
            pickups.append(Pickup(item.name, source, stand, p, keys.setdefault(key, len(keys))))
        self.pickups = tuple(pickups)
        sources = list(keys)
        fields = self.graph.fields(sources)
        self.dist_m = np.stack([f.cost_at(self.cand_xy) for f in fields], axis=1)
        self.start_dist_m = np.array([f.cost_at(start)[0] for f in fields])
        self.pickup_dist_m = np.stack([f.cost_at(np.array(sources)) for f in fields], axis=1)
        for p in self.pickups:
            if not np.isfinite(self.start_dist_m[p.field]):
                raise Infeasible(f"no collision-free path from the robot's start to the pickup "
                                 f"of {p.item!r} at table {p.source.table!r}")
        if not np.isfinite(self.dist_m).any(axis=1).any():
            raise Infeasible(f"no standing position around table {scene.target!r} can be "
                             "reached from the supply tables")

    @property
    def speed(self) -> float:
        """Navigation speed, metres per second."""
        return self.scene.robot.speed_mps

    def targets_room(self, placements: Sequence[Placement]) -> Floats:
        """Room-frame ``(n, 2)`` positions of ``placements`` (given in item order)."""
        pts = [self.scene.table_to_room(p.x, p.y) for p in placements]
        return np.array([[q.x, q.y] for q in pts])

    def place_manipulation(self, placements: Sequence[Placement]) -> Floats:
        """``(n, P)`` probability that placing object ``j`` from stand ``s`` succeeds."""
        pts = self.targets_room(placements).reshape(-1, 2)
        # reach(self.candidates, pts), from the positions already at hand.
        r = np.hypot(self.cand_xy[:, None, 0] - pts[None, :, 0],
                     self.cand_xy[:, None, 1] - pts[None, :, 1])
        return np.asarray(placing(self.model, r.T, self.scene.robot), dtype=float)

    def place_feasibility(self, placements: Sequence[Placement]) -> Floats:
        """``(n, P)`` probability that object ``j``'s fetch-and-place succeeds from stand ``s``."""
        pick = np.array([p.success_p for p in self.pickups])
        return pick[:, None] * self.cand_nav_p[None, :] * self.place_manipulation(placements)

    def fixed_costs_s(self) -> float:
        """Seconds of manipulation every plan spends: one pick and one place per object."""
        times = action_times(self.model, self.scene.robot)
        return len(self.items) * (times.pick_s + times.place_s)

    def unreachable_reason(self, placements: Sequence[Placement], feas: Floats) -> str | None:
        """Why some object cannot be placed from any standing position, or ``None``."""
        robot = self.scene.robot
        targets = self.targets_room(placements)
        for j, p in enumerate(placements):
            if feas[j].max() <= 0:
                nearest = self.nearest_stand_m(targets[j])
                far = f"the nearest the robot can drive to is {nearest:.2f} m away" \
                    if math.isfinite(nearest) else "the robot can drive to none"
                return (f"no standing position can reach {p.name!r} at table-frame "
                        f"({p.x:+.2f}, {p.y:+.2f}) m: {far} and the arm reaches "
                        f"{robot.reach_max_m:.2f} m")
        return None

    def nearest_stand_m(self, xy: Sequence[float]) -> float:
        """The distance, metres, from the room-frame point ``xy`` to the nearest standing
        position the robot can drive to (``inf``: none)."""
        drivable = self.cand_xy[self.cand_nav_p > 0]
        if not len(drivable):
            return math.inf
        return float(np.min(np.hypot(*(drivable - np.asarray(xy)).T)))


def _dist(stand: StandingPose, source: ObjectSource) -> float:
    """Horizontal distance, metres, from a base pose to an object's start."""
    return float(np.hypot(stand.pose.x - source.x, stand.pose.y - source.y))
