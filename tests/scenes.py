"""Small hand-built dining rooms shared by the planning, simulation and method tests, and
a constant true success model for simulators."""

from __future__ import annotations

from dataclasses import dataclass, replace

from llm_grop.simulation.outcomes import BaseOutcomes
from llm_grop.world.arrangement import Configuration, Placement
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.robot import Robot
from llm_grop.world.scene import Chair, ObjectSource, Scene, SceneTable


def two_table_room(chairs: tuple[Chair, ...] = (), sources: tuple[ObjectSource, ...] = ()
                   ) -> Scene:
    """A 6 x 4 m room: the 0.9 x 0.6 m dining table at (3, 2), a counter at the west wall."""
    return Scene(
        name="test room", width=6.0, depth=4.0,
        tables=(SceneTable("dining table", Box(3.0, 2.0, 0.9, 0.6)),
                SceneTable("counter", Box(0.4, 2.0, 0.5, 1.2))),
        target="dining table", robot_start=Pose2D(1.5, 0.6, 0.0),
        sources=sources or (ObjectSource("dinner plate", "counter", 0.45, 2.1),
                            ObjectSource("bread", "counter", 0.45, 1.8),
                            ObjectSource("dinner fork", "counter", 0.45, 2.4),
                            ObjectSource("dinner knife", "counter", 0.45, 1.6),
                            ObjectSource("mug", "counter", 0.45, 2.5)),
        chairs=chairs)


def doorway_room(gap_m: float = 0.74) -> Scene:
    """:func:`two_table_room` split by a wall at x = 1.6 m with a doorway ``gap_m`` wide
    at y = 2 m: the robot starts west of it and the dining table is east."""
    lo = (4.0 - gap_m) / 2
    return replace(two_table_room(), walls=(Box(1.6, lo / 2, 0.1, lo),
                                            Box(1.6, 4.0 - lo / 2, 0.1, lo)))


def placement(name: str, x: float, y: float, shape: str = "circle",
              size: tuple[float, float] = (0.27, 0.27), on: str | None = None) -> Placement:
    """A placement on the table (table frame, metres)."""
    return Placement(name, x, y, 0.0, shape, size, on, name, 0.02)  # type: ignore[arg-type]


def config(*placements: Placement) -> Configuration:
    """A configuration from placements."""
    return Configuration(tuple(placements))


@dataclass(frozen=True)
class Constant(BaseOutcomes):
    """A true success model with fixed probabilities (within reach)."""

    nav: float
    manip: float

    def navigation(self, clearance_m: float) -> float:
        return self.nav if clearance_m >= 0 else 0.0

    def manipulation(self, reach_m: float, robot: Robot) -> float:
        return self.manip if robot.reach_min_m <= reach_m <= robot.reach_max_m else 0.0
