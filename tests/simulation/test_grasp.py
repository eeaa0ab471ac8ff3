"""The MuJoCo grasps, in real physics: ``fix`` holds only when both pads squeeze the object
(Gazebo grasp-fix's attach test); ``friction`` holds by contact friction alone, and a slip
is reported."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cli_support import one_line_error
from llm_grop.cli import main
from llm_grop.experiment.calibration import room
from llm_grop.planning.navigation import Navigator
from llm_grop.simulation.mujoco.options import BaseOptions, MujocoOptions
from llm_grop.simulation.mujoco.session import MujocoSession
from llm_grop.simulation.mujoco.simulator import MujocoSimulator
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import ObjectSource
from scenes import two_table_room


def _session(name: str, options: MujocoOptions | None = None) -> MujocoSession:
    """The robot facing the calibration table with ``name`` 0.55 m in front of it."""
    scene = room((ObjectSource(name, "dining table", 3.0, 1.85),), Pose2D(3.0, 1.3, math.pi / 2))
    return MujocoSimulator(options).session(scene, items_from_names([name], Catalog.load()),
                                     np.random.default_rng(0),
                                     replan=Navigator(scene, scene.robot.base_radius_m))


def test_pads_that_squeeze_attach_and_carry_it() -> None:
    s = _session("mug")
    step = s.pick("mug")
    assert step.ok and s.held == "mug"
    assert s.objects()["mug"].z > 0.9  # lifted to the carry posture, above the table


def test_taking_the_bottom_plate_of_a_pile_takes_the_top_one() -> None:
    # The plates of a pile are alike, so the plan may name any of them: the arm takes the
    # top one, as in the 2D simulator, and what stays is a pile of two.
    names = ["dinner plate", "dinner plate 2", "dinner plate 3"]
    scene = room(tuple(ObjectSource(n, "dining table", 3.0, 1.85, below)
                       for n, below in zip(names, [None, *names], strict=False)),
                 Pose2D(3.0, 1.3, math.pi / 2))
    s = MujocoSimulator().session(scene, items_from_names(["dinner plate"] * 3, Catalog.load()),
                                  np.random.default_rng(0),
                                  replan=Navigator(scene, scene.robot.base_radius_m))
    before = s.objects()
    step = s.pick("dinner plate")
    assert step.ok, step.note
    after = s.objects()
    assert after["dinner plate"].held
    # The top plate's place and the bottom one's were swapped before the grasp.
    assert (after["dinner plate 3"].on, after["dinner plate 3"].z) == (
        None, pytest.approx(before["dinner plate"].z, abs=0.005))
    assert (after["dinner plate 2"].on, after["dinner plate 2"].z) == (
        "dinner plate 3", pytest.approx(before["dinner plate 2"].z, abs=0.005))


def test_the_top_of_a_pile_of_six_plates_on_a_high_counter_is_picked() -> None:
    # Its rim is 1.04 m up: the arm cannot hold the hand a full approach (0.10 m) above
    # it, so it comes down from 0.05 m.
    names = ["dinner plate", *(f"dinner plate {k}" for k in range(2, 7))]
    scene = two_table_room(sources=tuple(
        ObjectSource(n, "counter", 0.45, 2.1, below)
        for n, below in zip(names, [None, *names], strict=False)))
    scene = replace(scene, tables=tuple(replace(t, height=0.9) if t.name == "counter" else t
                                        for t in scene.tables))
    s = MujocoSimulator().session(scene, items_from_names(["dinner plate"] * 6, Catalog.load()),
                                  np.random.default_rng(0),
                                  replan=Navigator(scene, scene.robot.base_radius_m))
    assert s.navigate(Pose2D(1.12, 2.1, math.pi)).ok
    step = s.pick("dinner plate 6")
    assert step.ok, step.note


def test_pads_that_touch_without_squeezing_do_not_attach() -> None:
    s = _session("mug")
    # Fingers too weak to press: they close onto the mug and touch it with under 1 N.
    fingers = [s.w.m.actuator(n).id for n in ("finger_left", "finger_right")]
    s.w.m.actuator_forcerange[fingers] = (-0.8, 0.8)
    step = s.pick("mug")
    assert not step.ok and step.reason == "grasp_missed"
    assert s.held is None
    assert s.objects()["mug"].z < 0.8  # still on the table


@pytest.mark.parametrize("kind", ["salad plate", "mug"])
def test_held_by_friction_a_plate_or_mug_carried_at_full_speed_stays_in_hand(kind: str) -> None:
    # A plate hangs from its rim, so the pads must resist its turning as well as its weight.
    s = _session(kind, MujocoOptions(grasp="friction"))
    assert s.pick(kind).ok
    for goal in (Pose2D(1.0, 0.6, math.pi), Pose2D(5.0, 0.6, 0.0)):
        step = s.navigate(goal)
        assert step.ok, step.note
    assert s.held == kind
    assert s.objects()[kind].z > 0.9


def test_held_by_friction_a_mug_shaken_harder_than_friction_allows_slips_and_is_reported(
        ) -> None:
    # A base that brakes and turns 40 to 80 times harder than the real one, and fingers
    # that squeeze with 2.5 N: more than the grip test's 2 N, far less than the drive needs.
    shaky = BaseOptions(accel_mps2=40.0, turn_accel_radps2=80.0, traction_n=50000.0)
    s = _session("mug", MujocoOptions(grasp="friction", base=shaky))
    fingers = [s.w.m.actuator(n).id for n in ("finger_left", "finger_right")]
    s.w.m.actuator_forcerange[fingers] = (-2.5, 2.5)
    step = s.pick("mug")
    if step.ok:
        step = s.navigate(Pose2D(1.0, 0.6, math.pi))
        assert not step.ok and step.reason == "fell"
        assert "dropped 'mug' in transit" in step.note
    else:
        assert step.reason == "grasp_missed" and "slipped" in step.note
    assert s.held is None
    assert not s.objects()["mug"].held


def test_grasp_friction_on_the_command_line(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "run.json"
    assert main(["run", "a mug", "--method", "grop", "--chairs", "0", "--simulator",
                 "mujoco", "--grasp", "friction", "--json", str(out), "-q"]) == 0
    doc = json.loads(out.read_text())
    assert doc["simulator"] == "mujoco" and doc["success"]


@pytest.mark.parametrize("command", ["run", "bench"])
def test_grasp_friction_needs_mujoco(command: str, tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    args = ["run", "a mug"] if command == "run" else \
        ["bench", "--tasks", "1", "--trials", "1", "--out", str(tmp_path / "b")]
    assert main([*args, "--grasp", "friction", "-q"]) == 2
    assert "--grasp friction: needs the mujoco simulator" in one_line_error(capsys)
    assert not (tmp_path / "b").exists()
