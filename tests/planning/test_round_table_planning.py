"""Round tables from the arrangement's predicates to execution: on-the-top and centre tests
on a circle, obstacles and standing positions round it, chairs and supplies at round tables,
pictures, and ``llm-grop run --table round:1.2`` end to end in 2D and in MuJoCo."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from llm_grop.arrangement.predicates import CENTER_FRACTION, Footprint, in_center, inside_table
from llm_grop.arrangement.random_placement import random_configurations
from llm_grop.cli import main
from llm_grop.files.scene_file import load_scene, set_target_top
from llm_grop.geometry.obstacles import Obstacles
from llm_grop.planning.occupancy import build_grid
from llm_grop.planning.standing import candidate_standing_poses
from llm_grop.render.room import draw_run
from llm_grop.render.table import draw_arrangement
from llm_grop.simulation.scenario import prepare_episode
from llm_grop.world.arrangement import Arrangement, Placement
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import Scene, SceneTable
from llm_grop.world.table import Table

RECORDING = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "embedded_calls.jsonl"
REPLAY = ["--llm", "replay", "--replay", str(RECORDING)]
ROUND = Table.circle(1.2)
PLATE = Footprint("circle", 0.135, 0.135)
FORK = Footprint("box", 0.0125, 0.1)


def _round_room(diameter: float = 1.2) -> Scene:
    """A 6 x 4 m room: a round dining table at (3, 2) and a round counter by the west wall."""
    return Scene(
        name="round room", width=6.0, depth=4.0,
        tables=(SceneTable("dining table", Box(3.0, 2.0, diameter, diameter), shape="circle"),
                SceneTable("counter", Box(0.6, 2.0, 0.9, 0.9), shape="circle")),
        target="dining table", robot_start=Pose2D(1.5, 0.5, 0.0), chair_band_m=(0.05, 0.6))


# -- predicates -----------------------------------------------------------------------------

def test_a_circle_footprint_must_lie_within_the_radius() -> None:
    r = ROUND.radius - PLATE.hx - 1e-9  # just inside the edge
    x = np.array([0.0, r * math.cos(0.7), 0.3, 0.45, -0.42])
    y = np.array([0.0, r * math.sin(0.7), 0.3, 0.0, -0.42])
    assert inside_table(x, y, PLATE, ROUND).tolist() == [True, True, True, True, False]
    # The same spot on the 1.2 m square is on the table.
    assert bool(inside_table(-0.42, -0.42, PLATE, Table(1.2, 1.2)))
    assert not bool(inside_table(0.0, 0.0, PLATE, ROUND, margin=0.5))


def test_a_box_footprint_needs_every_corner_of_its_bounding_box_on_the_circle() -> None:
    # Its farthest corner decides: (x + hx, y + hy) at the radius.
    x = 0.3
    y_edge = math.sqrt(ROUND.radius ** 2 - (x + FORK.hx) ** 2) - FORK.hy
    ys = np.array([y_edge - 1e-6, y_edge + 1e-6, -(y_edge - 1e-6), -(y_edge + 1e-6)])
    assert inside_table(x, ys, FORK, ROUND).tolist() == [True, False, True, False]
    # Vectorised over (M, K) like the sampler's draws.
    grid = np.zeros((3, 4))
    assert inside_table(grid, grid, FORK, ROUND).shape == (3, 4)


def test_center_on_a_round_table_is_a_disc() -> None:
    reach = CENTER_FRACTION * ROUND.width  # 0.3 m
    x = np.array([0.0, 0.29, 0.25, 0.2, 0.0])
    y = np.array([0.0, 0.0, 0.25, 0.2, -0.31])
    assert in_center(x, y, ROUND).tolist() == [True, True, False, True, False]
    assert bool(in_center(0.25, 0.25, Table(1.2, 1.2)))  # the square's middle is a square
    assert not bool(in_center(reach - 0.01, 0.0, ROUND, margin=0.02))


def test_random_placement_keeps_objects_on_the_circle() -> None:
    items = items_from_names(["dinner plate", "dinner fork", "dinner knife", "mug",
                              "bread plate"], Catalog.load())
    configs = random_configurations(items, Table.circle(0.7), np.random.default_rng(3), m=10)
    for c in configs:
        for p in c.placements:
            assert bool(inside_table(p.x, p.y, Footprint.of_placement(p), Table.circle(0.7)))


# -- the room -------------------------------------------------------------------------------

def test_clearance_is_the_distance_to_the_circle() -> None:
    obstacles = Obstacles(_round_room(), include_chairs=False)
    pts = np.array([[3.0 + 0.8, 2.0], [3.0 + 0.5, 2.5], [3.0 + 0.55, 2.55], [3.0, 2.0]])
    d = obstacles.clearance(pts)
    assert d[0] == pytest.approx(0.2)
    assert d[1] == pytest.approx(math.hypot(0.5, 0.5) - 0.6)  # the square's corner is free
    assert d[2] == pytest.approx(math.hypot(0.55, 0.55) - 0.6)
    assert d[3] == 0.0
    assert obstacles.free(3.0 + 0.9, 2.0, 0.3)  # touching is free
    assert not obstacles.free(3.0 + 0.89, 2.0, 0.3)
    grid = build_grid(_round_room(), 0.05, include_chairs=False)
    cell = grid.cell_of(np.array([[3.6 + 0.025, 2.0 + 0.025]]))[0]
    assert grid.clearance_m[cell[0], cell[1]] < 0.06


def test_standing_positions_loop_round_the_circle_facing_its_centre() -> None:
    scene, robot = _round_room(), _round_room().robot
    poses = candidate_standing_poses(scene, "dining table", robot, standoffs_m=(0.05, 0.25))
    assert len(poses) > 60
    radii = sorted({round(math.hypot(p.pose.x - 3.0, p.pose.y - 2.0), 3) for p in poses})
    assert radii == pytest.approx([0.6 + 0.05 + robot.base_radius_m,
                                   0.6 + 0.25 + robot.base_radius_m], abs=2e-3)
    angles = np.array([math.atan2(p.pose.y - 2.0, p.pose.x - 3.0) for p in poses])
    assert np.ptp(angles) > 1.9 * math.pi  # all the way round
    for p in poses:
        towards = math.atan2(2.0 - p.pose.y, 3.0 - p.pose.x)
        assert abs(math.remainder(p.pose.theta - towards, 2 * math.pi)) < 1e-9
        assert p.clearance_m >= 0.0


def test_chairs_stand_round_a_round_table_and_objects_start_on_a_round_counter() -> None:
    scene = _round_room()
    items = items_from_names(["dinner plate", "dinner fork", "dinner knife", "mug"],
                             Catalog.load())
    episode = prepare_episode(scene, items, seed=4, chairs=3)
    assert len(episode.chairs) == 3
    for c in episode.chairs:
        gap = math.hypot(c.box.x - 3.0, c.box.y - 2.0) - 0.6 - c.box.depth / 2
        assert 0.05 - 1e-3 <= gap <= 0.6 + 1e-3
        # Its -y side faces the centre (the back, +y, is away from the table).
        u, v = c.box.to_local(3.0, 2.0)
        assert abs(u) < 1e-3 and v < 0
    counter = scene.table("counter")
    for s in episode.sources:
        assert counter.contains(s.x, s.y)
        assert math.hypot(s.x - 0.6, s.y - 2.0) <= 0.45 - 0.05 - 0.06 + 1e-9


# -- pictures -------------------------------------------------------------------------------

def test_the_table_picture_draws_a_circle(tmp_path: Path) -> None:
    plate = Placement("dinner plate", 0.0, -0.3, 0.0, "circle", (0.27, 0.27), None,
                      "dinner plate", 0.02)
    paths = []
    for table in (ROUND, Table(1.2, 1.2)):
        paths.append(tmp_path / f"{table.shape}.png")
        draw_arrangement(Arrangement("a plate", table, (plate,)), paths[-1])
    round_img = np.asarray(Image.open(paths[0]).convert("RGB"), dtype=int)
    square_img = np.asarray(Image.open(paths[1]).convert("RGB"), dtype=int)
    tan = np.array([0xEA, 0xDC, 0xC3])
    # The square has more table-coloured pixels than the circle inscribed in it, by about
    # 1 - pi/4 of the square's area.
    on_round = (np.abs(round_img - tan).sum(axis=2) < 10).sum()
    on_square = (np.abs(square_img - tan).sum(axis=2) < 10).sum()
    assert 0.15 < 1 - on_round / on_square < 0.3


def test_a_round_target_is_a_circle_in_the_room_picture(tmp_path: Path) -> None:
    from llm_grop.api import run

    result = run("a dinner plate", method="grop", scene=_round_room(), chairs=1, seed=1)
    draw_run(result, tmp_path / "room.png")
    assert (tmp_path / "room.png").read_bytes()[:4] == b"\x89PNG"


# -- end to end -----------------------------------------------------------------------------

def test_llm_grop_sets_a_round_table_end_to_end(tmp_path: Path) -> None:
    out_json, out_png = tmp_path / "run.json", tmp_path / "run.png"
    code = main(["run", "--task", "8", "--table", "round:1.2", *REPLAY, "--json", str(out_json),
                 "--image", str(out_png), "-q"])
    assert code == 0
    data = json.loads(out_json.read_text())
    assert data["success"] and not data["unplaced"]
    assert data["final"]["table"] == {"shape": "circle", "size": [1.2, 1.2]}
    target = next(t for t in data["scene"]["tables"] if t["name"] == "dining table")
    assert target["shape"] == "circle" and target["size"] == [1.2, 1.2]
    for o in data["final"]["objects"]:
        foot = Footprint.of_placement(Placement(o["name"], o["x"], o["y"], o["yaw"], o["shape"],
                                                tuple(o["size"]), o["on"], o["kind"]))
        assert bool(inside_table(o["x"], o["y"], foot, ROUND)), o
    centre = (4.0, 3.0)
    for s in data["steps"]:
        if s["action"] == "place" and s["ok"]:
            x, y, _ = s["standing"]
            assert math.hypot(x - centre[0], y - centre[1]) >= 0.6 + 0.3 - 0.05
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_llm_grop_sets_a_round_table_in_mujoco(tmp_path: Path) -> None:
    out_json = tmp_path / "run.json"
    code = main(["run", "--task", "8", "--table", "round:1.2", "--simulator", "mujoco",
                 *REPLAY, "--json", str(out_json), "-q"])
    assert code == 0
    data = json.loads(out_json.read_text())
    assert data["simulator"] == "mujoco" and data["success"]
    assert data["final"]["table"]["shape"] == "circle"
    assert len(data["final"]["objects"]) == 5


def test_the_packaged_room_takes_a_round_table_for_every_method() -> None:
    from llm_grop.api import run

    scene = set_target_top(load_scene(), ROUND)
    for method in ("tpra", "grop"):
        result = run("a dinner plate, a dinner fork and a mug", method=method, scene=scene,
                     seed=0)
        assert result.final.table == ROUND
        for p in result.final.placements:
            assert bool(inside_table(p.x, p.y, Footprint.of_placement(p), ROUND))
