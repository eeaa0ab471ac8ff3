"""The episode stream as a Rerun recording (``.rrd``; the ``[viz]`` extra).

Everything is on the ``sim_time`` timeline (simulated seconds); the room is in metres,
z up. Entities:

- ``world/room`` (floor and walls), ``world/tables/<name>``, ``world/chairs/<name>``:
  boxes and cylinders, static;
- ``world/objects/<name>``: each object's shape in its kind's colour with its name,
  moved by its pose over time;
- ``world/robot``: the base's pose over time (its body and heading drawn under it);
  ``world/trajectory``: where the base has driven so far;
- ``world/plan/paths``, ``world/plan/standing``, ``world/plan/targets``: the planned
  paths, standing positions (numbered in the plan's order) and final places, static;
- ``plan``: the plan's summary (expected utility, feasibility, cost) and the
  arrangement's relations, static text; ``events``: every attempt as a log line,
  failed ones with their ``reason``;
- from a simulator that reports them: ``world/arm`` (the arm's links) and
  ``arm/joints/<name>`` (angles, radians), ``world/scan`` (the lidar's hits) and
  ``cameras/<name>`` (downsampled frames).

High-rate series are kept in memory and written as columns at :meth:`RerunSink.close`,
so the episode pays a list append per pose rather than a log call.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from llm_grop.recording.stream import (
    ArmState,
    BodyPose,
    CameraFrame,
    EpisodeEnd,
    EpisodeStart,
    ObjectShape,
    Scan,
)
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.kind_colors import TABLE_TOP, kind_color
from llm_grop.world.plan import ExecutedStep
from llm_grop.world.scene import Scene

#: The recording's application id: recordings of llm-grop episodes open side by side.
APPLICATION = "llm-grop"
#: The timeline every entity is on, simulated seconds.
TIMELINE = "sim_time"
#: Heights drawn, metres: the walls (as the 3D world builds them), a chair's seat, the
#: robot's body.
WALL_HEIGHT_M, SEAT_Z_M, BODY_HEIGHT_M = 1.0, 0.45, 0.4
#: An object that moved less than this since its last logged pose is not logged again
#: (metres; about a tenth of a degree for rotations).
STILL_M = 5e-4
#: JPEG quality of camera frames.
JPEG_QUALITY = 80
_GREY, _WALL, _WOOD, _CHAIR = (200, 200, 200), (219, 217, 209), (150, 110, 70), (89, 64, 46)
_ROBOT, _PATH, _FAILED = (70, 90, 140), (40, 120, 200), (220, 60, 50)


def _rgb(color: str) -> tuple[int, int, int]:
    h = color.lstrip("#")
    return (int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16))


def _entity(*parts: str) -> str:
    """An entity path of ``parts``, each escaped (object names have spaces)."""
    return "/".join(rr.escape_entity_path_part(p) for p in parts)


def _yaw(theta: float) -> rr.RotationAxisAngle:
    return rr.RotationAxisAngle(axis=(0.0, 0.0, 1.0), radians=theta)


class RerunSink:
    """Writes one episode to the Rerun recording ``path`` (see the module)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.rec = rr.RecordingStream(APPLICATION)
        self.rec.save(str(path))
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self._transforms: dict[str, list[tuple[float, tuple[float, ...], tuple[float, ...]]]]
        self._transforms = defaultdict(list)
        self._scalars: dict[str, list[tuple[float, float]]] = defaultdict(list)
        self._strips: dict[str, list[tuple[float, np.ndarray]]] = defaultdict(list)
        self._points: dict[str, list[tuple[float, np.ndarray]]] = defaultdict(list)
        self._last: dict[str, BodyPose] = {}
        self._trail: list[tuple[float, float]] = []
        self._closed = False

    def _at(self, t_s: float) -> None:
        self.rec.set_time(TIMELINE, duration=t_s)

    # -- the episode ------------------------------------------------------------------
    def begin(self, start: EpisodeStart) -> None:
        self.rec.send_recording_name(
            f"{start.method} task {start.task} seed {start.seed} ({start.simulator})"
            if start.task is not None else f"{start.method} seed {start.seed} "
                                           f"({start.simulator})")
        self.rec.send_blueprint(_layout(start.streams))
        self._room(start.scene)
        for shape in start.objects:
            self._object(shape)
        self._robot(start.scene)
        self._plan(start)
        self._trail.append((start.scene.robot_start.x, start.scene.robot_start.y))

    def step(self, t_s: float, step: ExecutedStep) -> None:
        what = f"{step.action} {step.object or ''}".strip()
        if step.ok:
            text, level = f"{what}: ok ({step.duration_s:.1f} s)", "INFO"
        else:
            text = f"{what} (attempt {step.attempt}): failed, {step.reason or 'refused'}" \
                   + (f": {step.note}" if step.note else "") + f" ({step.duration_s:.1f} s)"
            level = "WARN"
        self._at(t_s)
        self.rec.log("events", rr.TextLog(text, level=level))
        if step.action == "navigate" and step.path:
            self._trail.extend(step.path[1:])
            self.rec.log("world/trajectory", rr.LineStrips3D(
                [[(x, y, 0.01) for x, y in self._trail]], colors=[_ROBOT], radii=[0.01]))

    def end(self, t_s: float, end: EpisodeEnd) -> None:
        self._at(t_s)
        why = ", ".join(f"{n}: {r}" for n, r in end.unplaced)
        self.rec.log("events", rr.TextLog(
            f"episode ended: {'success' if end.success else 'failed'} after "
            f"{end.execution_time_s:.1f} s" + (f" ({why} not placed)" if why else ""),
            level="INFO" if end.success else "WARN"))

    # -- the stream -------------------------------------------------------------------
    def base(self, t_s: float, pose: Pose2D) -> None:
        self._transforms["world/robot"].append(
            (t_s, (pose.x, pose.y, 0.0), (0.0, 0.0, math.sin(pose.theta / 2),
                                           math.cos(pose.theta / 2))))

    def bodies(self, t_s: float, poses: Sequence[BodyPose]) -> None:
        for p in poses:
            last = self._last.get(p.name)
            if last is not None and math.dist((p.x, p.y, p.z), (last.x, last.y, last.z)) \
                    < STILL_M and math.dist(p.quat_xyzw, last.quat_xyzw) < STILL_M:
                continue
            self._last[p.name] = p
            self._transforms[_entity("world", "objects", p.name)].append(
                (t_s, (p.x, p.y, p.z), p.quat_xyzw))

    def arm(self, t_s: float, arm: ArmState) -> None:
        self._strips["world/arm"].append((t_s, np.asarray(arm.links, dtype=np.float32)))
        for name, angle in arm.joints:
            self._scalars[_entity("arm", "joints", name)].append((t_s, angle))
        self._scalars["arm/fingers_m"].append((t_s, arm.fingers_m))

    def scan(self, t_s: float, scan: Scan) -> None:
        xy = scan.points()
        self._points["world/scan"].append(
            (t_s, np.column_stack([xy, np.full(len(xy), scan.height_m)]).astype(np.float32)))

    def frame(self, t_s: float, frame: CameraFrame) -> None:
        self._at(t_s)
        self.rec.log(_entity("cameras", frame.camera),
                     rr.Image(frame.image).compress(jpeg_quality=JPEG_QUALITY))

    def close(self) -> None:
        """Write the buffered series and finish the file."""
        if self._closed:
            return
        self._closed = True
        try:
            self._flush_series()
        finally:
            self.rec.flush()
            self.rec.disconnect()

    def _flush_series(self) -> None:
        rec = self.rec
        for entity, rows in self._transforms.items():
            rec.send_columns(entity, indexes=[_times(rows)], columns=rr.Transform3D.columns(
                translation=[r[1] for r in rows], quaternion=[r[2] for r in rows]))
        for entity, values in self._scalars.items():
            rec.send_columns(entity, indexes=[_times(values)],
                             columns=rr.Scalars.columns(scalars=[v for _, v in values]))
        for entity, strips in self._strips.items():
            rec.send_columns(entity, indexes=[_times(strips)], columns=rr.LineStrips3D.columns(
                strips=[s for _, s in strips]))
        for entity, clouds in self._points.items():
            points = np.concatenate([c for _, c in clouds]) if clouds else np.zeros((0, 3))
            rec.send_columns(entity, indexes=[_times(clouds)], columns=rr.Points3D.columns(
                positions=points).partition([len(c) for _, c in clouds]))

    # -- what does not move -----------------------------------------------------------
    def _room(self, scene: Scene) -> None:
        log, w, d, t = self.rec.log, scene.width, scene.depth, 0.05
        log("world/room/floor", rr.Boxes3D(centers=[(w / 2, d / 2, -0.005)],
                                           half_sizes=[(w / 2, d / 2, 0.005)],
                                           colors=[_GREY]), static=True)
        outer = [Box(w / 2, -t / 2, w + 2 * t, t), Box(w / 2, d + t / 2, w + 2 * t, t),
                 Box(-t / 2, d / 2, t, d), Box(w + t / 2, d / 2, t, d)]
        walls = [*outer, *scene.walls]
        log("world/room/walls", rr.Boxes3D(
            centers=[(b.x, b.y, WALL_HEIGHT_M / 2) for b in walls],
            half_sizes=[(b.width / 2, b.depth / 2, WALL_HEIGHT_M / 2) for b in walls],
            rotation_axis_angles=[_yaw(b.yaw) for b in walls], colors=[_WALL]), static=True)
        for table in scene.tables:
            b, h = table.box, table.height
            color = _rgb(TABLE_TOP) if table.name == scene.target else _WOOD
            entity = _entity("world", "tables", table.name)
            if table.is_round:
                log(entity, rr.Cylinders3D(
                    lengths=[0.03, h - 0.03], radii=[b.width / 2, 0.05],
                    centers=[(b.x, b.y, h - 0.015), (b.x, b.y, (h - 0.03) / 2)],
                    colors=[color, _WOOD], labels=[table.name, ""]), static=True)
                continue
            legs = [b.to_room(sx * (b.width / 2 - 0.05), sy * (b.depth / 2 - 0.05))
                    for sx in (-1, 1) for sy in (-1, 1)]
            log(entity, rr.Boxes3D(
                centers=[(b.x, b.y, h - 0.015), *((x, y, (h - 0.03) / 2) for x, y in legs)],
                half_sizes=[(b.width / 2, b.depth / 2, 0.015),
                            *[(0.025, 0.025, (h - 0.03) / 2)] * 4],
                rotation_axis_angles=[_yaw(b.yaw)] * 5, colors=[color, *[_WOOD] * 4],
                labels=[table.name, *[""] * 4]), static=True)
        for chair in scene.chairs:
            b = chair.box
            log(_entity("world", "chairs", chair.name), rr.Boxes3D(
                centers=[(b.x, b.y, SEAT_Z_M / 2)],
                half_sizes=[(b.width / 2, b.depth / 2, SEAT_Z_M / 2)],
                rotation_axis_angles=[_yaw(b.yaw)], colors=[_CHAIR], labels=[chair.name],
                fill_mode="transparentfillmajorwireframe"), static=True)

    def _object(self, shape: ObjectShape) -> None:
        color, (sx, sy), h = _rgb(kind_color(shape.kind)), shape.size, shape.height
        entity = _entity("world", "objects", shape.name)
        if shape.shape == "circle":
            self.rec.log(entity, rr.Cylinders3D(lengths=[h], radii=[sx / 2],
                                                centers=[(0, 0, h / 2)], colors=[color],
                                                labels=[shape.name]), static=True)
        else:
            self.rec.log(entity, rr.Boxes3D(half_sizes=[(sx / 2, sy / 2, h / 2)],
                                            centers=[(0, 0, h / 2)], colors=[color],
                                            labels=[shape.name]), static=True)

    def _robot(self, scene: Scene) -> None:
        r = scene.robot.base_radius_m
        self.rec.log("world/robot/body", rr.Cylinders3D(
            lengths=[BODY_HEIGHT_M], radii=[r], centers=[(0, 0, BODY_HEIGHT_M / 2)],
            colors=[_ROBOT], labels=["robot"], fill_mode="transparentfillmajorwireframe"),
            static=True)
        self.rec.log("world/robot/heading", rr.Arrows3D(
            origins=[(0, 0, BODY_HEIGHT_M)], vectors=[(r, 0, 0)], colors=[_ROBOT]),
            static=True)

    def _plan(self, start: EpisodeStart) -> None:
        log, plan, scene = self.rec.log, start.plan, start.scene
        legs = [s for s in plan.steps if s.action == "navigate" and s.path]
        log("world/plan/paths", rr.LineStrips3D(
            [[(x, y, 0.02) for x, y in s.path] for s in legs], colors=[_PATH], radii=[0.008],
            labels=[f"to {s.object}" for s in legs]), static=True)
        stands = [(s.object or "", s.standing) for s in plan.steps
                  if s.action == "place" and s.standing is not None]
        if stands:
            log("world/plan/standing", rr.Arrows3D(
                origins=[(p.x, p.y, 0.03) for _, p in stands],
                vectors=[(0.25 * math.cos(p.theta), 0.25 * math.sin(p.theta), 0.0)
                         for _, p in stands],
                colors=[_PATH], labels=[f"{k} {name}" for k, (name, _) in
                                        enumerate(stands, start=1)]), static=True)
        table_z = scene.target_table.height
        targets = [(p, scene.table_to_room(p.x, p.y, p.yaw)) for p in plan.configuration]
        if targets:
            log("world/plan/targets", rr.Boxes3D(
                centers=[(q.x, q.y, table_z + 0.002) for _, q in targets],
                half_sizes=[(p.size[0] / 2, p.size[1] / 2, 0.002) for p, _ in targets],
                rotation_axis_angles=[_yaw(q.theta) for _, q in targets],
                colors=[_rgb(kind_color(p.kind or p.name)) for p, _ in targets],
                fill_mode="majorwireframe"), static=True)
        log("plan", rr.TextDocument(_summary(start), media_type="text/markdown"), static=True)
        log("plan", rr.AnyValues(expected_utility=plan.utility, feasibility=plan.feasibility,
                                 expected_cost_s=plan.cost_s,
                                 configuration_index=plan.configuration_index), static=True)
        log("plan/relations", rr.TextDocument(
            "\n".join(f"- {r.sentence()}" for r in start.relations) or "(none)",
            media_type="text/markdown"), static=True)


