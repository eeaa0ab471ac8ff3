"""Round tables in the world layer: ``--table round:D``, round scene tables, the contract's
``table.shape: circle``, and the one-line errors for a round table in a rectangular frame."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import pytest

from cli_support import one_line_error
from llm_grop.cli import main
from llm_grop.contract.serialize import arrangement_from_dict, arrangement_to_dict
from llm_grop.errors import BadInput
from llm_grop.files.scene_file import load_scene, parse_scene, scene_to_dict, set_target_top
from llm_grop.world.arrangement import Arrangement
from llm_grop.world.geometry2d import Box, Disc
from llm_grop.world.scene import SceneTable
from llm_grop.world.table import Table

RECORDING = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "embedded_calls.jsonl"
REPLAY = ["--llm", "replay", "--replay", str(RECORDING)]

ROOM = """
room: {width: 6.0, depth: 4.0}
tables:
  - {name: round table, shape: circle, center: [3.0, 2.0], TABLE}
  - {name: counter, center: [0.4, 2.0], size: [0.5, 1.2]}
target: round table
robot: {start: [1.5, 0.6, 0.0]}
"""


def _room(table: str) -> str:
    return ROOM.replace("TABLE", table)


# -- the table and --table ------------------------------------------------------------------

@pytest.mark.parametrize("text, diameter", [("round:1.2", 1.2), ("ROUND: 0.9", 0.9),
                                            ("round:.75", 0.75)])
def test_round_text_is_a_circle_of_that_diameter(text: str, diameter: float) -> None:
    table = Table.parse(text)
    assert table == Table(diameter, diameter, "circle") == Table.circle(diameter)
    assert table.is_round and table.radius == pytest.approx(diameter / 2)
    assert table.area == pytest.approx(math.pi * diameter ** 2 / 4)
    assert table.label == f"round {diameter:g} m table"


@pytest.mark.parametrize("text, canonical", [("ROUND: 1.20", "round:1.2"),
                                             ("0.9x0.6", "0.9x0.6"), ("1X2", "1.0x2.0")])
def test_text_spells_the_table_as_parse_reads_it(text: str, canonical: str) -> None:
    assert Table.parse(text).text == canonical
    assert Table.parse(canonical) == Table.parse(text)


def test_rectangles_parse_as_before() -> None:
    table = Table.parse("0.9x0.6")
    assert table == Table(0.9, 0.6) and not table.is_round
    assert table.area == pytest.approx(0.54) and table.label == "0.9 x 0.6 m table"
    with pytest.raises(ValueError):
        _ = table.radius


@pytest.mark.parametrize("text, words", [
    ("round:1.2x0.8", "a round table has one size, its diameter"),
    ("round:", "round:D such as round:1.2"),
    ("round:0", "table: size must be positive"),
    ("oval:1.2", "expected WxD in metres such as 0.9x0.6, or round:D"),
    ("1.2", "expected WxD"),
])
def test_bad_table_text_is_one_bad_input(text: str, words: str) -> None:
    with pytest.raises(BadInput, match="^table: ") as err:
        Table.parse(text)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_a_round_table_in_a_rectangular_frame_is_bad_input() -> None:
    with pytest.raises(BadInput, match="round table has one size.*1.2 x 0.8 m"):
        Table(1.2, 0.8, "circle")
    with pytest.raises(BadInput, match="shape must be one of rectangle, circle"):
        Table(1.0, 1.0, "oval")
    with pytest.raises(BadInput, match="table 'round': a round table has one size"):
        SceneTable("round", Box(3.0, 2.0, 1.2, 0.8), shape="circle")


# -- the contract ---------------------------------------------------------------------------

def test_a_round_table_round_trips_through_the_arrangement_json() -> None:
    a = Arrangement("a dinner plate", Table.circle(1.2), ())
    data = arrangement_to_dict(a)
    assert data["table"] == {"shape": "circle", "size": [1.2, 1.2]}
    assert arrangement_from_dict(data).table == Table.circle(1.2)


def test_a_circle_of_two_sizes_in_json_is_bad_input() -> None:
    data = {"request": "x", "table": {"shape": "circle", "size": [1.2, 0.8]}, "objects": []}
    with pytest.raises(BadInput) as err:
        arrangement_from_dict(data, "a.json")
    assert str(err.value) == ("a.json: table: a round table (shape circle) has one size, its "
                              "diameter: expected [d, d], got [1.2, 0.8]")


# -- scenes ---------------------------------------------------------------------------------

@pytest.mark.parametrize("table", ["size: [1.2, 1.2]", "diameter: 1.2",
                                   "size: [1.2, 1.2], diameter: 1.2"])
def test_a_scene_table_may_be_round(table: str) -> None:
    scene = parse_scene(_room(table), "s.yaml")
    t = scene.target_table
    assert t.is_round and t.box == Box(3.0, 2.0, 1.2, 1.2)
    assert t.footprint == Disc(3.0, 2.0, 0.6)
    assert scene.target_top == Table.circle(1.2)
    assert scene.static_obstacles()[0] == Disc(3.0, 2.0, 0.6)
    # On the square's corner but off the circle.
    assert t.box.contains(3.55, 2.55) and not t.contains(3.55, 2.55)
    assert t.contains(3.0, 2.59)


def test_a_round_scene_round_trips_through_its_json_form() -> None:
    scene = parse_scene(_room("diameter: 1.2"), "s.yaml")
    data = scene_to_dict(scene)
    assert data["tables"][0]["shape"] == "circle" and data["tables"][0]["size"] == [1.2, 1.2]
    assert "shape" not in data["tables"][1]
    assert parse_scene(json.dumps(data), "run.json") == scene


@pytest.mark.parametrize("table, message", [
    ("size: [1.2, 0.8]", "tables[0] ('round table').size: a round table has one size, its "
                         "diameter: give [d, d] or diameter: d, got [1.2, 0.8]"),
    ("size: [1.0, 1.0], diameter: 1.2", "tables[0] ('round table').diameter: 1.2 m disagrees "
                                        "with size [1, 1]"),
    ("yaw: 0.0", "tables[0] ('round table').size: Field required"),
    ("diameter: 0", "tables[0] ('round table').diameter: must be greater than 0, got 0"),
    # Its bounding square would overlap the counter's corner region; the circle does not,
    # but 4.2 m reaches out of the 4 m deep room.
    ("diameter: 4.2", "tables[0] ('round table'): extends outside the room (6 x 4 m)"),
])
def test_bad_round_scene_tables_are_one_line_errors(table: str, message: str) -> None:
    with pytest.raises(BadInput) as err:
        parse_scene(_room(table), "s.yaml")
    assert str(err.value).startswith(f"s.yaml: {message}")


def test_only_a_round_table_has_a_diameter() -> None:
    text = _room("diameter: 1.2").replace("name: counter,", "name: counter, diameter: 0.5,")
    with pytest.raises(BadInput, match=r"tables\[1\] \('counter'\)\.diameter: only a round"):
        parse_scene(text, "s.yaml")


def test_overlaps_use_the_circle_not_its_square() -> None:
    # A chair in the corner of the table's bounding square, clear of the circle itself.
    text = _room("diameter: 1.2") + "chairs: [{center: [3.62, 2.62], size: [0.2, 0.2]}]\n"
    assert parse_scene(text, "s.yaml").chairs[0].name == "chair 1"
    # A source pinned on the square's corner is not on the round counter.
    text = ROOM.replace("TABLE", "diameter: 1.2").replace(
        "{name: counter, center: [0.4, 2.0], size: [0.5, 1.2]}",
        "{name: counter, shape: circle, center: [0.6, 2.0], diameter: 0.8}")
    pinned = text + "sources: [{object: mug, table: counter, position: [0.9, 2.3]}]\n"
    with pytest.raises(BadInput, match="is not on the top of table 'counter'"):
        parse_scene(pinned, "s.yaml")


def test_set_target_top_makes_the_packaged_table_round() -> None:
    scene = load_scene()
    rounded = set_target_top(scene, Table.circle(1.2))
    t, before = rounded.target_table, scene.target_table
    assert t.is_round and (t.box.x, t.box.y, t.height) == (before.box.x, before.box.y,
                                                           before.height)
    assert rounded.target_top == Table.circle(1.2)
    assert [u for u in rounded.tables if u.name != t.name] == \
        [u for u in scene.tables if u.name != t.name]


@pytest.mark.parametrize("top, keep, words", [
    (Table.circle(6.5), True, "table: a round 6.5 m table as 'dining table' extends outside"),
    (Table(6.5, 5.0), True, "overlaps table 'kitchen counter'"),
    (Table(6.0, 0.6), True, "overlaps wall 1"),
    (Table.circle(1.2), False, "covers the robot's start"),
    (Table.circle(2.0), True, "overlaps chair 1; sample the chairs instead (chairs=N)"),
])
def test_a_top_that_does_not_fit_is_bad_input(top: Table, keep: bool, words: str) -> None:
    from llm_grop.world.scene import Chair

    scene = load_scene()
    scene = scene.with_chairs((Chair("chair 1", Box(4.0, 2.05, 0.45, 0.45)),))
    if "start" in words:
        scene = replace(scene, robot_start=replace(scene.robot_start, x=4.0, y=2.3))
    with pytest.raises(BadInput, match="^table: ") as err:
        set_target_top(scene, top, keep_chairs=keep)
    assert words in str(err.value)
    if "chair" in words:  # chairs sampled afresh (--chairs N) are not in the way
        set_target_top(scene, top, keep_chairs=False)


def test_round_scene_table_equality_keeps_its_shape() -> None:
    t = SceneTable("t", Box(1.0, 1.0, 0.8, 0.8), shape="circle")
    assert replace(t, shape="rectangle").footprint == t.box
    assert t.footprint == Disc(1.0, 1.0, 0.4)


# -- the command line -----------------------------------------------------------------------

@pytest.mark.parametrize("command", ["arrange", "run", "bench"])
@pytest.mark.parametrize("text, words", [
    ("round:1.2x0.8", "a round table has one size, its diameter in metres"),
    ("round:-1", "round:D such as round:1.2"),
])
def test_cli_bad_round_table_is_one_line_exit_2(command: str, text: str, words: str,
                                                 tmp_path: Path, capsys) -> None:
    task = ["--tasks", "8", "--out", str(tmp_path / "b")] if command == "bench" \
        else ["--task", "8"]
    code = main([command, *task, "--table", text, *REPLAY, "-q"])
    assert code == 2
    line = one_line_error(capsys)
    assert line.startswith("llm-grop: error: --table: ") and words in line
    assert not (tmp_path / "b").exists()


def test_cli_scene_with_a_round_table_in_a_rectangular_frame_exits_2(tmp_path: Path,
                                                                    capsys) -> None:
    scene = tmp_path / "scene.yaml"
    scene.write_text(_room("size: [1.2, 0.8]"))
    assert main(["run", "--task", "8", "--scene", str(scene), *REPLAY, "-q"]) == 2
    assert "tables[0] ('round table').size: a round table has one size" in \
        one_line_error(capsys)


def test_cli_a_round_top_that_leaves_the_room_exits_2(capsys) -> None:
    assert main(["run", "--task", "8", "--table", "round:6.5", *REPLAY, "-q"]) == 2
    assert one_line_error(capsys) == ("llm-grop: error: --table: a round 6.5 m table as "
                                      "'dining table' extends outside the room (8 x 6 m)")


def test_bench_sets_round_tables_and_keeps_the_table_in_its_identity(tmp_path: Path) -> None:
    out = tmp_path / "bench"
    base = ["bench", "--tasks", "8", "--trials", "1", "--methods", "grop", *REPLAY,
            "--out", str(out), "-q"]
    assert main([*base, "--table", "ROUND:1.20"]) == 0
    assert json.loads((out / "experiment.json").read_text())["table"] == "round:1.2"
    row = json.loads((out / "trials.jsonl").read_text().splitlines()[0])
    assert row["final"]["table"] == {"shape": "circle", "size": [1.2, 1.2]}
    assert (out / "images" / "task8_trial00_grop.png").exists()
    assert main([*base, "--table", "round:1.2"]) == 0  # the same table resumes
    assert main([*base, "--table", "round:1.3"]) == 2  # another table is another experiment
