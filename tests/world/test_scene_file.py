"""Scene files: the packaged dining room, the JSON round trip and one-line errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml
from scipy import ndimage
from shapely.geometry import Polygon
from shapely.geometry import box as rect

from llm_grop.errors import BadInput
from llm_grop.files.scene_file import load_scene, parse_scene, scene_to_dict
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.robot import Robot
from llm_grop.world.scene import Chair, ObjectSource, Scene

ROOM = """
name: test
room: {width: 6.0, depth: 4.0}
walls:
  - {center: [5.0, 3.0], size: [0.1, 1.0]}
tables:
  - {name: dining table, center: [3.0, 2.0], size: [0.9, 0.6]}
  - {name: counter, center: [0.4, 2.0], size: [0.5, 1.2]}
target: dining table
robot: {start: [1.5, 0.6, 0.0]}
"""


def _poly(b: Box) -> Polygon:
    return Polygon(b.corners())


def _load(tmp_path: Path, text: str) -> Scene:
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    return load_scene(path)


def _error(tmp_path: Path, text: str) -> str:
    with pytest.raises(BadInput) as info:
        _load(tmp_path, text)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(tmp_path / "scene.yaml"))
    return message


# --- the packaged dining room -----------------------------------------------------------


@pytest.fixture(scope="module")
def packaged() -> Scene:
    return load_scene(None)


def test_packaged_scene_layout(packaged: Scene) -> None:
    assert (packaged.width, packaged.depth) == (8.0, 6.0)
    target = packaged.target_table.box
    assert packaged.target == "dining table"
    assert (target.width, target.depth, target.yaw) == (0.9, 0.6, 0.0)
    assert math.dist((target.x, target.y), (4.0, 3.0)) < 0.3
    clear = rect(target.x - 0.45 - 1.2, target.y - 0.3 - 1.2,
                 target.x + 0.45 + 1.2, target.y + 0.3 + 1.2)
    others = [_poly(b) for b in packaged.walls] + [
        _poly(t.box) for t in packaged.tables if t.name != "dining table"]
    assert not any(clear.intersects(o) for o in others)
    assert 2 <= len(packaged.supply_tables) <= 3
    assert set(packaged.source_tables) == {t.name for t in packaged.supply_tables}
    assert packaged.sources == () and packaged.chairs == ()
    assert packaged.chair_band_m == (0.05, 0.6)
    assert len(packaged.walls) >= 1


def test_packaged_scene_every_table_is_reachable(packaged: Scene) -> None:
    # Free cells for the base's centre, connected to the start's cell.
    r, step = packaged.robot.base_radius_m, 0.05
    free_space = rect(r, r, packaged.width - r, packaged.depth - r).difference(
        shapely.union_all([_poly(b).buffer(r) for b in packaged.static_obstacles()]))
    xs, ys = np.meshgrid(np.arange(0, packaged.width, step), np.arange(0, packaged.depth, step))
    free = shapely.contains_xy(free_space, xs, ys)
    labels, _ = ndimage.label(free)
    start = packaged.robot_start
    here = labels[round(start.y / step), round(start.x / step)]
    assert here > 0
    reached = labels == here
    for t in packaged.tables:
        near = shapely.contains_xy(_poly(t.box).buffer(r + 0.2), xs, ys) & reached
        assert near.any(), t.name


# --- the JSON form -----------------------------------------------------------------------


def test_packaged_scene_round_trips(packaged: Scene) -> None:
    data = scene_to_dict(packaged)
    json.dumps(data)
    assert parse_scene(yaml.dump(data), "again") == packaged
    assert set(data) >= {"room", "walls", "tables", "target", "robot"}
    assert "chairs" not in data  # it lists none, so each episode samples its own
    assert data["robot"]["start"] == [0.8, 0.8, 0.0]
    assert data["robot"]["capacity"] == 1


def test_full_scene_round_trips(tmp_path: Path) -> None:
    scene = _load(tmp_path, """
