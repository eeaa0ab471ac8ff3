"""Offscreen pictures of the MuJoCo world: the table (robot hidden), the room with the
robot, and an episode video, each from a named camera
(:data:`~llm_grop.simulation.mujoco.options.CAMERAS`): ``top-down``, ``diner``, ``robot``
or ``room``.

Rendering needs an OpenGL library without a screen: OSMesa (apt ``libosmesa6``) or EGL
(apt ``libegl1 libgl1-mesa-dri``, software rendering works). The package picks one when it
is imported (see :mod:`llm_grop.simulation.mujoco`); ``MUJOCO_GL`` chooses explicitly.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Literal

import mujoco
import numpy as np

from llm_grop.errors import BadInput
from llm_grop.simulation.mujoco.options import GL_APT, Camera, check_camera
from llm_grop.simulation.mujoco.world import World

View = Literal["table", "room"]
#: Each view's camera when none is named.
DEFAULT_CAMERA: dict[str, Camera] = {"table": "top-down", "room": "room"}

#: Geom groups drawn: furniture and tableware (0), what is drawn only (1: looks,
#: placemats), the robot (2); not the collision shapes behind looks (4).
_GROUPS_TABLE = (1, 1, 0, 0, 0, 0)
_GROUPS_ROOM = (1, 1, 1, 0, 0, 0)



def check_rendering() -> None:
    """:class:`BadInput` naming the apt package to install when offscreen rendering is
    not available (checked before any work, by opening a tiny GL context)."""
    renderer = new_renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), (8, 8))
    try:
        renderer.render()
    finally:
        renderer.close()


def new_renderer(model: mujoco.MjModel, size: tuple[int, int]) -> mujoco.Renderer:
    """A renderer of ``size`` (width, height) pixels; :class:`BadInput` for a size beyond
    the model's offscreen buffer, or naming what to install when no offscreen OpenGL is
    available."""
    limit = (model.vis.global_.offwidth, model.vis.global_.offheight)
    if size[0] > limit[0] or size[1] > limit[1]:
        raise BadInput(f"image size {size[0]}x{size[1]}: larger than the world's offscreen "
                       f"buffer {limit[0]}x{limit[1]}; raise MujocoOptions.image_size")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # GLFW warns before it fails
            return mujoco.Renderer(model, height=size[1], width=size[0])
    except Exception as exc:  # noqa: BLE001 - any GL failure means the same to the user
        backend = os.environ.get("MUJOCO_GL", "").lower()
        if backend in GL_APT:
            need = f"the apt package {GL_APT[backend]} (MUJOCO_GL={backend})"
        else:
            need = ("the apt package libosmesa6 (or libegl1 and libgl1-mesa-dri), and set "
                    "MUJOCO_GL=osmesa or egl before mujoco is first imported")
        raise BadInput(f"offscreen rendering is not available: install {need} "
                       f"({type(exc).__name__})") from None


def picture(world: World, view: View, size: tuple[int, int] | None = None,
            camera: str | None = None) -> np.ndarray:
    """An RGB image (height x width x 3, uint8) of ``world`` now, from ``camera``.

    ``table``: the furniture and tableware, robot hidden, as the raters see it; by default
    from ``top-down``, the target table straight from above (orthographic), the diner at
    the bottom. ``room``: the robot too; by default from ``room``, the whole room from
    above the diner's side. :class:`BadInput` for an unknown camera.
    """
    check_camera(camera)
    m = world.m
    width, height = size or (m.vis.global_.offwidth, m.vis.global_.offheight)
    renderer = new_renderer(m, (width, height))
    try:
        return render_with(renderer, world, view, camera)
    finally:
        renderer.close()


def render_with(renderer: mujoco.Renderer, world: World, view: View,
                camera: str | None = None) -> np.ndarray:
    """An RGB image of ``world`` showing ``view`` from ``camera`` (``None``: the view's
    :data:`DEFAULT_CAMERA`) with an open ``renderer`` (for frame after frame, as a video
    needs)."""
    option = mujoco.MjvOption()
    option.geomgroup[:] = _GROUPS_TABLE if view == "table" else _GROUPS_ROOM
    option.sitegroup[:] = 0
    name = camera or DEFAULT_CAMERA[view]
    cam = _room_camera(world) if name == "room" else name
    renderer.update_scene(world.d, camera=cam, scene_option=option)
    return renderer.render().copy()


def _room_camera(world: World) -> mujoco.MjvCamera:
    scene = world.scene
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = (scene.width / 2, scene.depth / 2, 0.3)
    cam.distance = 1.05 * max(scene.width, scene.depth)
    cam.azimuth = 90.0
    cam.elevation = -60.0
    return cam


def check_video_path(path: str | os.PathLike[str]) -> None:
    """:class:`BadInput` unless ``path`` names an MP4 file."""
    if Path(path).suffix.lower() != ".mp4":
        raise BadInput("the video must be an .mp4 file", param="video_path", value=str(path))


class VideoRecorder:
    """Streams room views of an episode (robot drawn) from ``camera`` to an MP4 file (H.264
    through imageio-ffmpeg): pass it as the simulator's ``on_frame`` and call :meth:`close`
    at the end."""

    def __init__(self, path: str | os.PathLike[str], *, fps: int = 25,
                 size: tuple[int, int] = (640, 480), camera: str = "room") -> None:
        check_video_path(path)
        check_camera(camera)
        import imageio_ffmpeg

        self.path, self.size, self.camera = Path(path), size, camera
        self._writer = imageio_ffmpeg.write_frames(str(self.path), size, fps=fps,
                                                   macro_block_size=8, quality=6)
        self._writer.send(None)
        self._renderer: mujoco.Renderer | None = None
        self.frames = 0

    def __call__(self, world: World) -> None:
        if self._renderer is None:
            self._renderer = new_renderer(world.m, self.size)
        self._writer.send(np.ascontiguousarray(render_with(self._renderer, world, "room",
                                                           self.camera)))
        self.frames += 1

    def close(self) -> None:
        """Finish the file."""
        self._writer.close()
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
