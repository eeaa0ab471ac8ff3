"""Inputs the fuzzers found that broke a parser, kept as plain regression tests (the
catalog's are in ``tests/world/test_catalog.py``, the distance parser's in
``tests/arrangement/test_distances.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from llm_grop.errors import BadInput
from llm_grop.files.scene_file import parse_scene
from llm_grop.llm.record import LLMCallRecord, append_record, load_records

_ROOM = "room: {width: 8, depth: 6}\n"
_TABLE = "{name: dining table, center: [4, 3], size: [0.9, 0.6]}"


@pytest.mark.parametrize(("text", "message"), [
    # A table name with a line break used to be listed as it is, over two lines.
    (_ROOM + f'tables: [{_TABLE}, {{name: "side\\ntable", center: [7, 1], size: [1, 1]}}]\n'
     "target: dining table\nsource_tables: [counter]\n",
     "x.yaml: source_tables[0]: no table named 'counter' (tables: dining table, "
     "'side\\ntable')"),
    # So was an unknown key with one.
    (_ROOM + f'tables: [{_TABLE}]\ntarget: dining table\n"col\\nour": red\n',
     "x.yaml: 'col\\nour': unknown key; expected one of name, room, walls, tables, target, "
     "source_tables, sources, chairs, chair_band_m, robot, diners"),
    # And a chair's name where the robot's start collides with the chair.
    (_ROOM + f"tables: [{_TABLE}]\ntarget: dining table\n"
     'chairs: [{name: "a\\nchair", center: [0.8, 0.8], size: [0.4, 0.4]}]\n'
     "robot: {start: [0.8, 0.8, 0]}\n",
     "x.yaml: robot.start: the base (radius 0.3 m) at (0.8, 0.8) collides with 'a\\nchair'"),
])
def test_scene_errors_stay_on_one_line(text: str, message: str) -> None:
    with pytest.raises(BadInput) as info:
        parse_scene(text, "x.yaml")
    assert str(info.value) == message


@pytest.mark.parametrize("response", ["a\x85b", "line\u2028separator", "para\u2029graph",
                                      "\x1c\x1d\x1e", "cr\rlf\r\n"])
def test_replay_records_keep_any_line_break(tmp_path: Path, response: str) -> None:
    # JSON keeps these characters as they are; reading the file split records at them.
    record = LLMCallRecord("embedded", "m", "prompt", response, 0.5)
    path = tmp_path / "calls.jsonl"
    append_record(path, record)
    append_record(path, record)
    assert load_records(path) == [record, record]
