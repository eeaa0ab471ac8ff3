"""Settings of the MuJoCo world (metres, seconds, radians, newtons, pixels)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, get_args

from pydantic import ConfigDict

from llm_grop.errors import BadInput
from llm_grop.settings import DEFAULTS
from llm_grop.settings.record import Grasp

#: How the hand holds an object (the settings record's ``grasp``).
GRASPS: tuple[str, ...] = get_args(Grasp)

#: The named cameras of renders and videos: ``top-down``, orthographic straight down on
#: the target table, the diner at the bottom; ``diner``, the first diner's view from their
#: seat at a seated person's eye height; ``robot``, the robot's head camera, which moves
#: with it; ``room``, the whole room from above the diner's side.
#: The apt package that gives each offscreen GL backend (``MUJOCO_GL``).
GL_APT = {"osmesa": "libosmesa6", "egl": "libegl1 libgl1-mesa-dri"}

Camera = Literal["top-down", "diner", "robot", "room"]
CAMERAS: tuple[str, ...] = get_args(Camera)


def check_camera(camera: str | None) -> None:
    """:class:`BadInput` naming the cameras unless ``camera`` is one of :data:`CAMERAS` (or
    ``None``, each picture's default)."""
    if camera is not None and camera not in CAMERAS:
        raise BadInput(f"unknown camera {camera!r}; choose from {', '.join(CAMERAS)}",
                       param="camera")


@dataclass(frozen=True)
class LidarOptions:
    """The base's 2D laser scanner: rays cast in MuJoCo in one horizontal plane.

    Attributes:
        height_m: height of the scan plane above the floor, metres. Table tops (0.69 m)
            and chair seats (0.43 m) are above it; table and chair legs cross it.
        beams: rays per scan, spread evenly over the full turn.
        rate_hz: scans per simulated second.
        range_m: farthest return, metres.
    """

    height_m: float = 0.25
    beams: int = 360
    rate_hz: float = 10.0
    range_m: float = 6.0


@dataclass(frozen=True)
class BaseOptions:
    """The wheeled base: its limits, its path follower, its goal checker and its safety
    layer.

    Attributes:
        accel_mps2: largest forward acceleration and braking, metres per second squared.
        turn_accel_radps2: largest turning acceleration, radians per second squared.
        traction_n: largest force the wheels transmit to the floor, newtons (friction 0.6
            under the robot's 98 kg); a bump cannot push harder than this.
        lookahead_m: the path follower's lookahead distance, metres.
        rotate_to_heading_rad: turn in place first when the lookahead point is further
            than this off the heading, radians.
        xy_goal_tolerance_m: the goal checker's position tolerance, metres (ROS 1
            base_local_planner's default, which the authors' move_base used).
        yaw_goal_tolerance_rad: the goal checker's heading tolerance, radians (likewise).
        stop_margin_m: the safety layer keeps the footprint this far from what the lidar
            sees, metres.
        slow_horizon_s: the safety layer slows so that the footprint, carrying on at the
            commanded speed, would reach an obstacle no sooner than this, seconds (Nav2's
            collision monitor's approach behaviour).
        min_speed_mps: below this allowed speed the safety layer stops the base and the
            drive fails ``blocked``, metres per second.
        progress_timeout_s: a drive fails ``blocked`` when the base has neither moved
            0.1 m nor turned 0.5 rad for this long, seconds (Nav2's progress checker).
    """

    accel_mps2: float = 0.5
    turn_accel_radps2: float = 2.0
    traction_n: float = 580.0
    lookahead_m: float = 0.3
    rotate_to_heading_rad: float = 0.6
    xy_goal_tolerance_m: float = 0.10
    yaw_goal_tolerance_rad: float = 0.05
    stop_margin_m: float = 0.01
    slow_horizon_s: float = 1.0
    min_speed_mps: float = 0.03
    progress_timeout_s: float = 6.0


@dataclass(frozen=True)
class MujocoOptions:
    """Settings of the 3D world.

    Attributes:
        base: the wheeled base and its navigation (:class:`BaseOptions`).
        lidar: the base's laser scanner (:class:`LidarOptions`).
        grasp: how the hand holds (:data:`Grasp`): ``fix`` or ``friction``.
        chair_mass_kg: mass of a chair, kilograms; chairs are free bodies a bump pushes.
        chair_friction: sliding friction between a chair's legs and the floor.
        nav_noise_var_m2: variance, per axis, square metres, of an offset added to every
            navigation goal after the base arrives (the authors' setting is 0.03; 0, the
            default: the arrival error is whatever the controller achieves).
        heading_noise_std_rad: standard deviation of the heading offset added with it,
            radians (used only when ``nav_noise_var_m2`` is above 0).
        timestep_s: physics time step, seconds.
        image_size: width and height of offscreen renders, pixels.
        video_path: where to write an MP4 video of the episode (``None``: no video).
        video_frame_s: simulated seconds between two video frames.
        video_fps: frames per second of the video.
        camera: the camera (:data:`CAMERAS`) of the table render and of the video;
            ``None``: ``top-down`` for the table render, ``room`` for the video. The room
            render always uses ``room``.
        record_dt_s: simulated seconds between two reports of the base, the objects, the
            arm and the lidar to an episode's recording.
        record_cameras: the cameras (:data:`CAMERAS`) whose frames a recording holds
            (empty, the default: none; each frame is an offscreen render, which costs
            more than the rest of a recording).
        record_camera_s: simulated seconds between two of a recording's camera frames.
        record_image_size: width and height of a recording's camera frames, pixels.
    """

    base: BaseOptions = field(default_factory=BaseOptions)
    lidar: LidarOptions = field(default_factory=LidarOptions)
    grasp: Grasp = DEFAULTS.grasp  # type: ignore[assignment]
    chair_mass_kg: float = 5.0
    chair_friction: float = 0.5
    nav_noise_var_m2: float = 0.0
    heading_noise_std_rad: float = 0.03
    timestep_s: float = 0.004
    image_size: tuple[int, int] = (640, 480)
    video_path: str | None = field(default=None, metadata={"path": "file"})
    video_frame_s: float = 0.2
    video_fps: int = 25
    camera: Camera | None = None
    record_dt_s: float = 0.2
    record_cameras: tuple[Camera, ...] = ()
    record_camera_s: float = 5.0
    record_image_size: tuple[int, int] = (160, 120)

    # The front doors check a user's options with pydantic; unknown keys are refused.
    __pydantic_config__ = ConfigDict(extra="forbid")

    def __post_init__(self) -> None:
        if self.grasp not in GRASPS:
            raise BadInput(f"unknown grasp {self.grasp!r}; choose from "
                           f"{', '.join(GRASPS)}", param="grasp")
        check_camera(self.camera)
        for camera in self.record_cameras:
            check_camera(camera)
        if self.record_dt_s <= 0 or self.record_camera_s <= 0:
            raise BadInput("mujoco options: record_dt_s and record_camera_s must be positive")
        if self.nav_noise_var_m2 < 0 or self.heading_noise_std_rad < 0:
            raise BadInput("mujoco options: nav_noise_var_m2 and heading_noise_std_rad must "
                           "not be negative")
        if self.lidar.beams < 1 or self.lidar.rate_hz <= 0 or self.lidar.range_m <= 0:
            raise BadInput("mujoco options: lidar: beams, rate_hz and range_m must be "
                           "positive")
        if self.chair_mass_kg <= 0 or self.chair_friction <= 0:
            raise BadInput("mujoco options: chair_mass_kg and chair_friction must be "
                           "positive")
