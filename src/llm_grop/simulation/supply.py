"""Where the requested objects wait before an episode: spots on the supply tables, each
within the arm's sure reach of a free standing position at one of its table's sides (room
frame, metres and radians).

An object gets the spot the scene pins for it, else the top of a pile of its kind that has
room (a catalog kind's ``stack``: plates and bowls), else a random spot in the band along
an open side of a supply table, the objects spread round-robin over the tables; a crowded
table is swept row by row for the first free spot. Every spot, pinned ones included, is
checked for reach before the episode: a robot standing :data:`STANDOFF_M` from the side's
edge must reach it within :func:`sure_reach_m`. When objects do not fit, one
:class:`Infeasible` names each of them and, per supply table, why.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from shapely.geometry import Point, Polygon
from shapely.geometry import box as rect

from llm_grop.errors import Infeasible
from llm_grop.files.jsonio import rounded
from llm_grop.files.profiles import load_profile
from llm_grop.geometry.obstacles import Obstacles
from llm_grop.world.arrangement import Item
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.robot import FINGER_THICKNESS_M, GRIP_CLEARANCE_M, Robot
from llm_grop.world.scene import ObjectSource, Scene, SceneTable

#: Smallest radius of the disc an object occupies on a supply table while it waits, metres;
#: larger objects take the disc round their footprint.
OBJECT_RADIUS_M = 0.06
#: Gap kept between two waiting objects' discs, metres.
OBJECT_GAP_M = 0.01
#: Gap kept between two waiting objects' footprints on a crowded table (see
#: ``_swept_spot``), metres: room for a finger of the open gripper beside an object it
#: grasps (the pad's opening past the object and the finger's thickness), with 5 mm to
#: spare.
FINGER_ROOM_M = GRIP_CLEARANCE_M + FINGER_THICKNESS_M + 0.005
#: Clearance between a waiting object's disc and its table's edge, metres.
EDGE_MARGIN_M = 0.05
#: Waiting objects lie at most this far, metres, from a table edge the robot can stand at,
#: so that the arm reaches them comfortably.
EDGE_BAND_M = 0.20
#: Gap, metres, between a supply table's edge and the base's footprint where the robot
#: stands to pick (the planner's nearest stand-off).
STANDOFF_M = 0.05
#: Step, metres, between the standing positions tried along a side.
STANCE_STEP_M = 0.02
#: Chairs at a round table stand within this angle, radians, either side of its ±y axis;
#: objects on a round supply table lie within it of the open side's direction.
ROUND_ARC_RAD = math.pi / 4
#: Step, metres, of the sweep along a crowded supply table's edge (see ``_swept_spot``).
SWEEP_STEP_M = 0.01
#: Random draws per object and table before the sweep.
TRIES = 200
#: Compass names of the room's directions, counter-clockwise from +x.
_COMPASS = ("east", "north", "west", "south")


def sure_reach_m(robot: Robot) -> float:
    """Farthest reach, metres from the base's centre, at which a pick is as sure as it
    gets: the knee of the default feasibility profile (0.7 of ``robot.reach_max_m``,
    0.595 m for the default robot), the curve the 2D simulator draws from."""
    return load_profile("default").curves.knee * robot.reach_max_m


@dataclass(frozen=True)
class Side:
    """An open side of a supply table: ``(du, dv)`` its outward direction in the table's
    own frame, ``name`` the room's compass direction it faces (``"south"``: the robot
    approaches from the south), and ``stances`` the free base centres ``(N, 2)`` along it,
    :data:`STANDOFF_M` from its edge, from which the robot picks."""

    du: int
    dv: int
    name: str
    stances: np.ndarray


@dataclass(frozen=True)
class Spot:
    """Where one object waits (:class:`ObjectSource`) and where the robot stands to pick
    it: ``approach``, a base pose facing the spot, at the ``side`` named (``None`` and
    ``""`` for a pinned spot out of reach)."""

    source: ObjectSource
    side: str
    approach: Pose2D | None


class Supply:
    """The supply tables of ``scene`` as the objects of one episode fill them.

    ``taken`` holds each waiting object's ``(x, y, disc radius, half x, half y)``.
    """

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.robot = scene.robot
        self.reach_m = sure_reach_m(scene.robot)
        self.obstacles = Obstacles(scene, include_chairs=True)
        self.sides = {t.name: self._sides(t) for t in scene.supply_tables}
        self.taken: list[tuple[float, float, float, float, float]] = []

    # -- reach ----------------------------------------------------------------------
    def _sides(self, table: SceneTable) -> tuple[Side, ...]:
        """The sides of ``table`` in front of whose middle the base fits (so the random
        draws see the same sides as ever), with their free standing positions."""
        box = table.box
        radius = self.robot.base_radius_m
        blocked = [Polygon(b.outline()) for b in self.scene.static_obstacles()]
        room = rect(0.0, 0.0, self.scene.width, self.scene.depth)
        out = []
        for du, dv in ((0, -1), (0, 1), (-1, 0), (1, 0)):
            gap = 0.1 + radius
            x, y = box.to_room(du * (box.width / 2 + gap), dv * (box.depth / 2 + gap))
            base = Point(x, y).buffer(radius)
            if room.contains(base) and not any(base.intersects(p) for p in blocked):
                out.append(Side(du, dv, _compass(box.yaw + math.atan2(dv, du)),
                                self._stances(table, du, dv)))
        return tuple(out)

    def _stances(self, table: SceneTable, du: int, dv: int) -> np.ndarray:
        """Free base centres along side ``(du, dv)`` of ``table``, :data:`STANDOFF_M`
        from its edge (round a round top: on the arc facing that way)."""
        box = table.box
        gap = STANDOFF_M + self.robot.base_radius_m
        if table.is_round:
            r = box.width / 2 + gap
            n = max(2, math.ceil(2 * ROUND_ARC_RAD * r / STANCE_STEP_M) + 1)
            phi = math.atan2(dv, du) + np.linspace(-ROUND_ARC_RAD, ROUND_ARC_RAD, n)
            local = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
        else:
            half = box.depth / 2 if du else box.width / 2
            n = max(2, math.ceil(2 * half / STANCE_STEP_M) + 1)
            t = np.linspace(-half, half, n)
            across = np.full(n, (box.width / 2 if du else box.depth / 2) + gap)
            local = np.stack([du * across, t] if du else [t, dv * across], axis=1)
        pts = np.array([box.to_room(u, v) for u, v in local], dtype=float).reshape(-1, 2)
        free = [self.obstacles.free(x, y, self.robot.base_radius_m) for x, y in pts]
        return pts[np.array(free, dtype=bool)].reshape(-1, 2)

    def approach(self, table: str, x: float, y: float) -> tuple[Side, Pose2D] | None:
        """The nearest free standing position at ``table``'s open sides from which the arm
        reaches room point ``(x, y)`` surely, as its side and a pose facing the point;
        ``None`` when none does."""
        best: tuple[float, Side, np.ndarray] | None = None
        for side in self.sides.get(table, ()):
            if not len(side.stances):
                continue
            d = np.hypot(side.stances[:, 0] - x, side.stances[:, 1] - y)
            k = int(np.argmin(d))
            if best is None or d[k] < best[0]:
                best = (float(d[k]), side, side.stances[k])
        if best is None or not self.robot.reach_min_m <= best[0] <= self.reach_m + 1e-9:
            return None
        _, side, (sx, sy) = best
        return side, Pose2D(float(sx), float(sy), math.atan2(y - sy, x - sx))

    # -- spots ----------------------------------------------------------------------
    def clear(self, x: float, y: float, radius: float) -> bool:
        """Whether a disc of ``radius`` metres at ``(x, y)`` keeps its gap to every
        waiting object's disc."""
        return all(math.hypot(x - tx, y - ty) >= radius + tr + OBJECT_GAP_M
                   for tx, ty, tr, _, _ in self.taken)

    def free_spot(self, table: SceneTable, radius: float, rng: np.random.Generator,
                  half: tuple[float, float]) -> tuple[float, float, Side, Pose2D] | None:
        """A random room-frame point on ``table``, within :data:`EDGE_BAND_M` of an open
        side, whose object disc (``radius`` metres) is clear of the edge and of the waiting
        discs, and that the arm reaches surely; ``None`` when none turns up.

        When random draws find no room, the table is swept for the first spot where the
        object's footprint (half sides ``half``, unturned in the room) keeps
        :data:`FINGER_ROOM_M` from every waiting footprint: a fork stood across a counter's
        edge takes a few centimetres of it, not the disc round it."""
        box = table.box
        inset = EDGE_MARGIN_M + radius
        hw, hd = box.width / 2 - inset, box.depth / 2 - inset
        sides = self.sides.get(table.name, ())
        if hw < 0 or hd < 0 or not sides:
            return None
        for _ in range(TRIES):
            side = sides[int(rng.integers(len(sides)))]
            du, dv = side.du, side.dv
            u, v = rng.uniform(-hw, hw), rng.uniform(-hd, hd)
            if table.is_round:
                # On the arc facing the open side, its edge gap between the inset and the band.
                phi = math.atan2(dv, du) + rng.uniform(-ROUND_ARC_RAD, ROUND_ARC_RAD)
                reach = box.width / 2 - rng.uniform(inset, max(inset, EDGE_BAND_M))
                u, v = reach * math.cos(phi), reach * math.sin(phi)
            # Pull the point towards the chosen open side, into the band along it.
            elif du:
                u = du * (box.width / 2 - min(box.width / 2 - u * du, EDGE_BAND_M))
                u = float(np.clip(u, -hw, hw))
            else:
                v = dv * (box.depth / 2 - min(box.depth / 2 - v * dv, EDGE_BAND_M))
                v = float(np.clip(v, -hd, hd))
            x, y = (rounded(c) for c in box.to_room(u, v))
            if self.clear(x, y, radius):
                found = self.approach(table.name, x, y)
                if found is not None:
                    return (x, y, *found)
        if table.is_round or box.yaw != 0.0:
            return None
        return self._swept_spot(table, half)

    def _swept_spot(self, table: SceneTable, half: tuple[float, float]
                    ) -> tuple[float, float, Side, Pose2D] | None:
        """A crowded table (several diners' tableware): each open side's band swept in
        :data:`SWEEP_STEP_M` steps, the row along the edge first, then rows further in
        while the arm reaches them, for the first free spot, so the tables fill up."""
        box = table.box
        bw = box.width / 2 - EDGE_MARGIN_M - half[0]
        bd = box.depth / 2 - EDGE_MARGIN_M - half[1]
        if bw < 0 or bd < 0:
            return None
        for side in self.sides.get(table.name, ()):
            du, dv = side.du, side.dv
            # Rows go in while a robot standing straight in front still reaches them.
            stand_m = STANDOFF_M + self.robot.base_radius_m
            deep = min(2 * (bw if du else bd),
                       max(0.0, self.reach_m - stand_m - EDGE_MARGIN_M
                           - (half[0] if du else half[1])))
            along = np.arange(-(bd if du else bw), (bd if du else bw) + 1e-9, SWEEP_STEP_M)
            for d in np.arange(0.0, deep + 1e-9, SWEEP_STEP_M):
                for t in along:
                    u = du * (bw - d) if du else float(t)
                    v = dv * (bd - d) if dv else float(t)
                    x, y = (rounded(c) for c in box.to_room(u, v))
                    if all(abs(x - tx) >= half[0] + hx + FINGER_ROOM_M
                           or abs(y - ty) >= half[1] + hy + FINGER_ROOM_M
                           for tx, ty, _, hx, hy in self.taken):
                        found = self.approach(table.name, x, y)
                        if found is not None:
                            return (x, y, *found)
        return None

    def why_not(self, table: SceneTable, radius: float) -> str:
        """Why no spot on ``table`` takes an object whose disc has ``radius`` metres: its
        open sides' compass names, comma-separated, when only the reach is to blame."""
        sides = self.sides.get(table.name, ())
        if min(table.box.width, table.box.depth) / 2 < EDGE_MARGIN_M + radius:
            return f"{table.name!r} is too small for it"
        if not sides:
            return (f"{table.name!r} has no side where the base (radius "
                    f"{self.robot.base_radius_m:g} m) fits")
        return ", ".join(s.name for s in sides)


