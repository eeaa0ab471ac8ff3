"""The simulator interface: primitives, one attempt at a time.

A simulator offers sessions. A session is one episode in a scene, driven one action at a
time: each navigate, pick or place is a single attempt that returns a typed
:class:`~llm_grop.world.plan.ExecutedStep`, and the session reports where every object
physically is (:class:`~llm_grop.world.plan.ObjectState`). It owns its ground truth: what
really happens when the robot drives, picks and places (its own success model or physics,
the true chairs). What to try next, when to give up and what counts as success belong to
the executive above it (:mod:`llm_grop.execution`), as in dm_control and robosuite, where
the physics offers state and actuation and the task logic lives above. The planner's
feasibility model is only a belief and never reaches a simulator. Backends are registered
in :mod:`llm_grop.simulation.registry`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar, Protocol

import numpy as np

from llm_grop.errors import BadInput
from llm_grop.recording.stream import SensorObserver
from llm_grop.settings.declared import declared_options
from llm_grop.settings.declared import option_names as declared_names
from llm_grop.world.arrangement import Item
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, ObjectState, Point
from llm_grop.world.scene import Scene


class PathPlanner(Protocol):
    """The robot's own path planner, for replanning after a failed navigation: a
    collision-free path for the base from ``start`` to ``goal`` (room frame), around the
    known furniture and the ``obstacles`` the robot's sensors saw (room-frame points)."""

    def plan(self, start: Point, goal: Point, seed: int,
             obstacles: Sequence[Point] = ()) -> tuple[Point, ...] | None:
        """The path's points in metres, or ``None`` when there is none."""
        ...