name: full
room: {width: 6.0, depth: 4.0}
walls:
  - {center: [5.0, 3.0], size: [0.1, 1.0], yaw: 0.3}
tables:
  - {name: dining table, center: [3.0, 2.0], size: [0.9, 0.6], yaw: 0.05}
  - {name: counter, center: [0.4, 2.0], size: [0.5, 1.2], height: 0.9}
target: dining table
source_tables: [counter]
sources:
  - {object: mug, table: counter, position: [0.4, 2.3]}
chairs:
  - {center: [3.0, 2.6], size: [0.45, 0.45]}
  - {center: [3.0, 1.4], size: [0.45, 0.45], yaw: 0.1}
chair_band_m: [0.05, 0.6]
robot: {start: [1.5, 0.6, 1.2], base_radius_m: 0.25, capacity: 2, speed_mps: 0.4}
""")
    assert scene.sources == (ObjectSource("mug", "counter", 0.4, 2.3),)
    assert [c.name for c in scene.chairs] == ["chair 1", "chair 2"]
    assert scene.robot == Robot(base_radius_m=0.25, capacity=2, speed_mps=0.4)
    assert scene.robot_start == Pose2D(1.5, 0.6, 1.2)
    data = scene_to_dict(scene)
    json.dumps(data)
    assert "name" not in data["chairs"][0]
    assert parse_scene(yaml.dump(data), "again") == scene


def test_other_chair_names_are_kept(packaged: Scene) -> None:
    scene = packaged.with_chairs((Chair("stool", Box(4.0, 3.6, 0.4, 0.4)),))
    assert parse_scene(yaml.dump(scene_to_dict(scene)), "again") == scene


def test_defaults(tmp_path: Path) -> None:
    scene = _load(tmp_path, """
