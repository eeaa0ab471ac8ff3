"""The episode stream as a ROS 2 bag (MCAP, CDR-encoded ``ros2msg`` schemas; the
``mcap`` and ``mcap-ros2-support`` libraries of the ``[ros]`` extra, no ROS needed).

Standard message types of ROS 2 Humble, stamped with simulated time (seconds since the
episode began, as nanoseconds since the epoch: ``ros2 bag play`` replays relative time):

- ``/tf`` (``tf2_msgs/TFMessage``): ``map`` → ``base_link`` and ``map`` → each object
  (its frame: its name with ``_`` for spaces), whenever they move; ``/tf_static``:
  ``base_link`` → ``laser``, the lidar's scan plane;
- ``/plan/path`` (``nav_msgs/Path``): each planned drive, in ``map``;
- ``/plan/goals`` (``geometry_msgs/PoseStamped``): each planned navigation goal in
  ``map``, a Nav2 ``NavigateToPose`` goal;
- ``/objects`` (``visualization_msgs/MarkerArray``): the tables, chairs and walls in
  ``map``, and each object in its own frame, in its kind's colour, with its name;
- ``/scan`` (``sensor_msgs/LaserScan``): the lidar's sweeps, where the simulator reports
  them (MuJoCo);
- ``/events`` (``std_msgs/String``): every attempt as one JSON object (the run JSON's step
  with ``t_s``, when it ended), and the episode's end.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Sequence
from dataclasses import asdict
from importlib import resources
from pathlib import Path
from typing import Any

import yaml
from mcap_ros2.writer import Writer

from llm_grop.recording.stream import (
    ArmState,
    BodyPose,
    CameraFrame,
    EpisodeEnd,
    EpisodeStart,
    ObjectShape,
    Scan,
)
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.kind_colors import TABLE_TOP, hex_rgb, kind_color
from llm_grop.world.plan import ExecutedStep
from llm_grop.world.scene import Scene

#: The fixed frame, and the base's.
MAP, BASE, LASER = "map", "base_link", "laser"
#: Marker types (``visualization_msgs/Marker``).
CUBE, CYLINDER = 1, 3
#: An object that moved less than this since its last transform is not sent again
#: (metres; a tenth of a degree for rotations).
STILL_M = 5e-4
_TYPES = {"tf": "tf2_msgs/msg/TFMessage", "path": "nav_msgs/msg/Path",
          "goal": "geometry_msgs/msg/PoseStamped",
          "markers": "visualization_msgs/msg/MarkerArray",
          "scan": "sensor_msgs/msg/LaserScan", "string": "std_msgs/msg/String"}


@functools.cache
def message_definitions() -> dict[str, str]:
    """Each message type's ROS 2 Humble definition with its dependencies
    (``ros2_msgs.yaml``), by type name (``tf2_msgs/msg/TFMessage``)."""
    text = resources.files("llm_grop.recording").joinpath("ros2_msgs.yaml").read_text("utf-8")
    return {str(k): str(v).strip() for k, v in yaml.safe_load(text).items()}


def frame_of(name: str) -> str:
    """An object's tf frame: its name with ``_`` for each space."""
    return name.replace(" ", "_")


def _stamp(t_s: float) -> dict[str, int]:
    ns = max(0, round(t_s * 1e9))
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _header(t_s: float, frame: str) -> dict[str, Any]:
    return {"stamp": _stamp(t_s), "frame_id": frame}


def _quat_yaw(theta: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(theta / 2), "w": math.cos(theta / 2)}


def _pose(x: float, y: float, z: float, q: dict[str, float]) -> dict[str, Any]:
    return {"position": {"x": x, "y": y, "z": z}, "orientation": q}


def _pose_stamped(t_s: float, pose: Pose2D) -> dict[str, Any]:
    return {"header": _header(t_s, MAP), "pose": _pose(pose.x, pose.y, 0.0,
                                                       _quat_yaw(pose.theta))}


