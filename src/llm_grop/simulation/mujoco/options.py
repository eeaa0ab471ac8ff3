"""Settings of the MuJoCo world (metres, seconds, radians, pixels)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MujocoOptions:
    """Settings of the 3D world.

    Attributes:
        nav_noise_var_m2: variance of the final base position, per axis, square metres.
        heading_noise_std_rad: standard deviation of the final heading, radians.
        timestep_s: physics time step, seconds.
        image_size: width and height of offscreen renders, pixels.
        video_path: where to write an MP4 video of the episode (``None``: no video).
        video_frame_s: simulated seconds between two video frames.
        video_fps: frames per second of the video.
    """

    nav_noise_var_m2: float = 0.03
    heading_noise_std_rad: float = 0.03
    timestep_s: float = 0.004
    image_size: tuple[int, int] = (640, 480)
    video_path: str | None = None
    video_frame_s: float = 0.2
    video_fps: int = 25
