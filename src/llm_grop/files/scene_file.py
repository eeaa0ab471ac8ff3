"""Dining-room scene files (YAML) and their JSON form; errors name the file and the field.

The file's layout (room frame: metres and radians, the room spans ``[0, width] x
[0, depth]``)::

    name: dining room
    room: {width: 8.0, depth: 6.0}
    walls: [{center: [x, y], size: [w, d], yaw: 0.0}]
    tables: [{name: dining table, center: [x, y], size: [w, d], yaw: 0.0, height: 0.75},
             {name: round table, shape: circle, center: [x, y], diameter: 1.2}]  # or size: [d, d]
    target: dining table
    source_tables: [kitchen counter]                      # optional
    sources: [{object: mug, table: kitchen counter, position: [x, y]},   # optional
              {object: dinner plate 2, table: ..., position: [x, y], rests_on: dinner plate}]
    chairs: [{center: [x, y], size: [w, d], yaw: 0.0}]    # optional, "chair 1", ...
    chair_band_m: [0.0, 1.0]                              # optional
    robot: {start: [x, y, theta], base_radius_m: 0.3, ...}  # all optional
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import fields
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

import shapely
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    FiniteFloat,
    NonNegativeFloat,
    PositiveFloat,
    StrictInt,
    StringConstraints,
)
from shapely.geometry import Point, Polygon
from shapely.geometry import box as rect

from llm_grop.datafile import load_yaml_model, unknown_key
from llm_grop.errors import BadInput
from llm_grop.files.jsonio import rounded
from llm_grop.world.geometry2d import Box, Disc, Pose2D
from llm_grop.world.robot import Robot
from llm_grop.world.scene import Chair, ObjectSource, Scene, SceneTable
from llm_grop.world.seat import Seat
from llm_grop.world.table import Table

#: Overlaps shallower than this (metres) are ignored, so that touching shapes and
#: values rounded to 0.1 mm in JSON still load.
#: Closest two pinned object starts may be, centre to centre, metres.
_SOURCE_GAP_M = 0.05
_TOL_M = 1e-3
#: How far a round table's two sizes may differ, metres (JSON rounds to 0.1 mm).
_ROUND_TOL_M = 1e-6

_Name = Annotated[str, StringConstraints(strip_whitespace=True, min_length=1)]
_XY = tuple[FiniteFloat, FiniteFloat]
_Size = tuple[PositiveFloat, PositiveFloat]


class _SceneModel(BaseModel):
    """A part of a scene. It keeps keys it does not know, so a run JSON a later version wrote
    still reads; in a scene file they are typos, and :func:`parse_scene` refuses them."""

    model_config = ConfigDict(extra="allow")


#: The largest room side, metres: a dining room, and a bound on the planner's grids.
MAX_ROOM_SIDE_M = 100.0


class RoomEntry(_SceneModel):
    width: Annotated[PositiveFloat, Field(le=MAX_ROOM_SIDE_M)]
    depth: Annotated[PositiveFloat, Field(le=MAX_ROOM_SIDE_M)]


class WallEntry(_SceneModel):
    center: _XY
    size: _Size
    yaw: FiniteFloat = 0.0


class TableEntry(_SceneModel):
    """A table: a rectangle ``size: [w, d]``, or ``shape: circle`` with ``size: [d, d]``
    or ``diameter: d`` (metres)."""

    name: _Name
    center: _XY
    size: _Size | None = None
    shape: Literal["rectangle", "circle"] = "rectangle"
    diameter: PositiveFloat | None = None
    yaw: FiniteFloat = 0.0
    height: PositiveFloat = 0.75


class ChairEntry(WallEntry):
    name: _Name | None = None


class SourceEntry(_SceneModel):
    """Where an object starts; ``rests_on`` names the source it rests on in a pile (same
    table, same position). Not ``on``: YAML reads a bare ``on`` key as ``true``."""

    object: _Name
    table: _Name
    position: _XY
    rests_on: _Name | None = None


class RobotEntry(_SceneModel):
    start: tuple[FiniteFloat, FiniteFloat, FiniteFloat] = (0.5, 0.5, 0.0)
    base_radius_m: FiniteFloat | None = None
    reach_min_m: FiniteFloat | None = None
    reach_max_m: FiniteFloat | None = None
    speed_mps: FiniteFloat | None = None
    turn_speed_radps: FiniteFloat | None = None
    pick_time_s: FiniteFloat | None = None
    place_time_s: FiniteFloat | None = None
    ik_failure_s: FiniteFloat | None = None
    capacity: StrictInt | None = None


class SceneFile(_SceneModel):
    """A scene file (and the run JSON's ``scene``), before its geometry is checked."""

    name: _Name | None = None
    room: RoomEntry
    walls: list[WallEntry] = []
    tables: list[TableEntry]
    target: _Name
    source_tables: list[_Name] = []
    sources: list[SourceEntry] = []
    chairs: list[ChairEntry] | None = None
    chair_band_m: tuple[NonNegativeFloat, NonNegativeFloat] = (0.0, 1.0)
    robot: RobotEntry = Field(default_factory=RobotEntry)
    diners: list[tuple[FiniteFloat, FiniteFloat, FiniteFloat]] | None = None


def parse_scene(text: str, where: str) -> Scene:
    """The scene in YAML ``text``; ``where`` names its file in errors.

    Raises :class:`BadInput` with one line ``<where>: <field path>: <reason>``.
    """
    m = load_yaml_model(text, where, SceneFile, "tables", "name")
    typo = _unknown_key(m)
    if typo is not None:
        path, why = typo
        raise BadInput(f"{where}: {path}: {why}")

    def fail(path: str, reason: str) -> BadInput:
        return BadInput(f"{where}: {path}: {reason}")

    if not m.tables:
        raise fail("tables", "no tables; list at least the target table")
    names = [t.name for t in m.tables]
    listed = ", ".join(_plain(n) for n in names)
    for k, name in enumerate(names):
        if name in names[:k]:
            raise fail(f"tables[{k}] ({name!r}).name", f"table {name!r} is listed twice")
    if m.target not in names:
        raise fail("target", f"no table named {m.target!r} (tables: {listed})")
    for k, name in enumerate(m.source_tables):
        if name not in names:
            raise fail(f"source_tables[{k}]", f"no table named {name!r} (tables: {listed})")
        if name == m.target:
            raise fail(f"source_tables[{k}]", f"{name!r} is the target table, not a supply table")
        if name in m.source_tables[:k]:
            raise fail(f"source_tables[{k}]", f"{name!r} is listed twice")
    lo, hi = m.chair_band_m
    if lo > hi:
        raise fail("chair_band_m", f"lower bound {lo} exceeds upper bound {hi}")

    room = rect(0.0, 0.0, m.room.width, m.room.depth)
    size = f"{m.room.width:g} x {m.room.depth:g} m"
    walls = tuple(_box(w) for w in m.walls)
    wall_polys = [_poly(b) for b in walls]
    tables = tuple(_table(t, f"tables[{k}] ({t.name!r})", fail) for k, t in enumerate(m.tables))
    table_polys = [_poly(t.footprint) for t in tables]
    for k, poly in enumerate(table_polys):
        path = f"tables[{k}] ({names[k]!r})"
        if not _inside(poly, room):
            raise fail(path, f"extends outside the room ({size})")
        for j in range(k):
            if _overlap(poly, table_polys[j]):
                raise fail(path, f"overlaps table {names[j]!r}")
        for j, wall in enumerate(wall_polys):
            if _overlap(poly, wall):
                raise fail(path, f"overlaps wall {j + 1}")

    chairs = tuple(Chair(c.name or f"chair {k + 1}", _box(c))
                   for k, c in enumerate(m.chairs or []))
    for k, chair in enumerate(chairs):
        path, poly = f"chairs[{k}] ({chair.name!r})", _poly(chair.box)
        if not _inside(poly, room):
            raise fail(path, f"extends outside the room ({size})")
        for name, other in zip(names, table_polys, strict=True):
            if _overlap(poly, other):
                raise fail(path, f"overlaps table {name!r}")
        for j, wall in enumerate(wall_polys):
            if _overlap(poly, wall):
                raise fail(path, f"overlaps wall {j + 1}")

    sources = tuple(ObjectSource(s.object, s.table, *s.position, s.rests_on)
                    for s in m.sources)
    for k, s in enumerate(sources):
        path = f"sources[{k}] ({s.object!r})"
        if s.table not in names:
            raise fail(f"{path}.table", f"no table named {s.table!r} (tables: {listed})")
        if s.table == m.target:
            raise fail(f"{path}.table", f"{s.table!r} is the target table, not a supply table")
        at = f"({s.x:g}, {s.y:g})"
        if not (0.0 <= s.x <= m.room.width and 0.0 <= s.y <= m.room.depth):
            raise fail(f"{path}.position", f"{at} is outside the room ({size})")
        for j, wall in enumerate(walls):
            if wall.contains(s.x, s.y):
                raise fail(f"{path}.position", f"inside wall {j + 1}")
        if not tables[names.index(s.table)].contains(s.x, s.y, _TOL_M):
            raise fail(f"{path}.position", f"{at} is not on the top of table {s.table!r}")
        below = [j for j, other in enumerate(sources[:k]) if other.object == s.on]
        if s.on is not None:
            if not below:
                raise fail(f"{path}.rests_on", f"no earlier source is {s.on!r}; list what "
                           "a pile rests on before it")
            under = sources[below[0]]
            if (under.table, under.x, under.y) != (s.table, s.x, s.y):
                raise fail(f"{path}.rests_on", f"{s.on!r} starts at ({under.x:g}, "
                           f"{under.y:g}) on {under.table!r}; an object on it starts at the "
                           "same spot")
            if any(other.on == s.on for other in sources[:k]):
                raise fail(f"{path}.rests_on", f"another source already rests on {s.on!r}")
        for j, other in enumerate(sources[:k]):
            if s.object == other.object:
                raise fail(f"{path}.object", f"listed twice (sources[{j}])")
            # A pile's objects share its bottom one's spot.
            if s.on is not None and (s.table, s.x, s.y) == (other.table, other.x, other.y):
                continue
            if math.hypot(s.x - other.x, s.y - other.y) < _SOURCE_GAP_M:
                raise fail(f"{path}.position", f"{at} is where sources[{j}] "
                           f"({other.object!r}) starts; keep {100 * _SOURCE_GAP_M:g} cm apart")

    params = {k: v for k, v in m.robot.model_dump().items() if k != "start" and v is not None}
    try:
        robot = Robot(**params)
    except BadInput as exc:
        raise BadInput(f"{where}: {exc}") from None
    start = Pose2D(*m.robot.start)
    reason = _start_blocked(start, robot.base_radius_m, room, walls, tables, chairs)
    if reason:
        raise fail("robot.start", reason)

    scene = Scene(
        name=m.name or "dining room", width=m.room.width, depth=m.room.depth,
        tables=tables, target=m.target, robot_start=start, walls=walls,
        source_tables=tuple(m.source_tables), sources=sources, chairs=chairs, robot=robot,
        chair_band_m=(lo, hi), chairs_listed=m.chairs is not None,
        diners=tuple(Seat(*d) for d in m.diners or ()))
    try:
        scene.target_top  # noqa: B018 - a seat inside the target table is refused here
    except BadInput as exc:
        raise fail("diners", str(exc).removeprefix("table: ")) from None
    return scene


def set_target_top(scene: Scene, top: Table, *, keep_chairs: bool = True) -> Scene:
    """``scene`` with its target table's top replaced by ``top`` (``--table``): same
    centre, yaw and height, ``top``'s size and shape.

    Raises :class:`BadInput` (one line naming the ``table`` parameter and what it hits) when the new
    top leaves the room or overlaps a wall, another table, the robot's start or, with
    ``keep_chairs``, one of the scene's chairs.
    """
    out = scene.with_target_top(top)
    target = out.target_table
    poly = _poly(target.footprint)
    what = f"a {top.label} as {target.name!r}"

    def refused(why: str) -> BadInput:
        return BadInput(f"{what} {why}", param="table", mentions=("chairs",))

    if not _inside(poly, rect(0.0, 0.0, scene.width, scene.depth)):
        raise refused(f"extends outside the room ({scene.width:g} x {scene.depth:g} m)")
    for t in out.tables:
        if t.name != target.name and _overlap(poly, _poly(t.footprint)):
            raise refused(f"overlaps table {t.name!r}")
    for j, wall in enumerate(out.walls):
        if _overlap(poly, _poly(wall)):
            raise refused(f"overlaps wall {j + 1}")
    for c in out.chairs if keep_chairs else ():
        if _overlap(poly, _poly(c.box)):
            raise refused(f"overlaps {_plain(c.name)}; sample the chairs instead (chairs=N)")
    start = out.robot_start
    if _overlap(Point(start.x, start.y).buffer(out.robot.base_radius_m), poly):
        raise refused(f"covers the robot's start ({start.x:g}, {start.y:g})")
    return out


def load_scene(path: str | os.PathLike[str] | None = None) -> Scene:
    """The scene in YAML file ``path``, or the packaged dining room when ``None``.

    Raises :class:`BadInput` for a file that cannot be read or is malformed.
    """
    if path is None:
        packaged = resources.files("llm_grop").joinpath("data/scenes/dining_room.yaml")
        return parse_scene(packaged.read_text(encoding="utf-8"), "packaged dining_room.yaml")
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise BadInput(f"scene: cannot read {str(path)!r}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise BadInput(f"scene: cannot read {str(path)!r}: not UTF-8 text") from None
    return parse_scene(text, str(path))


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """``scene`` as a JSON-ready dict in the scene file's layout (metres and radians
    rounded to 0.1 mm / 0.1 mrad); :func:`parse_scene` reads it back."""
    def box(b: Box) -> dict[str, Any]:
        return {"center": [rounded(b.x), rounded(b.y)],
                "size": [rounded(b.width), rounded(b.depth)], "yaw": rounded(b.yaw)}

    chairs = []
    for k, c in enumerate(scene.chairs):
        # The file names chairs "chair 1", ... itself; other names must be kept.
        named = {} if c.name == f"chair {k + 1}" else {"name": c.name}
        chairs.append(named | box(c.box))
    robot: dict[str, Any] = {"start": [rounded(v) for v in scene.robot_start.as_list()]}
    for f in fields(Robot):
        value = getattr(scene.robot, f.name)
        robot[f.name] = value if isinstance(value, int) else rounded(value)
    out: dict[str, Any] = {
        "name": scene.name,
        "room": {"width": rounded(scene.width), "depth": rounded(scene.depth)},
        "walls": [box(w) for w in scene.walls],
        # A round table says so; rectangles are written as before.
        "tables": [{"name": t.name} | box(t.box) | {"height": rounded(t.height)}
                   | ({"shape": t.shape} if t.is_round else {}) for t in scene.tables],
        "target": scene.target,
        "source_tables": list(scene.source_tables),
        # A pile's upper objects say what they rest on; others are written as before.
        "sources": [{"object": s.object, "table": s.table,
                     "position": [rounded(s.x), rounded(s.y)]}
                    | ({"rests_on": s.on} if s.on is not None else {}) for s in scene.sources],
        "chairs": chairs,
        "chair_band_m": [rounded(v) for v in scene.chair_band_m],
        "robot": robot,
    }
    if not (scene.chairs_listed or scene.chairs):
        del out["chairs"]
    if scene.diners:
        out["diners"] = [[rounded(v) for v in d.as_list()] for d in scene.diners]
    return out


def _unknown_key(m: BaseModel, path: str = "") -> tuple[str, str] | None:
    """The path of the first key in ``m`` that the scene layout does not know and why it is
    refused (with the closest known key), or ``None``."""
    for key in m.model_extra or {}:
        return f"{path}{_plain(str(key))}", unknown_key(str(key), list(type(m).model_fields))
    for field in type(m).model_fields:
        value = getattr(m, field)
        entries = enumerate(value) if isinstance(value, list) else [(None, value)]
        for i, entry in entries:
            if isinstance(entry, BaseModel):
                label = "" if i is None else f"[{i}]" + (
                    f" ({entry.name!r})" if getattr(entry, "name", None) else "")
                found = _unknown_key(entry, f"{path}{field}{label}.")
                if found is not None:
                    return found
    return None


def _plain(text: str) -> str:
    """``text`` as it is when printable, else quoted, so that an error stays on one line
    (a name from the file may hold a line break)."""
    return text if text.isprintable() else repr(text)


def _box(m: WallEntry) -> Box:
    return Box(m.center[0], m.center[1], m.size[0], m.size[1], m.yaw)


def _table(t: TableEntry, path: str, fail: Callable[[str, str], BadInput]) -> SceneTable:
    """The table of entry ``t`` (at ``path`` in the file); a round one's size comes from
    ``size: [d, d]`` or ``diameter: d``. ``fail(field path, reason)`` makes the error."""
    if t.shape == "rectangle":
        if t.diameter is not None:
            raise fail(f"{path}.diameter", "only a round table (shape: circle) has a diameter")
        if t.size is None:
            raise fail(f"{path}.size", "Field required")
        w, d = t.size
    else:
        sizes = [] if t.size is None else [t.size]
        if t.diameter is not None:
            sizes.append((t.diameter, t.diameter))
        if not sizes:
            raise fail(f"{path}.size", "Field required (a round table: [d, d] or diameter: d)")
        for w, d in sizes:
            if not math.isclose(w, d, rel_tol=0.0, abs_tol=_ROUND_TOL_M):
                raise fail(f"{path}.size", f"a round table has one size, its diameter: give "
                           f"[d, d] or diameter: d, got [{w:g}, {d:g}]")
        if len(sizes) == 2 and not math.isclose(sizes[0][0], t.diameter or 0.0, rel_tol=0.0,
                                                abs_tol=_ROUND_TOL_M):
            raise fail(f"{path}.diameter", f"{t.diameter:g} m disagrees with size "
                       f"[{sizes[0][0]:g}, {sizes[0][1]:g}]")
        w, d = sizes[0]
    return SceneTable(t.name, Box(t.center[0], t.center[1], w, d, t.yaw), t.height, t.shape)


def _poly(b: Box | Disc) -> Polygon:
    """``b``'s footprint as a shapely polygon (room frame, metres)."""
    return Polygon(b.outline())


def _overlap(a: shapely.Geometry, b: shapely.Geometry) -> bool:
    """Whether ``a`` and ``b`` overlap by more than the tolerance (touching is fine)."""
    return bool(a.buffer(-_TOL_M, join_style="mitre").intersects(b))


def _inside(a: shapely.Geometry, room: Polygon) -> bool:
    return bool(room.buffer(_TOL_M, join_style="mitre").contains(a))


def _start_blocked(start: Pose2D, radius: float, room: Polygon, walls: tuple[Box, ...],
                   tables: tuple[SceneTable, ...], chairs: tuple[Chair, ...]) -> str | None:
    """Why the base (a disc of ``radius`` metres) cannot stand at ``start``, or ``None``."""
    disc = Point(start.x, start.y).buffer(radius)
    at = f"the base (radius {radius:g} m) at ({start.x:g}, {start.y:g})"
    if not _inside(disc, room):
        return f"{at} crosses the room's outer wall"
    for j, wall in enumerate(walls):
        if _overlap(disc, _poly(wall)):
            return f"{at} collides with wall {j + 1}"
    for t in tables:
        if _overlap(disc, _poly(t.footprint)):
            return f"{at} collides with table {t.name!r}"
    for c in chairs:
        if _overlap(disc, _poly(c.box)):
            return f"{at} collides with {_plain(c.name)}"
    return None