def supply_layout(scene: Scene, items: Sequence[Item], rng: np.random.Generator
                  ) -> tuple[Spot, ...]:
    """Where each of ``items`` waits on ``scene``'s supply tables (see the module's
    docstring), one :class:`Spot` per item in order; spots are drawn from ``rng``.

    Raises :class:`Infeasible`, one line naming every object that does not fit or that the
    arm cannot reach and why, when any does not.
    """
    supply = Supply(scene)
    tables = scene.supply_tables
    radius = {i.name: _radius(i) for i in items}
    half = {i.name: (i.spec.size[0] / 2, i.spec.size[1] / 2) for i in items}
    stack = {i.name: i.spec.stack for i in items}
    kind = {i.name: i.kind for i in items}
    spots: dict[str, Spot] = {}
    unreachable: list[str] = []
    # Piles by kind: the names in each, bottom first.
    piles: dict[str, list[list[str]]] = {}
    used: set[ObjectSource] = set()
    for item in items:
        s = scene.source_for(item.name, item.kind)
        if s is None or s in used:
            continue
        used.add(s)
        on = s.on if s.on in spots else None
        src = ObjectSource(item.name, s.table, s.x, s.y, on)
        supply.taken.append((s.x, s.y, radius[item.name], *half[item.name]))
        found = supply.approach(s.table, s.x, s.y)
        if found is None:
            unreachable.append(item.name)
        spots[item.name] = Spot(src, found[0].name, found[1]) if found is not None \
            else Spot(src, "", None)
        pile = next((p for p in piles.get(item.kind, []) if on is not None and p[-1] == on),
                    None)
        if pile is not None:
            pile.append(item.name)
        else:
            piles.setdefault(item.kind, []).append([item.name])
    missing: list[str] = []
    turn = 0
    for item in items:
        if item.name in spots:
            continue
        pile = next((p for p in piles.get(item.kind, []) if len(p) < stack[item.name]), None)
        if pile is not None:
            below = spots[pile[-1]]
            src = below.source
            spots[item.name] = Spot(ObjectSource(item.name, src.table, src.x, src.y,
                                                 pile[-1]), below.side, below.approach)
            pile.append(item.name)
            continue
        if not tables:
            raise Infeasible(f"no supply table for {item.name!r}: the scene has no table "
                             "besides the target")
        for j in range(len(tables)):
            table = tables[(turn + j) % len(tables)]
            found = supply.free_spot(table, radius[item.name], rng, half[item.name])
            if found is not None:
                break
        else:
            missing.append(item.name)
            continue
        turn += 1
        x, y, side, pose = found
        supply.taken.append((x, y, radius[item.name], *half[item.name]))
        spots[item.name] = Spot(ObjectSource(item.name, table.name, x, y), side.name, pose)
        piles.setdefault(item.kind, []).append([item.name])
    if missing or unreachable:
        raise Infeasible(_report(supply, items, missing, unreachable, radius, kind))
    return tuple(spots[i.name] for i in items)


