"""The robot's tray: its declaration, loading and unloading in 2D, riding and sliding in
real MuJoCo physics, trips through the executive in both simulators, and capacity's bad
input."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from cli_support import one_line_error
from llm_grop.api import run
from llm_grop.cli import main
from llm_grop.errors import BadInput
from llm_grop.files.scene_file import load_scene
from llm_grop.settings import RunSettings
from llm_grop.simulation.kinematic2d import Kinematic2D
from llm_grop.simulation.mujoco.arm import ArmIK
from llm_grop.simulation.mujoco.drive import follow
from llm_grop.simulation.mujoco.options import BaseOptions, LidarOptions
from llm_grop.simulation.mujoco.simulator import MujocoSimulator
from llm_grop.simulation.mujoco.tableware import tableware
from llm_grop.simulation.mujoco.world import World
from llm_grop.simulation.mujoco.world_model import TRAY_TOP, ObjectStart, build
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.request import items_from_names
from llm_grop.world.robot import Robot
from llm_grop.world.scene import Scene
from llm_grop.world.tray import load_tray
from scenes import placement, two_table_room

SETTING = "a dinner plate, a dinner fork, a dinner knife and a water cup"


def _footprint(name: str) -> tuple[str, tuple[float, float]]:
    spec = Catalog.load().resolve(name)
    return spec.shape, spec.size


def test_the_tray_declares_four_and_holds_a_place_setting() -> None:
    tray = load_tray()
    assert tray.capacity == 4 == Kinematic2D().tray_capacity() == MujocoSimulator().tray_capacity()
    names = ["dinner plate", "dinner fork", "dinner knife", "water cup"]
    slots = tray.assign([_footprint(n) for n in names])
    assert slots is not None and len(set(slots)) == 4
    # One large slot: two dinner plates do not fit side by side.
    assert tray.assign([_footprint("dinner plate")] * 2) is None
    assert tray.assign([_footprint("water cup")] * 5) is None  # more than it holds
    # Every slot lies inside the rim.
    for s in tray.slots:
        assert math.hypot(s.x, s.y) + min(s.half_x, s.half_y) <= tray.radius_m


@pytest.mark.parametrize("simulator", [Kinematic2D(), MujocoSimulator()])
def test_capacity_above_the_tray_is_one_line_before_any_work(simulator) -> None:  # type: ignore[no-untyped-def]
    scene = replace(two_table_room(), robot=Robot(capacity=5))
    with pytest.raises(BadInput, match=r"^robot.capacity: 5 objects per trip is more than "
                                       r"simulator '\w+' can carry \(its tray holds 4\)$"):
        simulator.check(scene)
    simulator.check(replace(two_table_room(), robot=Robot(capacity=4)))


def test_capacity_below_one_is_bad_input() -> None:
    with pytest.raises(BadInput, match="capacity"):
        RunSettings(capacity=0)
    with pytest.raises(BadInput, match="robot.capacity: must be at least 1"):
        Robot(capacity=0)


@pytest.mark.parametrize("flag, words", [
    ("0", "'--capacity': 0 is not in the range x>=1"),
    ("5", "robot.capacity: 5 objects per trip is more than simulator 'kinematic2d'")])
def test_cli_capacity_one_line(capsys, flag: str, words: str) -> None:  # type: ignore[no-untyped-def]
    assert main(["run", "a dinner plate", "--method", "grop", "--capacity", flag, "-q"]) == 2
    assert words in one_line_error(capsys)


def test_2d_load_rides_and_unload() -> None:
    scene = replace(two_table_room(), robot=Robot(capacity=4))
    items = items_from_names(["dinner plate", "dinner fork"], Catalog.load())
    s = Kinematic2D().session(scene, items, np.random.default_rng(0), replan=None)  # type: ignore[arg-type]
    s.pose = Pose2D(1.0, 2.0, math.pi)  # facing the counter, in reach of both
    assert s.fits_tray(["dinner plate", "dinner fork"])
    assert s.pick("dinner plate").ok
    load = s.load("dinner plate")
    assert load.action == "place" and load.tray and load.ok
    assert s.held is None and s.objects()["dinner plate"].tray
    assert s.pick("dinner fork").ok and s.load("dinner fork").ok
    s.pose = Pose2D(2.4, 2.0, 0.0)  # drove to the dining table: the tray came along
    plate = s.objects()["dinner plate"]
    assert plate.tray and not plate.held and plate.table is None
    assert math.hypot(plate.x - 2.4, plate.y - 2.0) < 0.3
    unload = s.unload("dinner plate")
    assert unload.action == "pick" and unload.tray and unload.ok and s.held == "dinner plate"
    # One object in the hand at a time: unloading another is refused.
    assert not s.unload("dinner fork").ok
    seconds = Kinematic2D().options.outcomes.attempt_time_s("place", scene.robot)
    assert load.duration_s == pytest.approx(seconds)


def _counts(steps, tray: bool) -> int:  # type: ignore[no-untyped-def]
    return sum(s.tray == tray for s in steps)


def _quick() -> Scene:
    """The packaged scene with a robot whose picks and places (so loads and unloads) are
    quick, so that the planner's trips pay for their loads."""
    base = load_scene()
    return replace(base, robot=replace(base.robot, pick_time_s=0.1, place_time_s=0.1))