def _transform(t_s: float, parent: str, child: str, xyz: Sequence[float],
               q: dict[str, float]) -> dict[str, Any]:
    return {"header": _header(t_s, parent), "child_frame_id": child,
            "transform": {"translation": dict(zip("xyz", map(float, xyz), strict=True)),
                          "rotation": q}}


def step_json(t_s: float, step: ExecutedStep) -> dict[str, Any]:
    """An attempt as the run JSON writes a step (poses as ``[x, y, theta]``, what is
    unset left out), with ``t_s``, the simulated second it ended."""
    out: dict[str, Any] = {"t_s": round(t_s, 6)}
    for key, value in asdict(step).items():
        if value is None or value == () or key == "note" and not value:
            continue
        if isinstance(value, dict):  # a Pose2D
            value = [value["x"], value["y"], value["theta"]]
        elif key == "path":
            value = [list(p) for p in value]
        out[key] = value
    return out


class McapSink:
    """Writes one episode to the ROS 2 bag ``path`` (see the module)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._file = open(path, "wb")  # noqa: SIM115 - closed by close()
        self.w = Writer(self._file)
        defs = message_definitions()
        self.schemas = {key: self.w.register_msgdef(name, defs[name])
                        for key, name in _TYPES.items()}
        self._last: dict[str, BodyPose] = {}
        self._seq: dict[str, int] = {}
        self._closed = False

    def _write(self, topic: str, kind: str, t_s: float, message: dict[str, Any]) -> None:
        ns = max(0, round(t_s * 1e9))
        n = self._seq.get(topic, 0)
        self._seq[topic] = n + 1
        self.w.write_message(topic, self.schemas[kind], message, log_time=ns, publish_time=ns,
                             sequence=n)

    # -- the episode ------------------------------------------------------------------
    def begin(self, start: EpisodeStart) -> None:
        self._write("/tf_static", "tf", 0.0, {"transforms": [_transform(
            0.0, BASE, LASER, (0.0, 0.0, 0.25), _quat_yaw(0.0))]})
        plan = start.plan
        for s in plan.steps:
            if s.action != "navigate" or s.goal is None:
                continue
            self._write("/plan/goals", "goal", 0.0, _pose_stamped(0.0, s.goal))
            self._write("/plan/path", "path", 0.0, {"header": _header(0.0, MAP), "poses": [
                _pose_stamped(0.0, Pose2D(x, y, 0.0)) for x, y in s.path]})
        self._write("/objects", "markers", 0.0, {"markers": [
            *_room_markers(start.scene),
            *(_object_marker(k, o) for k, o in enumerate(start.objects))]})
        self.base(0.0, start.scene.robot_start)

    def step(self, t_s: float, step: ExecutedStep) -> None:
        self._write("/events", "string", t_s, {"data": json.dumps(step_json(t_s, step))})

    def end(self, t_s: float, end: EpisodeEnd) -> None:
        self._write("/events", "string", t_s, {"data": json.dumps({
            "t_s": round(t_s, 6), "episode": "ended", "success": end.success,
            "execution_time_s": end.execution_time_s,
            "unplaced_reasons": dict(end.unplaced)})})

    # -- the stream -------------------------------------------------------------------
    def base(self, t_s: float, pose: Pose2D) -> None:
        self._write("/tf", "tf", t_s, {"transforms": [_transform(
            t_s, MAP, BASE, (pose.x, pose.y, 0.0), _quat_yaw(pose.theta))]})

    def bodies(self, t_s: float, poses: Sequence[BodyPose]) -> None:
        moved = []
        for p in poses:
            last = self._last.get(p.name)
            if last is not None and math.dist((p.x, p.y, p.z), (last.x, last.y, last.z)) \
                    < STILL_M and math.dist(p.quat_xyzw, last.quat_xyzw) < STILL_M:
                continue
            self._last[p.name] = p
            moved.append(_transform(t_s, MAP, frame_of(p.name), (p.x, p.y, p.z),
                                    dict(zip("xyzw", p.quat_xyzw, strict=True))))
        if moved:
            self._write("/tf", "tf", t_s, {"transforms": moved})

    def arm(self, t_s: float, arm: ArmState) -> None:
        """Not in the bag: a robot description (URDF) would be needed to show joints."""

    def scan(self, t_s: float, scan: Scan) -> None:
        n = len(scan.ranges_m)
        self._write("/scan", "scan", t_s, {
            "header": _header(t_s, LASER), "angle_min": scan.angle_min_rad,
            "angle_max": scan.angle_min_rad + scan.angle_increment_rad * (n - 1),
            "angle_increment": scan.angle_increment_rad, "time_increment": 0.0,
            "scan_time": 0.0, "range_min": 0.0, "range_max": scan.range_max_m,
            "ranges": scan.ranges_m.tolist(),
            "intensities": []})

    def frame(self, t_s: float, frame: CameraFrame) -> None:
        """Not in the bag (the Rerun recording holds the frames)."""

    def close(self) -> None:
        """Write the bag's summary and close the file."""
        if self._closed:
            return
        self._closed = True
        try:
            self.w.finish()
        finally:
            self._file.close()