def _report(supply: Supply, items: Sequence[Item], missing: Sequence[str],
            unreachable: Sequence[str], radius: dict[str, float], kind: dict[str, str]
            ) -> str:
    """One line: how many objects the supply tables hold, and which do not and why."""
    scene = supply.scene
    reach = f"the arm's sure reach ({supply.reach_m:.3g} m)"
    held = len(items) - len(missing) - len(unreachable)
    parts = []
    # Objects of one kind fail for the same reasons: say them once per kind.
    by_kind: dict[str, list[str]] = {}
    for name in missing:
        by_kind.setdefault(kind[name], []).append(name)
    for names in by_kind.values():
        reasons, sides = [], []
        for t in scene.supply_tables:
            why = supply.why_not(t, radius[names[0]])
            if why.startswith(repr(t.name)):
                reasons.append(why)
            else:
                sides.append(f"{t.name!r} ({why})")
        if sides:
            reasons.insert(0, f"no free spot within {reach} of the open sides of "
                              f"{', '.join(sides)}")
        verb = "does" if len(names) == 1 else "do"
        parts.append(f"{', '.join(map(repr, names))} {verb} not fit: {'; '.join(reasons)}")
    for name in unreachable:
        s = scene.source_for(name, kind[name])
        assert s is not None
        parts.append(f"{name!r} starts at ({s.x:g}, {s.y:g}) on {s.table!r}, beyond {reach} "
                     "of every free standing position at its open sides")
    return (f"the supply tables hold {held} of the {len(items)} objects: "
            + "; ".join(parts))


def _radius(item: Item) -> float:
    """Radius, metres, of the disc round ``item``'s footprint (at least
    :data:`OBJECT_RADIUS_M`)."""
    sx, sy = item.spec.size
    r = sx / 2 if item.spec.shape == "circle" else math.hypot(sx, sy) / 2
    return max(OBJECT_RADIUS_M, r)


def _compass(angle_rad: float) -> str:
    """The compass name of the room direction ``angle_rad`` (counter-clockwise from +x,
    the room's east)."""
    return _COMPASS[round(angle_rad / (math.pi / 2)) % 4]

