"""What the 3D world reports to an episode's observer while attempts run (the streams
:class:`~llm_grop.simulation.mujoco.simulator.MujocoSimulator` declares): every
``record_dt_s`` simulated seconds the base's pose, every object's pose, the arm's joints
and links, and the lidar's newest sweep; every ``record_camera_s`` a small frame from each
of ``record_cameras``. Nothing here knows what the observer writes."""

from __future__ import annotations

import logging
import math

import mujoco

from llm_grop.errors import BadInput
from llm_grop.recording.stream import ArmState, BodyPose, CameraFrame, Scan, SensorObserver
from llm_grop.simulation.mujoco.arm import ARM_JOINTS
from llm_grop.simulation.mujoco.options import MujocoOptions
from llm_grop.simulation.mujoco.render import new_renderer, render_with
from llm_grop.simulation.mujoco.world import World

log = logging.getLogger(__name__)

#: The arm's bodies from the mount on the base to the hand, drawn as one line.
ARM_LINKS = ("arm_mount", "shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2",
             "wrist_3", "hand")


class Reporter:
    """The world's observation hook for one session: call it with the world (as
    :attr:`World.observe`); :meth:`close` releases its renderer."""

    def __init__(self, world: World, names: tuple[str, ...], options: MujocoOptions,
                 observer: SensorObserver) -> None:
        self.observer, self.names, self.o = observer, names, options
        m = world.m
        self.links = [m.body(n).id for n in ARM_LINKS]
        self.bodies = [m.body(n).id for n in names]
        lidar = world.lidar
        n = lidar.o.beams
        self.increment = 2 * math.pi / n
        self.scanned = -1.0
        self.next_frame = 0.0
        self.renderer: mujoco.Renderer | None = None
        self.cameras = tuple(options.record_cameras)

    def __call__(self, w: World) -> None:
        t, d, obs = float(w.d.time), w.d, self.observer
        obs.base(t, w.base_pose())
        xyz, wxyz = d.xpos[self.bodies].tolist(), d.xquat[self.bodies].tolist()
        obs.bodies(t, [BodyPose(name, x, y, z, (qx, qy, qz, qw), name == w.held)
                       for name, (x, y, z), (qw, qx, qy, qz)
                       in zip(self.names, xyz, wxyz, strict=True)])
        obs.arm(t, ArmState(tuple(zip(ARM_JOINTS, w.arm_q().tolist(), strict=True)),
                            tuple(map(tuple, d.xpos[self.links].tolist())),
                            w.finger_opening()))
        last = w.lidar.last
        if last is not None and last[0] > self.scanned:
            self.scanned = last[0]
            lo = w.lidar.o
            obs.scan(last[0], Scan(last[1], lo.height_m, 0.0, self.increment, lo.range_m,
                                   last[2]))
        if self.cameras and t >= self.next_frame:
            # Half a report early, so that rounding never skips a report.
            self.next_frame = t + self.o.record_camera_s - 0.5 * self.o.record_dt_s
            self._frames(w, t)

    def _frames(self, w: World, t: float) -> None:
        if self.renderer is None:
            try:
                self.renderer = new_renderer(w.m, self.o.record_image_size)
            except BadInput as exc:
                # A recording without pictures is still a recording: say so once.
                log.warning("recording without camera frames: %s", exc)
                self.cameras = ()
                return
        for camera in self.cameras:
            image = render_with(self.renderer, w, "room", camera)
            self.observer.frame(t, CameraFrame(camera, image))

    def close(self) -> None:
        """Release the renderer."""
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None