def test_2d_trips_through_the_executive_and_capacity_one_unchanged() -> None:
    quick = _quick()
    four = run(SETTING, method="grop", seed=0, chairs=0, capacity=4, scene=quick)
    one = run(SETTING, method="grop", seed=0, chairs=0, scene=quick)
    assert four.success and one.success
    assert any(len(t) > 1 for t in four.execution.trips)
    loaded = {s.object for s in four.execution.steps if s.tray and s.action == "place" and s.ok}
    several = {n for t in four.execution.trips if len(t) > 1 for n in t}
    assert loaded == several
    assert all(len(t) == 1 for t in one.execution.trips)
    assert _counts(one.execution.steps, True) == 0


#: Where the test's base starts, facing +x.
START = Pose2D(2.0, 1.0, 0.0)


def _world(starts_on_tray: list[str], start: Pose2D = START) -> World:
    """The test room with the tray on the base, ``starts_on_tray`` in its slots, the base
    at ``start`` facing +x."""
    tray = load_tray()
    scene = replace(two_table_room(), robot=Robot(capacity=4), robot_start=start)
    fits = tray.assign([_footprint(n) for n in starts_on_tray])
    assert fits is not None
    starts = []
    for name, k in zip(starts_on_tray, fits, strict=True):
        slot = tray.slots[k]
        spec = Catalog.load().resolve(name)
        p = placement(name, 0.0, 0.0, spec.shape, spec.size)
        item = tableware(replace(p, kind=spec.name, height=spec.height))
        yaw = slot.yaw(spec.shape, spec.size) or 0.0
        starts.append(ObjectStart(item, start.x + slot.x, start.y + slot.y,
                                  tray.top_z_m + 0.002, yaw))
    wm = build(scene, starts, tray=True)
    return World(wm, scene, ArmIK(), lidar=LidarOptions(), speed_mps=0.5,
                 turn_speed_radps=1.0)


def _offsets(w: World, names: list[str]) -> np.ndarray:
    """Where each object lies in the base's frame (metres)."""
    b = w.base_pose()
    c, s = math.cos(b.theta), math.sin(b.theta)
    out = []
    for n in names:
        p = w.object_pose(n)
        dx, dy = p.x - b.x, p.y - b.y
        out.append((c * dx + s * dy, -s * dx + c * dy))
    return np.array(out)


RIDERS = ["dinner plate", "dinner knife", "water cup"]


def test_objects_ride_a_normal_drive_in_mujoco() -> None:
    w = _world(RIDERS)
    before = _offsets(w, RIDERS)
    top = w.top_z(TRAY_TOP)
    drive = follow(w, [(2.0, 1.0), (3.2, 1.0)], Pose2D(3.2, 1.0, 0.0), BaseOptions())
    assert drive.ok
    moved = np.linalg.norm(_offsets(w, RIDERS) - before, axis=1)
    assert moved.max() < 0.01, moved
    for n in RIDERS:
        p = w.object_pose(n)
        assert p.tilt < 0.1 and abs(p.z - top) < 0.01


def _bump(w: World) -> None:
    """Up to 0.6 m/s gently, then on into the room's east wall: a hard stop."""
    for k in range(1, 26):
        w.command_base(0.6 * k / 25, 0.0)
        w.advance(0.04)
    w.advance(2.5)
    w.command_base(0.0, 0.0)
    w.advance(1.0)


def test_a_hard_stop_moves_what_rides_in_mujoco() -> None:
    w = _world(RIDERS, Pose2D(4.6, 1.0, 0.0))
    before = _offsets(w, RIDERS)
    _bump(w)
    assert w.base_pose().x > 5.6  # against the wall (x = 6 m)
    moved = np.linalg.norm(_offsets(w, RIDERS) - before, axis=1)
    assert moved.max() > 0.01, moved
    again = _world(RIDERS, Pose2D(4.6, 1.0, 0.0))  # the same physics, the same slide
    _bump(again)
    assert np.allclose(_offsets(again, RIDERS), _offsets(w, RIDERS), atol=1e-9)


def test_mujoco_trip_loads_and_unloads_with_the_arm() -> None:
    # The default belief, which takes the robot's quick times (the fitted one has its own).
    result = run(SETTING, method="grop", seed=0, chairs=0, capacity=4, scene=_quick(),
                 feasibility="default", simulator=MujocoSimulator())
    ex = result.execution
    placed = {p.name for p in result.final.placements} - set(ex.unplaced)

    def carried(trip: tuple[str, ...]) -> bool:
        """Every object of ``trip`` loaded, unloaded and placed."""
        for name in trip:
            mine = [s for s in ex.steps if s.object == name and s.tray and s.ok]
            if {s.action for s in mine} != {"place", "pick"} or name not in placed:
                return False
        return True

    assert any(len(t) > 1 and carried(t) for t in ex.trips), (ex.trips, ex.unplaced_reasons)
    # At this seed the knife's first slot (on the tray's left) takes the elbow into the
    # wall beside the robot; the load goes on to another free slot, and every trip rides.
    assert all(carried(t) for t in ex.trips if len(t) > 1), (ex.trips, ex.unplaced_reasons)
    knife = [s for s in ex.steps if s.object == "dinner knife" and s.tray
             and s.action == "place"]
    assert [s.ok for s in knife] == [True] and "contact" in knife[0].note, knife