def _color(hex_color: str, alpha: float = 1.0) -> dict[str, float]:
    r, g, b = hex_rgb(hex_color)
    return {"r": r, "g": g, "b": b, "a": alpha}


def _marker(ns: str, k: int, kind: int, frame: str, xyz: Sequence[float], yaw: float,
            scale: Sequence[float], color: dict[str, float], text: str = "") -> dict[str, Any]:
    return {"header": _header(0.0, frame), "ns": ns, "id": k, "type": kind, "action": 0,
            "pose": _pose(*map(float, xyz), _quat_yaw(yaw)),
            "scale": dict(zip("xyz", map(float, scale), strict=True)), "color": color,
            "lifetime": {"sec": 0, "nanosec": 0}, "frame_locked": True, "points": [],
            "colors": [], "texture_resource": "",
            "texture": {"header": _header(0.0, ""), "format": "", "data": b""},
            "uv_coordinates": [], "text": text, "mesh_resource": "",
            "mesh_file": {"filename": "", "data": b""}, "mesh_use_embedded_materials": False}


def _room_markers(scene: Scene) -> list[dict[str, Any]]:
    """The room's furniture as markers in ``map``: each table's top, each chair, each
    interior wall."""
    out = []
    for k, t in enumerate(scene.tables):
        b = t.box
        color = _color(TABLE_TOP if t.name == scene.target else "#966e46")
        out.append(_marker("tables", k, CYLINDER if t.is_round else CUBE, MAP,
                           (b.x, b.y, t.height - 0.015), b.yaw, (b.width, b.depth, 0.03),
                           color, t.name))
    for k, c in enumerate(scene.chairs):
        b = c.box
        out.append(_marker("chairs", k, CUBE, MAP, (b.x, b.y, 0.225), b.yaw,
                           (b.width, b.depth, 0.45), _color("#59402e", 0.6), c.name))
    for k, b in enumerate(scene.walls):
        out.append(_marker("walls", k, CUBE, MAP, (b.x, b.y, 0.5), b.yaw,
                           (b.width, b.depth, 1.0), _color("#dbd9d1")))
    return out


def _object_marker(k: int, o: ObjectShape) -> dict[str, Any]:
    """An object's shape in its own frame (its bottom centre), in its kind's colour."""
    sx, sy = o.size
    return _marker("objects", k, CYLINDER if o.shape == "circle" else CUBE, frame_of(o.name),
                   (0.0, 0.0, o.height / 2), 0.0, (sx, sy, o.height), _color(kind_color(o.kind)),
                   o.name)
