"""One episode stream to many sinks: :class:`Episode`, what the executive and a simulator
report to, and what opens the sinks a run's settings ask for (:func:`open_episode`)."""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Sequence
from pathlib import Path

from llm_grop.errors import BadInput
from llm_grop.recording.stream import (
    ArmState,
    BodyPose,
    CameraFrame,
    EpisodeEnd,
    EpisodeStart,
    Scan,
    Sink,
)
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, Point

log = logging.getLogger(__name__)

#: Simulated seconds between two poses of a drive whose simulator does not report its base
#: while it moves (the 2D one): the drive is drawn along its path at this rate.
MOTION_DT_S = 0.2
#: What installs each recording's library (the optional extra, and its size).
EXTRAS = {"rerun": "[viz] extra (Rerun, about 170 MB): pip install 'llm-grop[viz]'",
          "mcap": "[ros] extra (mcap, mcap-ros2-support): pip install 'llm-grop[ros]'"}
#: The module each recording's library is imported as, and each file's suffix.
MODULES = {"rerun": "rerun", "mcap": "mcap_ros2"}
SUFFIXES = {"rerun": ".rrd", "mcap": ".mcap"}


class Episode:
    """The episode stream fanned out to ``sinks``, in order. Where the simulator does not
    report the base while it drives (no ``base`` among its streams), each drive is filled
    in here along the path it took, a pose every :data:`MOTION_DT_S` simulated seconds,
    with what the hand holds riding along. :meth:`close` finishes every sink."""

    def __init__(self, sinks: Sequence[Sink]) -> None:
        self.sinks = tuple(sinks)
        self.streams: frozenset[str] = frozenset()
        self._pose: Pose2D | None = None
        self._held: dict[str, BodyPose] = {}
        #: The latest simulated time reported (the end comes no earlier).
        self._t = 0.0

    # -- from the executive -----------------------------------------------------------
    def begin(self, start: EpisodeStart) -> None:
        self.streams = start.streams
        self._pose = start.scene.robot_start
        for s in self.sinks:
            s.begin(start)

    def step(self, t_s: float, step: ExecutedStep) -> None:
        self._t = max(self._t, t_s)
        if step.action == "navigate" and "base" not in self.streams:
            self._drive(t_s, step)
        for s in self.sinks:
            s.step(t_s, step)

    def end(self, t_s: float, end: EpisodeEnd) -> None:
        # The sum of the steps' rounded durations may fall a microsecond short of the
        # session's clock: the end is never before what came before it.
        t_s = max(t_s, self._t)
        for s in self.sinks:
            s.end(t_s, end)

    # -- from the session (or the executive) ------------------------------------------
    def base(self, t_s: float, pose: Pose2D) -> None:
        self._pose, self._t = pose, max(self._t, t_s)
        for s in self.sinks:
            s.base(t_s, pose)

    def bodies(self, t_s: float, poses: Sequence[BodyPose]) -> None:
        self._held = {p.name: p for p in poses if p.held}
        for s in self.sinks:
            s.bodies(t_s, poses)

    def arm(self, t_s: float, arm: ArmState) -> None:
        for s in self.sinks:
            s.arm(t_s, arm)

    def scan(self, t_s: float, scan: Scan) -> None:
        for s in self.sinks:
            s.scan(t_s, scan)

    def frame(self, t_s: float, frame: CameraFrame) -> None:
        for s in self.sinks:
            s.frame(t_s, frame)

    def close(self) -> None:
        """Finish every sink's file; the first failure is raised once all were tried."""
        failed: BaseException | None = None
        for s in self.sinks:
            try:
                s.close()
            except Exception as exc:  # noqa: BLE001 - the others still get finished
                failed = failed or exc
        if failed is not None:
            raise failed

    # -- filling in a drive -----------------------------------------------------------
    def _drive(self, t_s: float, step: ExecutedStep) -> None:
        """Poses along ``step``'s driven path over its duration, ending before ``t_s``
        (where the executive reports where the base stopped)."""
        if len(step.path) < 2 or step.duration_s <= 0:
            return
        start = t_s - step.duration_s
        n = int(step.duration_s / MOTION_DT_S)
        for k in range(1, n):
            t = start + k * MOTION_DT_S
            pose = along(step.path, k / n)
            for s in self.sinks:
                s.base(t, pose)
            if self._held:
                riding = [BodyPose(b.name, pose.x, pose.y, b.z, _yaw_quat(pose.theta), True)
                          for b in self._held.values()]
                for s in self.sinks:
                    s.bodies(t, riding)


def along(path: Sequence[Point], fraction: float) -> Pose2D:
    """The pose ``fraction`` (0 to 1) of the way along ``path`` by length, heading along
    the segment it lies on."""
    segments = [(a, b, math.dist(a, b)) for a, b in zip(path, path[1:], strict=False)]
    segments = [s for s in segments if s[2] > 0] or [(path[0], path[-1], 0.0)]
    left = fraction * sum(length for *_, length in segments)
    for a, b, length in segments:
        if left <= length:
            f = left / length if length else 1.0
            return Pose2D(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]),
                          math.atan2(b[1] - a[1], b[0] - a[0]))
        left -= length
    a, b, _ = segments[-1]
    return Pose2D(b[0], b[1], math.atan2(b[1] - a[1], b[0] - a[0]))


def _yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def check_extra(kind: str) -> None:
    """:class:`BadInput` naming the setting ``kind`` (``rerun``, ``mcap``) when the library
    that
    writes its recordings is not installed (found without importing it)."""
    import importlib.util

    if importlib.util.find_spec(MODULES[kind]) is None:
        raise BadInput(f"needs the optional {EXTRAS[kind]}", param=kind)


def check_recording(kind: str, path: str | os.PathLike[str] | None) -> None:
    """:class:`BadInput` naming the setting ``kind`` (``rerun``) when its recording cannot
    be written to ``path``: the library's extra is not installed, the name lacks its
    suffix, or the directory does not exist or is not writable. Checked before any
    work."""
    if path is None:
        return
    suffix = SUFFIXES[kind]
    p = Path(path)
    check_extra(kind)
    if p.suffix.lower() != suffix:
        raise BadInput(f"{p}: a recording's name ends in {suffix}", param=kind)
    parent = p.expanduser().resolve().parent
    if p.is_dir():
        raise BadInput(f"{p}: is a directory; give a file name", param=kind)
    if not parent.is_dir():
        raise BadInput(f"{p}: directory {parent} does not exist", param=kind)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise BadInput(f"{p}: directory {parent} is not writable", param=kind)
    if p.exists() and not os.access(p, os.W_OK):
        raise BadInput(f"{p}: the file is not writable", param=kind)


def open_episode(*, rerun: str | os.PathLike[str] | None = None,
                 mcap: str | os.PathLike[str] | None = None) -> Episode | None:
    """The episode stream to the recordings asked for (``rerun``: a Rerun recording's
    path, ``mcap``: a ROS 2 bag's), each checked first (:func:`check_recording`);
    ``None`` when none is."""
    check_recording("rerun", rerun)
    check_recording("mcap", mcap)
    sinks: list[Sink] = []
    try:
        if rerun is not None:
            from llm_grop.recording.rerun_sink import RerunSink

            sinks.append(RerunSink(Path(rerun)))
        if mcap is not None:
            from llm_grop.recording.mcap_sink import McapSink

            sinks.append(McapSink(Path(mcap)))
    except BaseException:
        Episode(sinks).close()
        raise
    return Episode(sinks) if sinks else None