room: {width: 4, depth: 3}
tables: [{name: t, center: [2, 1.5], size: [0.9, 0.6]}]
target: t
""")
    assert scene.robot_start == Pose2D(0.5, 0.5, 0.0)
    assert scene.robot == Robot()
    assert scene.chair_band_m == (0.0, 1.0)
    assert scene.tables[0].height == 0.75
    assert scene.walls == () and scene.supply_tables == ()


# --- errors --------------------------------------------------------------------------------


def _swap(old: str, new: str) -> str:
    assert old in ROOM
    return ROOM.replace(old, new)


COUNTER = "{name: counter, center: [0.4, 2.0], size: [0.5, 1.2]}"


@pytest.mark.parametrize(("text", "needle"), [
    # a missing table
    (_swap("target: dining table", "target: kitchen table"),
     "target: no table named 'kitchen table' (tables: dining table, counter)"),
    ("room: {width: 6, depth: 4}\ntables: []\ntarget: t\n", "tables: no tables"),
    ("room: {width: 6, depth: 4}\ntarget: t\n", "tables: required, but missing"),
    (ROOM + "source_tables: [pantry]\n", "source_tables[0]: no table named 'pantry'"),
    (ROOM + "source_tables: [dining table]\n", "source_tables[0]: 'dining table' is the target"),
    (ROOM + "sources:\n  - {object: mug, table: pantry, position: [0.4, 2.0]}\n",
     "sources[0] ('mug').table: no table named 'pantry'"),
    (ROOM + "sources:\n  - {object: mug, table: dining table, position: [3.0, 2.0]}\n",
     "sources[0] ('mug').table: 'dining table' is the target"),
    # schema
    (_swap(COUNTER, "{name: dining table, center: [0.4, 2.0], size: [0.5, 1.2]}"),
     "tables[1] ('dining table').name: table 'dining table' is listed twice"),
    (_swap("size: [0.5, 1.2]", "size: [-0.5, 1.2]"), "tables[1] ('counter').size[0]:"),
    (_swap("size: [0.5, 1.2]", "size: [0.5, 1.2], colour: red"), "tables[1] ('counter').colour:"),
    (_swap("width: 6.0", "width: 0"), "room.width:"),
    (ROOM + "chair_band_m: [0.6, 0.1]\n", "chair_band_m: lower bound 0.6 exceeds"),
    ("- just a list\n", "top level:"),
    ("room: {width: [\n", "not valid YAML"),
    # sources
    (ROOM + "sources:\n  - {object: mug, table: counter, position: [6.5, 2.0]}\n",
     "sources[0] ('mug').position: (6.5, 2) is outside the room"),
    (ROOM + "sources:\n  - {object: mug, table: counter, position: [5.0, 3.2]}\n",
     "sources[0] ('mug').position: inside wall 1"),
    (ROOM + "sources:\n  - {object: mug, table: counter, position: [0.4, 3.99]}\n",
     "sources[0] ('mug').position: (0.4, 3.99) is not on the top of table 'counter'"),
    (ROOM + "sources:\n  - {object: dinner plate 2, table: counter, position: [0.4, 2.0], "
     "rests_on: dinner plate}\n",
     "sources[0] ('dinner plate 2').rests_on: no earlier source is 'dinner plate'; list "
     "what a pile rests on before it"),
    (ROOM + "sources:\n  - {object: dinner plate, table: counter, position: [0.4, 2.0]}\n"
     "  - {object: dinner plate 2, table: counter, position: [0.4, 2.3], rests_on: dinner plate}\n",
     "sources[1] ('dinner plate 2').rests_on: 'dinner plate' starts at (0.4, 2) on 'counter'; an "
     "object on it starts at the same spot"),
    (ROOM + "sources:\n  - {object: dinner plate, table: counter, position: [0.4, 2.0]}\n"
     "  - {object: dinner plate 2, table: counter, position: [0.4, 2.0], rests_on: dinner plate}\n"
     "  - {object: dinner plate 3, table: counter, position: [0.4, 2.0], rests_on: dinner plate}\n",
     "sources[2] ('dinner plate 3').rests_on: another source already rests on 'dinner plate'"),
    (ROOM + "sources:\n  - {object: dinner plate, table: counter, position: [0.4, 2.0]}\n"
     "  - {object: mug, table: counter, position: [0.4, 2.0]}\n",
     "sources[1] ('mug').position: (0.4, 2) is where sources[0] ('dinner plate') starts"),
    # tables
    (_swap("center: [0.4, 2.0]", "center: [2.6, 2.0]"),
     "tables[1] ('counter'): overlaps table 'dining table'"),
    (_swap("center: [0.4, 2.0]", "center: [5.0, 2.6]"), "tables[1] ('counter'): overlaps wall 1"),
    (_swap("center: [0.4, 2.0]", "center: [0.1, 2.0]"),
     "tables[1] ('counter'): extends outside the room (6 x 4 m)"),
    # chairs
    (ROOM + "chairs:\n  - {center: [3.0, 3.9], size: [0.45, 0.45]}\n",
     "chairs[0] ('chair 1'): extends outside the room"),
    (ROOM + "chairs:\n  - {center: [3.0, 3.0], size: [0.45, 0.45]}\n"
     "  - {center: [3.0, 2.4], size: [0.45, 0.45]}\n",
     "chairs[1] ('chair 2'): overlaps table 'dining table'"),
    (ROOM + "chairs:\n  - {center: [4.8, 3.0], size: [0.45, 0.45]}\n",
     "chairs[0] ('chair 1'): overlaps wall 1"),
    # the robot
    (_swap("start: [1.5, 0.6, 0.0]", "start: [0.2, 0.6, 0.0]"),
     "robot.start: the base (radius 0.3 m) at (0.2, 0.6) crosses the room's outer wall"),
    (_swap("start: [1.5, 0.6, 0.0]", "start: [4.8, 3.0, 0.0]"), "robot.start: "),
    (_swap("start: [1.5, 0.6, 0.0]", "start: [0.9, 2.0, 0.0]"),
     "robot.start: the base (radius 0.3 m) at (0.9, 2) collides with table 'counter'"),
    (ROOM + "chairs:\n  - {center: [1.5, 1.0], size: [0.45, 0.45]}\n",
     "robot.start: the base (radius 0.3 m) at (1.5, 0.6) collides with chair 1"),
    (_swap("start: [1.5, 0.6, 0.0]", "start: [1.5, 0.6, 0.0], base_radius_m: -1"),
     "robot.base_radius_m: must be positive"),
    (_swap("start: [1.5, 0.6, 0.0]", "start: [1.5, 0.6, 0.0], reach_min_m: 2"),
     "robot.reach_min_m:"),
    (_swap("start: [1.5, 0.6, 0.0]", "start: [1.5, 0.6, 0.0], capacity: 0"), "robot.capacity:"),
    (_swap("start: [1.5, 0.6, 0.0]", "start: [1.5, 0.6]"), "robot.start[2]: required, but missing"),
    (_swap("start: [1.5, 0.6, 0.0]", "start: [1.5, 0.6, 0.0], speed: 2"),
     "robot.speed: unknown key; did you mean 'speed_mps'?"),
])
def test_bad_scene(tmp_path: Path, text: str, needle: str) -> None:
    assert needle in _error(tmp_path, text)


def test_wall_collision_is_named(tmp_path: Path) -> None:
    message = _error(tmp_path, _swap("start: [1.5, 0.6, 0.0]", "start: [4.8, 3.0, 0.0]"))
    assert message.endswith("collides with wall 1")


def test_touching_shapes_are_fine(tmp_path: Path) -> None:
    # The counter touches the west wall and a chair touches the dining table's edge.
    scene = _load(tmp_path, _swap("center: [0.4, 2.0]", "center: [0.25, 2.0]")
                  + "chairs:\n  - {center: [3.0, 2.525], size: [0.45, 0.45]}\n")
    assert scene.table("counter").box.x == 0.25 and len(scene.chairs) == 1


@pytest.mark.parametrize("name", ["missing.yaml", "."])
def test_unreadable_file(tmp_path: Path, name: str) -> None:
    path = tmp_path / name
    with pytest.raises(BadInput, match=r"^scene: cannot read '.*': ") as info:
        load_scene(path)
    assert "\n" not in str(info.value)


def test_an_empty_chair_list_means_no_chairs(tmp_path: Path) -> None:
    from llm_grop.api import run

    text = (Path(__file__).resolve().parents[2] / "src/llm_grop/data/scenes/dining_room.yaml"
            ).read_text()
    path = tmp_path / "no_chairs.yaml"
    path.write_text(text + "chairs: []\n")
    scene = load_scene(path)
    assert scene.chairs == () and scene.chairs_listed
    assert run(task=1, method="grop", scene=path, seed=0).scene.chairs == ()
    assert len(run(task=1, method="grop", seed=0).scene.chairs) == 1
    assert scene_to_dict(scene)["chairs"] == []


def test_a_pile_of_sources_reads_and_round_trips(tmp_path: Path) -> None:
    scene = _load(tmp_path, ROOM + """sources:
  - {object: dinner plate, table: counter, position: [0.4, 2.0]}
  - {object: dinner plate 2, table: counter, position: [0.4, 2.0], rests_on: dinner plate}
  - {object: mug, table: counter, position: [0.4, 2.4]}
""")
    assert scene.sources == (ObjectSource("dinner plate", "counter", 0.4, 2.0),
                             ObjectSource("dinner plate 2", "counter", 0.4, 2.0, "dinner plate"),
                             ObjectSource("mug", "counter", 0.4, 2.4))
    data = scene_to_dict(scene)
    # Only a pile's upper objects carry `on`: other sources are written as before.
    assert [sorted(s) for s in data["sources"]] == [
        ["object", "position", "table"], ["object", "position", "rests_on", "table"],
        ["object", "position", "table"]]
    assert parse_scene(yaml.dump(data), "again") == scene
    height = scene.table("counter").height
    heights = {"dinner plate": 0.025, "dinner plate 2": 0.025}
    assert scene.resting_z("dinner plate 2", "dinner plate", heights) == \
        pytest.approx(height + 0.025)
    assert scene.resting_z("dinner plate", "dinner plate", heights) == height
