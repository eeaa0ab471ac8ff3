"""Top-down PNG pictures of a run (room map, trajectory, final setting), read back."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from llm_grop.errors import BadInput
from llm_grop.render.room import FIGSIZE_IN, draw_run
from llm_grop.render.table import DPI
from llm_grop.world.arrangement import Arrangement, Placement
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.plan import ExecutedStep, Execution, Plan, RunResult, Step
from llm_grop.world.relation import Relation
from llm_grop.world.scene import Chair, ObjectSource, Scene, SceneTable
from llm_grop.world.table import Table

REQUEST = "set the table with a dinner plate and a dinner fork"
PLATE = Placement("dinner plate", 0.0, -0.1, 0.0, "circle", (0.27, 0.27), None, "dinner plate")
FORK = Placement("dinner fork", -0.17, -0.1, 0.0, "box", (0.025, 0.2), None, "dinner fork")
RELATIONS = (Relation("dinner fork", "to the left of", "dinner plate"),)

SCENE = Scene(
    name="two tables",
    width=6.0,
    depth=4.0,
    tables=(SceneTable("dining", Box(4.0, 2.0, 1.2, 0.8)),
            SceneTable("counter", Box(1.0, 3.3, 1.4, 0.6))),
    target="dining",
    robot_start=Pose2D(1.0, 1.0, 0.0),
    walls=(Box(2.5, 3.6, 0.1, 0.8),),
    sources=(ObjectSource("dinner plate", "counter", 0.8, 3.3),
             ObjectSource("dinner fork", "counter", 1.2, 3.3)),
    chairs=(Chair("chair 1", Box(4.0, 1.2, 0.45, 0.45)),),
)
PICK_AT = Pose2D(1.0, 2.55, math.pi / 2)
PLACE_AT = Pose2D(4.0, 2.95, -math.pi / 2)
TO_COUNTER = ((1.0, 1.0), (1.0, 1.8), (1.0, 2.55))
TO_TABLE = ((1.0, 2.55), (2.0, 2.2), (3.2, 2.6), (4.0, 2.95))
BLOCKED = ((1.0, 2.55), (1.8, 1.6), (2.4, 1.3))


def run_result(steps: tuple[ExecutedStep, ...], unplaced: tuple[str, ...] = ()) -> RunResult:
    planned = Arrangement(REQUEST, Table(1.2, 0.8), (PLATE, FORK), RELATIONS)
    final = Arrangement(REQUEST, Table(1.2, 0.8),
                        tuple(p for p in (PLATE, FORK) if p.name not in unplaced), RELATIONS)
    plan = Plan(
        order=("dinner plate", "dinner fork"),
        steps=(Step("navigate", "dinner plate", goal=PICK_AT, path=TO_COUNTER, duration_s=4.0),
               Step("pick", "dinner plate", standing=PICK_AT, duration_s=8.0),
               Step("navigate", "dinner plate", goal=PLACE_AT, path=TO_TABLE, duration_s=7.0),
               Step("place", "dinner plate", standing=PLACE_AT, pose=(0.0, -0.1, 0.0))),
        configuration=(PLATE, FORK), configuration_index=0, utility=12.5, feasibility=0.9,
        cost_s=27.0, configurations_considered=3)
    execution = Execution(steps=steps, final=final.placements, unplaced=unplaced,
                          execution_time_s=sum(s.duration_s for s in steps),
                          robot_end=PLACE_AT)
    return RunResult(method="llm-grop", task=1, seed=7, request=REQUEST, planned=planned,
                     plan=plan, execution=execution, final=final, planning_time_s=0.42,
                     scene=SCENE, simulator="kinematic2d")


def nav(path: tuple[tuple[float, float], ...], ok: bool = True, attempt: int = 1
        ) -> ExecutedStep:
    return ExecutedStep("navigate", ok, 5.0, goal=Pose2D(*path[-1]), path=path, attempt=attempt,
                        note="" if ok else "blocked by a chair")


STEPS = (
    nav(TO_COUNTER),
    ExecutedStep("pick", True, 8.0, "dinner plate", standing=PICK_AT),
    nav(BLOCKED, ok=False),
    nav(TO_TABLE, attempt=2),
    ExecutedStep("place", True, 8.0, "dinner plate", standing=PLACE_AT, pose=(0.0, -0.1, 0.0)),
    nav(tuple(reversed(TO_TABLE))),
    ExecutedStep("pick", True, 8.0, "dinner fork", standing=PICK_AT),
    nav(TO_TABLE),
    ExecutedStep("place", True, 8.0, "dinner fork", standing=PLACE_AT, pose=(-0.17, -0.1, 0.0)),
)
EXPECTED_SHAPE = (round(FIGSIZE_IN[1] * DPI), round(FIGSIZE_IN[0] * DPI))


def test_png_is_written_and_decodes_with_the_fixed_size(tmp_path: Path) -> None:
    path = tmp_path / "run.png"
    draw_run(run_result(STEPS), path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    pixels = imread(path)
    assert pixels.shape[:2] == EXPECTED_SHAPE
    # Not a blank page: the map and its colours are there.
    assert np.unique(pixels[:, :, :3].reshape(-1, 3), axis=0).shape[0] > 50
    assert [p.name for p in tmp_path.iterdir()] == ["run.png"]


def test_same_run_same_bytes(tmp_path: Path) -> None:
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    draw_run(run_result(STEPS), a)
    draw_run(run_result(STEPS), str(b))
    assert a.read_bytes() == b.read_bytes()
    assert b"matplotlib" not in a.read_bytes()


def test_title_and_trajectory_change_the_picture(tmp_path: Path) -> None:
    draw_run(run_result(STEPS), tmp_path / "a.png")
    draw_run(run_result(STEPS), tmp_path / "b.png", title="Fig. 4")
    draw_run(run_result(STEPS[:2]), tmp_path / "c.png")
    a = (tmp_path / "a.png").read_bytes()
    assert (tmp_path / "b.png").read_bytes() != a
    assert (tmp_path / "c.png").read_bytes() != a


def test_failed_navigation_and_unplaced_objects_render(tmp_path: Path) -> None:
    steps = (nav(TO_COUNTER), ExecutedStep("pick", True, 8.0, "dinner plate", standing=PICK_AT),
             nav(BLOCKED, ok=False), nav(BLOCKED, ok=False, attempt=2))
    path = tmp_path / "failed.png"
    draw_run(run_result(steps, unplaced=("dinner plate", "dinner fork")), path)
    pixels = imread(path)[:, :, :3] * 255.0
    assert pixels.shape[:2] == EXPECTED_SHAPE
    red = np.all(np.abs(pixels - np.array([0xD6, 0x27, 0x28])) < 4, axis=2)
    assert red.sum() > 100  # the dashed red legs (and the failure line)


def test_empty_run_renders(tmp_path: Path) -> None:
    scene = replace(SCENE, walls=(), chairs=(), sources=())
    result = replace(run_result((), unplaced=("dinner plate", "dinner fork")), scene=scene,
                     task=None)
    path = tmp_path / "empty.png"
    draw_run(result, path)
    assert imread(path).shape[:2] == EXPECTED_SHAPE


def test_bad_paths_are_bad_input(tmp_path: Path) -> None:
    with pytest.raises(BadInput, match=r"^image .*run\.jpg: only PNG"):
        draw_run(run_result(STEPS), tmp_path / "run.jpg")
    with pytest.raises(BadInput, match=r"^image .*missing.*: cannot write") as info:
        draw_run(run_result(STEPS), tmp_path / "missing" / "run.png")
    assert "\n" not in str(info.value)
    assert not (tmp_path / "missing").exists()