class Session(Protocol):
    """One episode driven one attempt at a time.

    Poses are room frame unless said otherwise (metres, radians). A failed attempt's step
    says why in ``reason`` (:data:`~llm_grop.world.plan.REASONS`); its ``duration_s`` is
    the simulated time it took, a failed inverse kinematics attempt included.
    """

    @property
    def time_s(self) -> float:
        """Simulated seconds so far."""
        ...

    @property
    def held(self) -> str | None:
        """The object in the hand, if any."""
        ...

    def robot_pose(self) -> Pose2D:
        """The base's pose."""
        ...

    def objects(self) -> dict[str, ObjectState]:
        """Where every object of the episode physically is, after the physics settled."""
        ...

    def navigate(self, goal: Pose2D, path: Sequence[Point] = ()) -> ExecutedStep:
        """One attempt to drive to ``goal``: along ``path`` when given (the plan's), else
        along a path the robot plans itself from where it stands."""
        ...

    def pick(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` from where it lies, from where the robot stands."""
        ...

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        """One attempt to put the held ``name`` down at ``(x, y, yaw)`` in the target
        table's frame, on the object ``on`` (``None``: the table). ``ok`` means the hand
        let go there; where the object then came to rest is read from :meth:`objects`."""
        ...

    def load(self, name: str) -> ExecutedStep:
        """One attempt to put the held ``name`` down on the robot's tray, in a free slot
        that fits it (a ``place`` step marked ``tray``). ``ok`` means the hand let go
        there; where it came to rest is read from :meth:`objects`. Refused (``ok`` false,
        no ``reason``) when no free slot fits it."""
        ...

    def unload(self, name: str) -> ExecutedStep:
        """One attempt to pick ``name`` from the robot's tray (a ``pick`` step marked
        ``tray``)."""
        ...

    def fits_tray(self, names: Sequence[str]) -> bool:
        """Whether ``names`` fit on the robot's tray together, each in a slot of its own,
        besides what rides on it now."""
        ...

    def release(self, name: str) -> float:
        """Give up ``name`` if the hand holds it: put it down away from the target table (on
        the floor). The simulated seconds it took."""
        ...

    def close(self) -> None:
        """End the episode (a video being recorded is finished)."""
        ...


class ObservedSession(Session, Protocol):
    """A session of a simulator that declares :attr:`Simulator.streams`: it reports what
    they name to an observer while its attempts run."""

    def watch(self, observer: SensorObserver) -> None:
        """Report the declared streams to ``observer`` from now on (simulated time is the
        session's :attr:`time_s`)."""
        ...


class Simulator(ABC):
    """Offers sessions. A simulator, shipped or a plugin's, subclasses this and declares,
    as class attributes, what users may set and what it can do (the way simonw/llm's
    models declare ``Options`` and ``supports_schema``); callers read the declaration and
    never probe for a method:

    - ``name``: the name it is registered under (it goes into the run JSON);
    - ``Options``: a frozen dataclass of its options, whose instance the constructor
      takes; the front doors check a user's values against it (``--sim-option
      timestep_s=0.002``, ``sim_options`` in a sweep file) with pydantic, unknown keys
      refused (:func:`options_of`);
    - ``supports_pictures``: :meth:`picture` renders the last episode (and
      :meth:`check_rendering` says before any work whether it can);
    - ``supports_video``: its options' ``video_path`` records each episode as an MP4;
    - ``cameras``: the named cameras its pictures and videos may be taken from (its
      options' ``camera``);
    - :meth:`fitted_profile`: the packaged feasibility profile fitted to what it does,
      which the planner believes under ``--feasibility auto``.
    - :meth:`tray_capacity`: how many objects its robot carries per trip (1: in the
      hand; more: on its tray); a scene's ``robot.capacity`` above it is bad input.
    - ``streams``: what its sessions report to an episode's observer while an attempt
      runs (:data:`~llm_grop.recording.stream.STREAMS`: ``base``, ``bodies``, ``arm``,
      ``scan``, ``camera``); a simulator that declares any has sessions with
      ``watch(observer)`` (:class:`ObservedSession`). Every simulator's episodes are
      recorded without: the executive reports each attempt and where everything is after
      it.

    All randomness comes from the ``rng`` given to :meth:`session`.
    """

    name: ClassVar[str]
    Options: ClassVar[type]
    supports_pictures: ClassVar[bool] = False
    supports_video: ClassVar[bool] = False
    cameras: ClassVar[tuple[str, ...]] = ()
    streams: ClassVar[frozenset[str]] = frozenset()

    @abstractmethod
    def session(self, scene: Scene, items: Sequence[Item], rng: np.random.Generator, *,
                replan: PathPlanner) -> Session:
        """A new episode in ``scene`` (its chairs are the true ones) with ``items`` at
        their starts."""

    def fitted_profile(self) -> str:
        """The name of the packaged feasibility profile (``data/feasibility.yaml``) whose
        curves describe what this simulator does: the planner's belief under
        ``--feasibility auto``. The default, ``default``, is the assumed profile, for a
        simulator no profile was fitted to."""
        return "default"

    def tray_capacity(self) -> int:
        """How many objects the robot carries per trip: 1 (in the hand) unless the
        simulator gives it a tray."""
        return 1

    def check(self, scene: Scene, items: Sequence[Item] = ()) -> None:
        """:class:`~llm_grop.errors.BadInput` when this scene or these objects cannot be
        simulated; called before planning, so bad input costs no work. The default accepts
        every scene whose robot carries no more than :meth:`tray_capacity`."""
        self.check_capacity(scene)

    def check_capacity(self, scene: Scene) -> None:
        """:class:`~llm_grop.errors.BadInput` when the scene's robot would carry more
        objects per trip than its tray holds."""
        most = self.tray_capacity()
        if scene.robot.capacity > most:
            holds = f"its tray holds {most}" if most > 1 else "it has no tray and carries 1"
            raise BadInput(f"robot.capacity: {scene.robot.capacity} objects per trip is more "
                           f"than simulator {self.name!r} can carry ({holds})")

    def check_rendering(self) -> None:
        """:class:`~llm_grop.errors.BadInput` when :meth:`picture` cannot work here (a
        missing library), said before any work."""
        if not self.supports_pictures:
            raise BadInput(f"simulator {self.name!r} makes no pictures", param="simulator")

    def picture(self, view: str = "table", size: tuple[int, int] | None = None,
                camera: str | None = None) -> np.ndarray:
        """An RGB image (``height x width x 3``, ``uint8``) of the last episode as it
        stands: its ``table`` or the ``room``, from ``camera`` (one of :attr:`cameras`;
        ``None``: the view's default), ``size`` (width, height) pixels."""
        raise BadInput(f"simulator {self.name!r} makes no pictures", param="simulator")


def option_names(simulator: type[Simulator]) -> tuple[str, ...]:
    """The options ``simulator`` declares."""
    return declared_names(simulator.Options)


def options_of(simulator: type[Simulator], given: Mapping[str, Any]) -> Any:
    """``given`` (a user's values by option name) as ``simulator``'s declared options,
    each checked against its type by pydantic: the first problem is one
    :class:`~llm_grop.errors.BadInput` naming ``sim_options.KEY``."""
    return declared_options(simulator.Options, given, owner=f"simulator {simulator.name!r}",
                            param="sim_options")
