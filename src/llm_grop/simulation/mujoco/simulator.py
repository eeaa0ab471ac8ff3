"""The MuJoCo simulator (registered as ``mujoco``): a mobile manipulator in 3D physics,
offering the executive one attempt at a time (:class:`MujocoSession`).

* Navigation (:mod:`~llm_grop.simulation.mujoco.drive`): a differential-drive base under
  velocity control follows the path with pure pursuit, a safety layer on a simulated 2D
  lidar slows and stops it before what it sees, and a goal checker judges arrival within
  x/y and yaw tolerances. Contact with furniture it could not see (a chair leg between
  beams) stops it, pushes the chair by physics, and it backs off.
* Manipulation (:mod:`~llm_grop.simulation.mujoco.manipulation`): IK, pre-grasp, grasp,
  close, lift, carry; pre-place, lower, release, settle.
* The tray (``world/tray.xml``): with ``robot.capacity`` above 1 the base carries it;
  loading is a place onto it, unloading a pick from it, and what rides on it rides by
  friction (it may slide or tip when the base stops hard).
* Truth: every object's pose, tilt and support (from contact) are read from the settled
  bodies.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from llm_grop.errors import BadInput
from llm_grop.recording.stream import STREAMS
from llm_grop.simulation.base import PathPlanner, Simulator
from llm_grop.simulation.mujoco.arm import ArmIK
from llm_grop.simulation.mujoco.options import CAMERAS, MujocoOptions
from llm_grop.simulation.mujoco.render import VideoRecorder, View, check_rendering, picture
from llm_grop.simulation.mujoco.session import MujocoSession
from llm_grop.simulation.mujoco.tableware import tableware
from llm_grop.simulation.mujoco.world import World
from llm_grop.simulation.mujoco.world_model import ObjectStart, build, check_scene
from llm_grop.world.arrangement import Item, Placement, item_placement
from llm_grop.world.scene import Scene
from llm_grop.world.tray import load_tray

__all__ = ["MujocoOptions", "MujocoSimulator"]


class MujocoSimulator(Simulator):
    """Runs episodes in MuJoCo. :attr:`world` holds the last episode's world and
    :meth:`picture` renders it from a named camera (``options.camera`` chooses the one of
    the table render and the video). ``on_frame`` is called with the world every
    ``options.video_frame_s`` simulated seconds (a video recorder, a viewer)."""

    name = "mujoco"
    Options = MujocoOptions
    supports_pictures = True
    supports_video = True
    cameras = CAMERAS
    streams = frozenset(STREAMS)

    def __init__(self, options: MujocoOptions | None = None, *,
                 on_frame: Callable[[World], None] | None = None) -> None:
        self.options = options or MujocoOptions()
        self.on_frame = on_frame
        self.world: World | None = None
        self._ik: ArmIK | None = None

    def fitted_profile(self) -> str:
        """``mujoco``: the profile fitted to Task 8 episodes in this world
        (``benchmarks/fit_profile.py``)."""
        return "mujoco"

    def tray_capacity(self) -> int:
        """The tray's (``world/tray.xml``): with ``robot.capacity`` above 1 the base
        carries it."""
        return load_tray().capacity

    def picture(self, view: View = "table", size: tuple[int, int] | None = None,
                camera: str | None = None) -> np.ndarray:
        """An RGB image of the last episode as it ended, from ``camera`` (``None``: for the
        table, ``options.camera``, else each view's default; see
        :func:`~llm_grop.simulation.mujoco.render.picture`)."""
        if self.world is None:
            raise RuntimeError("nothing executed yet")
        if camera is None and view == "table":
            camera = self.options.camera
        return picture(self.world, view, size, camera)

    def check_rendering(self) -> None:
        """:class:`BadInput` naming the apt package when offscreen rendering is missing."""
        check_rendering()

    def check(self, scene: Scene, items: Sequence[Item] = ()) -> None:
        """:class:`BadInput` when this scene or these objects cannot be simulated (called
        before planning, so bad input costs no work)."""
        check_scene(scene)
        self.check_capacity(scene)
        for item in items:
            tableware(item_placement(item))

    def session(self, scene: Scene, items: Sequence[Item], rng: np.random.Generator, *,
                replan: PathPlanner) -> MujocoSession:
        """A new episode in ``scene`` with ``items`` at their starts, driven one attempt at
        a time; with ``options.video_path`` its video is recorded until it is closed."""
        o = self.options
        placements = tuple(item_placement(i) for i in items)
        world = self._world(scene, placements)
        recorder = VideoRecorder(o.video_path, fps=o.video_fps, size=o.image_size,
                                 camera=o.camera or "room") if o.video_path else None
        if recorder is not None:
            world.on_frame = _both(self.on_frame, recorder)
        return MujocoSession(o, scene, rng, replan, world, [p.name for p in placements],
                             recorder.close if recorder is not None else None)

    def _world(self, scene: Scene, placements: Sequence[Placement]) -> World:
        if self._ik is None:
            self._ik = ArmIK()
        starts = []
        for p in placements:
            item = tableware(p)
            src = scene.source_for(p.name, item.kind)
            if src is None:
                raise BadInput(f"scene {scene.name!r}: no start for object {p.name!r}")
            starts.append(ObjectStart(item, src.x, src.y, scene.table(src.table).height))
        o = self.options
        wm = build(scene, starts, timestep_s=o.timestep_s, image_size=o.image_size,
                   traction_n=o.base.traction_n, chair_mass_kg=o.chair_mass_kg,
                   chair_friction=o.chair_friction, tray=scene.robot.capacity > 1)
        world = World(wm, scene, self._ik, lidar=o.lidar, grasp=o.grasp,
                      speed_mps=scene.robot.speed_mps,
                      turn_speed_radps=scene.robot.turn_speed_radps, on_frame=self.on_frame,
                      frame_dt_s=o.video_frame_s)
        self.world = world
        return world


def _both(first: Callable[[World], None] | None, second: Callable[[World], None]
          ) -> Callable[[World], None]:
    """A frame hook calling ``first`` (if any), then ``second``."""
    def hook(w: World) -> None:
        if first is not None:
            first(w)
        second(w)
    return hook
