"""The named cameras of the dining room model (see
:data:`~llm_grop.simulation.mujoco.options.CAMERAS`): ``top-down`` and ``diner`` are
added here from the scene; ``robot`` rides on the base (``assets/robot.xml``); ``room`` is
a free camera set up at render time (:mod:`llm_grop.simulation.mujoco.render`). Metres,
radians unless a name says degrees."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from llm_grop.world.scene import Scene

#: The diner's camera: eye height above the floor (seated), how far behind the seat, and
#: its vertical field of view (metres, degrees).
DINER_EYE_M, DINER_BACK_M, DINER_FOVY_DEG = 1.20, 0.20, 55.0


def add_cameras(world: mujoco.MjsBody, scene: Scene, mat: tuple[float, float] | None) -> None:
    """Add to ``world`` the cameras made from the scene: ``top-down``, orthographic,
    straight down on the target table, image up = the table's +y (away from the diner);
    ``diner``, from the first diner's seat at a seated person's eye height, looking at
    their place (``mat``, else the table's centre)."""
    t = scene.target_table
    b = t.box
    cam = world.add_camera(name="top-down", pos=[b.x, b.y, t.height + 1.5],
                           quat=[math.cos(b.yaw / 2), 0, 0, math.sin(b.yaw / 2)])
    cam.proj = mujoco.mjtProjection.mjPROJ_ORTHOGRAPHIC
    cam.fovy = max(b.depth, b.width * 3 / 4) * 1.15
    seat = scene.target_top.seats[0]
    here = scene.table_to_room(seat.x, seat.y, seat.yaw)
    eye = np.array([here.x - DINER_BACK_M * math.cos(here.theta),
                    here.y - DINER_BACK_M * math.sin(here.theta), DINER_EYE_M])
    target = np.array([*(mat or (b.x, b.y)), t.height])
    world.add_camera(name="diner", pos=eye.tolist(), quat=_looking(target - eye),
                     fovy=DINER_FOVY_DEG)


def _looking(forward: np.ndarray) -> list[float]:
    """The quaternion of a camera looking along ``forward`` (not vertical), image up
    towards +z (a MuJoCo camera looks along its -z, its image's up is its +y)."""
    z = -forward / np.linalg.norm(forward)
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([x, y, z]).ravel())
    return quat.tolist()