def _layout(streams: frozenset[str]) -> rrb.Blueprint:
    """The viewer's layout: the room in 3D beside the plan and the attempts, with the
    simulator's camera frames and arm joints where it reports them."""
    side: list[rrb.View | rrb.Tabs] = [
        rrb.Tabs(rrb.TextDocumentView(origin="/plan", contents="$origin", name="plan"),
                 rrb.TextDocumentView(origin="/plan/relations", name="relations")),
        rrb.TextLogView(origin="/events", name="events")]
    if "camera" in streams:
        side.insert(0, rrb.Spatial2DView(origin="/cameras", name="cameras"))
    if "arm" in streams:
        side.append(rrb.TimeSeriesView(origin="/arm", name="arm"))
    return rrb.Blueprint(rrb.Horizontal(rrb.Spatial3DView(origin="/world", name="room"),
                                        rrb.Vertical(*side), column_shares=[3, 2]),
                         collapse_panels=False)


def _times(rows: Sequence[tuple[float, object]] | Sequence[tuple[float, ...]]
           ) -> rr.TimeColumn:
    return rr.TimeColumn(TIMELINE, duration=[r[0] for r in rows])


def _summary(start: EpisodeStart) -> str:
    """The plan in a few lines of Markdown."""
    p = start.plan
    lines = [f"# {start.request}", "",
             f"- method: {start.method}" + (f", task {start.task}" if start.task else "")
             + f", seed {start.seed}",
             f"- simulator: {start.simulator}; planner's belief: {start.feasibility}",
             f"- configuration {p.configuration_index} of {p.configurations_considered} "
             "(from 0)",
             f"- expected utility {p.utility:.2f}, feasibility {p.feasibility:.3f}, "
             f"cost {p.cost_s:.1f} s",
             f"- order: {', '.join(p.order)}"]
    if p.expected_duration_s is not None:
        lines.append(f"- expected duration {p.expected_duration_s:.1f} s")
    return "\n".join(lines)
