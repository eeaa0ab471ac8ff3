"""The dining room: walls, tables, chairs and where the tableware starts (room frame).

Room frame: the map frame, metres and radians; the room spans ``[0, width] x [0, depth]``
and its outer walls are its boundary. The *target table* is the one to be set; its own
frame is the contract's table frame (origin at the top's centre, +y away from the diner,
who sits at its -y edge). Chairs are not part of the pre-built map: a planner senses them
at planning time (see :meth:`Scene.static_obstacles`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from llm_grop.errors import BadInput
from llm_grop.world.angles import wrap_angle
from llm_grop.world.geometry2d import Box, Disc, Pose2D
from llm_grop.world.robot import Robot
from llm_grop.world.seat import Seat
from llm_grop.world.table import Table, TableShape


@dataclass(frozen=True)
class SceneTable:
    """A table in the room: ``name``, its top's ``box`` (room frame), ``height`` in metres
    and ``shape``.

    A round top (``shape="circle"``) is the disc inscribed in ``box``, a square whose
    side is the diameter; ``box`` keeps giving its centre, yaw (the table frame's
    orientation) and bounding square. Use :attr:`footprint` or :meth:`contains` for
    the true outline. Raises :class:`BadInput` for a round top whose box is not square.
    """

    name: str
    box: Box
    height: float = 0.75
    shape: TableShape = "rectangle"

    def __post_init__(self) -> None:
        if self.shape == "circle" and not math.isclose(self.box.width, self.box.depth,
                                                       rel_tol=0.0, abs_tol=1e-6):
            raise BadInput(f"table {self.name!r}: a round table has one size, its diameter, "
                           f"but was given {self.box.width:g} x {self.box.depth:g} m")

    @property
    def is_round(self) -> bool:
        """Whether the top is a circle."""
        return self.shape == "circle"

    @property
    def footprint(self) -> Box | Disc:
        """The top's true outline in the room frame: ``box``, or the disc inside it."""
        if self.is_round:
            return Disc(self.box.x, self.box.y, self.box.width / 2)
        return self.box

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        """Whether room-frame point ``(x, y)`` is on the top grown by ``margin`` metres."""
        return self.footprint.contains(x, y, margin)


@dataclass(frozen=True)
class Chair:
    """A chair: its footprint ``box`` in the room frame. Not in the pre-built map."""

    name: str
    box: Box


@dataclass(frozen=True)
class ObjectSource:
    """Where one requested object starts: on table ``table`` at room-frame ``(x, y)`` metres,
    on the top or, in a pile, on the object named ``on`` (which starts at the same spot).

    ``object`` is an item name ("dinner fork 2") or a catalog kind ("dinner fork").
    """

    object: str
    table: str
    x: float
    y: float
    on: str | None = None


@dataclass(frozen=True)
class Scene:
    """A dining room.

    Attributes:
        name: a label.
        width, depth: room size in metres (x and y extent).
        walls: interior walls as boxes (the outer walls are the room's boundary).
        tables: every table, the target included.
        target: the name of the table to set.
        source_tables: tables the tableware may start on (default: every other table).
        sources: where objects start; objects not listed are assigned to a source table.
        chairs: chairs in the room, sensed at planning time.
        robot_start: the robot's start pose.
        robot: the robot's parameters.
        chairs_listed: whether the scene states its chairs (an empty list: none), so an
            episode keeps them instead of sampling one.
        chair_band_m: chairs are sampled between these distances (metres) from the target
            table's ±y sides (the diner's side and the far side, in the table's frame);
            from a round table's edge, round the arcs on those two sides.
    """

    name: str
    width: float
    depth: float
    tables: tuple[SceneTable, ...]
    target: str
    robot_start: Pose2D
    walls: tuple[Box, ...] = ()
    source_tables: tuple[str, ...] = ()
    sources: tuple[ObjectSource, ...] = ()
    chairs: tuple[Chair, ...] = ()
    robot: Robot = field(default_factory=Robot)
    chair_band_m: tuple[float, float] = (0.0, 1.0)
    chairs_listed: bool = False
    diners: tuple[Seat, ...] = ()

    def table(self, name: str) -> SceneTable:
        """The table called ``name``; ``KeyError`` if there is none."""
        for t in self.tables:
            if t.name == name:
                return t
        raise KeyError(name)

    @property
    def target_table(self) -> SceneTable:
        """The table to set."""
        return self.table(self.target)

    @property
    def target_top(self) -> Table:
        """The target table's top as the arrangement's :class:`Table` (width, depth and
        shape; a round top's width and depth are its diameter)."""
        t = self.target_table
        return Table(t.box.width, t.box.depth, t.shape, self.diners)

    def with_target_top(self, top: Table) -> Scene:
        """This scene with the target table's top replaced by ``top`` (same centre, yaw
        and height). Nothing is checked here; see
        :func:`llm_grop.files.scene_file.set_target_top`."""
        t = self.target_table
        box = replace(t.box, width=top.width, depth=top.depth)
        tables = tuple(replace(t, box=box, shape=top.shape) if u.name == t.name else u
                       for u in self.tables)
        return replace(self, tables=tables)

    @property
    def supply_tables(self) -> tuple[SceneTable, ...]:
        """Tables the tableware may start on."""
        names = self.source_tables or tuple(t.name for t in self.tables if t.name != self.target)
        return tuple(self.table(n) for n in names)

    def static_obstacles(self) -> tuple[Box | Disc, ...]:
        """The pre-built map's obstacles: interior walls and every table's true outline
        (a :class:`Disc` for a round one; no chairs)."""
        return self.walls + tuple(t.footprint for t in self.tables)

    def source_for(self, item: str, kind: str) -> ObjectSource | None:
        """Where item ``item`` (of catalog kind ``kind``) starts, if the scene says."""
        for s in self.sources:
            if s.object == item:
                return s
        for s in self.sources:
            if s.object == kind:
                return s
        return None

    def resting_z(self, item: str, kind: str, heights: Mapping[str, float]) -> float:
        """Height, metres above the floor, of the bottom of item ``item`` (of kind ``kind``)
        where it starts: its table's top plus the heights of the objects under it in its
        pile (``heights``: item name -> height in metres). ``KeyError`` when it has no
        source."""
        source = self.source_for(item, kind)
        if source is None:
            raise KeyError(item)
        z, seen = self.table(source.table).height, {item}
        while source is not None and source.on is not None and source.on not in seen:
            seen.add(source.on)
            z += heights.get(source.on, 0.0)
            source = self.source_for(source.on, "")
        return z

    def with_chairs(self, chairs: tuple[Chair, ...]) -> Scene:
        """This scene with ``chairs`` instead of its own."""
        return replace(self, chairs=chairs, chairs_listed=True)

    def with_sources(self, sources: tuple[ObjectSource, ...]) -> Scene:
        """This scene with ``sources`` instead of its own."""
        return replace(self, sources=sources)

    def table_to_room(self, x: float, y: float, yaw: float = 0.0) -> Pose2D:
        """A table-frame pose of the target table in the room frame."""
        box = self.target_table.box
        rx, ry = box.to_room(x, y)
        return Pose2D(rx, ry, wrap_angle(yaw + box.yaw))

    def room_to_table(self, x: float, y: float, theta: float = 0.0) -> tuple[float, float, float]:
        """A room-frame pose in the target table's frame, as ``(x, y, yaw)``."""
        box = self.target_table.box
        u, v = box.to_local(x, y)
        return (u, v, wrap_angle(theta - box.yaw))

