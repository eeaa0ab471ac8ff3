"""The episode stream: what an episode reports as it runs, simulator-neutral and typed.

Times are simulated seconds since the episode began (the session's ``time_s``); poses
are in the room frame (the map frame: metres, radians, z up). Two kinds of reporter:

* the executive (:mod:`llm_grop.execution`) reports the episode's start and end, each
  attempt as it ends (:class:`~llm_grop.world.plan.ExecutedStep`) and where the base and
  every object are then; that much every simulator gives;
* a simulator whose class declares :attr:`~llm_grop.simulation.base.Simulator.streams`
  reports, while an attempt runs, what it names there (:data:`STREAMS`) to the
  :class:`SensorObserver` its session is given.

Observers (:class:`EpisodeObserver`) are sinks that turn the stream into a file; this
module imports no sink, so a simulator that reports to it loads none.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, Protocol, get_args

import numpy as np

from llm_grop.world.arrangement import Item
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, ObjectState, Plan
from llm_grop.world.relation import Relation
from llm_grop.world.scene import Scene

#: What a simulator may report while an attempt runs: ``base``, the base's pose;
#: ``bodies``, every object's pose; ``arm``, the arm's joints and links; ``scan``, the
#: base's 2D lidar; ``camera``, frames of its named cameras.
Stream = Literal["base", "bodies", "arm", "scan", "camera"]
STREAMS: tuple[Stream, ...] = get_args(Stream)


@dataclass(frozen=True)
class BodyPose:
    """Where object ``name`` is: its bottom centre ``(x, y, z)`` (room frame, metres) and
    its orientation as a unit quaternion ``(x, y, z, w)``; ``held`` while in the hand."""

    name: str
    x: float
    y: float
    z: float
    quat_xyzw: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    held: bool = False

    @classmethod
    def of_state(cls, state: ObjectState) -> BodyPose:
        """The pose of a reported :class:`ObjectState`: turned by its yaw about z, then
        tipped by its tilt about its own x axis (a state says how far, not which way)."""
        cy, sy = math.cos(state.yaw / 2), math.sin(state.yaw / 2)
        ct, st = math.cos(state.tilt_rad / 2), math.sin(state.tilt_rad / 2)
        # q_yaw (0, 0, sy, cy) times q_tilt (st, 0, 0, ct)
        quat = (cy * st, sy * st, sy * ct, cy * ct)
        return cls(state.name, state.x, state.y, state.z, quat, state.held)


@dataclass(frozen=True)
class ArmState:
    """The arm: each joint's angle (``(name, radians)``, base to hand), the room-frame
    points of its links from the mount on the base to the hand (metres), and the
    fingers' opening (metres)."""

    joints: tuple[tuple[str, float], ...]
    links: tuple[tuple[float, float, float], ...]
    fingers_m: float = 0.0


@dataclass(frozen=True)
class Scan:
    """One sweep of the base's planar lidar, as ROS's ``sensor_msgs/LaserScan`` has it:
    the scanner at ``pose`` (room frame) ``height_m`` above the floor, ray ``k`` at
    ``angle_min_rad + k * angle_increment_rad`` from the base's heading, its range in
    metres (``inf``: nothing within ``range_max_m``), one ``float`` array."""

    pose: Pose2D
    height_m: float
    angle_min_rad: float
    angle_increment_rad: float
    range_max_m: float
    ranges_m: np.ndarray = field(compare=False, repr=False)

    def points(self) -> np.ndarray:
        """Where the rays hit, ``(N, 2)`` room-frame points (metres); misses left out."""
        ranges = np.asarray(self.ranges_m, dtype=float)
        angles = self.pose.theta + self.angle_min_rad \
            + self.angle_increment_rad * np.arange(len(ranges))
        hit = np.isfinite(ranges)
        r, a = ranges[hit], angles[hit]
        return np.column_stack([self.pose.x + r * np.cos(a), self.pose.y + r * np.sin(a)])


@dataclass(frozen=True)
class CameraFrame:
    """A picture from the simulator's named ``camera``: ``height x width x 3`` ``uint8``
    RGB."""

    camera: str
    image: np.ndarray = field(compare=False, repr=False)


@dataclass(frozen=True)
class ObjectShape:
    """An object as drawn: its ``name``, catalog ``kind``, footprint ``shape`` (``circle``
    or ``box``) of ``size`` ``(sx, sy)`` and its ``height`` (metres)."""

    name: str
    kind: str
    shape: str
    size: tuple[float, float]
    height: float

    @classmethod
    def of_item(cls, item: Item) -> ObjectShape:
        """The shape of a requested item, from its catalog entry."""
        s = item.spec
        return cls(item.name, s.name, s.shape, s.size, s.height)


@dataclass(frozen=True)
class EpisodeStart:
    """What an episode is about to execute: the room (its chairs the true ones), the
    objects, the plan and the arrangement's relations it realises, and who made them.
    ``streams`` are what the simulator reports while attempts run (:data:`STREAMS`);
    the rest of the motion is what the executive reports."""

    scene: Scene
    objects: tuple[ObjectShape, ...]
    plan: Plan
    relations: tuple[Relation, ...]
    method: str
    task: int | None
    seed: int
    request: str
    simulator: str
    feasibility: str = "default"
    streams: frozenset[str] = frozenset()


@dataclass(frozen=True)
class EpisodeEnd:
    """How the episode ended: ``success``, the simulated seconds it took, and each
    unplaced object with why (one of :data:`~llm_grop.world.plan.REASONS`)."""

    success: bool
    execution_time_s: float
    unplaced: tuple[tuple[str, str], ...] = ()


class SensorObserver(Protocol):
    """What a simulator's session reports to while an attempt runs, at simulated time
    ``t_s`` (seconds); it reports only the :data:`STREAMS` its simulator declares."""

    def base(self, t_s: float, pose: Pose2D) -> None:
        """The base's pose (room frame)."""
        ...

    def bodies(self, t_s: float, poses: Sequence[BodyPose]) -> None:
        """Every object's pose."""
        ...

    def arm(self, t_s: float, arm: ArmState) -> None:
        """The arm's joints and links."""
        ...

    def scan(self, t_s: float, scan: Scan) -> None:
        """A lidar sweep."""
        ...

    def frame(self, t_s: float, frame: CameraFrame) -> None:
        """A camera's picture."""
        ...


class EpisodeObserver(SensorObserver, Protocol):
    """A whole episode's observer: the sensor stream, and from the executive its start,
    every attempt as it ends, and its end."""

    def begin(self, start: EpisodeStart) -> None:
        """The episode starts (simulated time 0)."""
        ...

    def step(self, t_s: float, step: ExecutedStep) -> None:
        """An attempt ended at ``t_s``; it began ``step.duration_s`` before."""
        ...

    def end(self, t_s: float, end: EpisodeEnd) -> None:
        """The episode ended."""
        ...


class Sink(EpisodeObserver, Protocol):
    """An observer that writes a file, finished by :meth:`close`."""

    def close(self) -> None:
        """Finish the file (also after a failed episode)."""
        ...
