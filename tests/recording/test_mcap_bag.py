"""ROS 2 bags of episodes (``--mcap``), read back with rosbags (a reader that is not the
writer) as ROS 2 Humble's types: the topics, their types and counts, and poses against
the run JSON, in 2D and in MuJoCo; the message definitions are Humble's."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from cli_support import one_line_error
from llm_grop.cli import main
from recording_support import REPLAY, run_without_package

pytest.importorskip("mcap_ros2")
highlevel = pytest.importorskip("rosbags.highlevel")
typesys = pytest.importorskip("rosbags.typesys")

TYPES = {"/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage",
         "/plan/path": "nav_msgs/msg/Path", "/plan/goals": "geometry_msgs/msg/PoseStamped",
         "/objects": "visualization_msgs/msg/MarkerArray", "/events": "std_msgs/msg/String"}


def _bag(tmp_path: Path, *flags: str) -> tuple[dict[str, Any], dict[str, str],
                                                dict[str, list[tuple[int, Any]]]]:
    out, bag = tmp_path / "run.json", tmp_path / "run.mcap"
    assert main(["run", "--task", "8", *REPLAY, "--json", str(out), "--mcap", str(bag), "-q",
                 *flags]) == 0
    store = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    types: dict[str, str] = {}
    messages: dict[str, list[tuple[int, Any]]] = {}
    with highlevel.AnyReader([bag], default_typestore=store) as reader:
        for c in reader.connections:
            types[c.topic] = c.msgtype
        for c, t, raw in reader.messages():
            messages.setdefault(c.topic, []).append((t, reader.deserialize(raw, c.msgtype)))
    return json.loads(out.read_text()), types, messages


def _yaw(q: Any) -> float:
    return 2 * math.atan2(q.z, q.w)


def _check(run: dict[str, Any], types: dict[str, str],
           messages: dict[str, list[tuple[int, Any]]]) -> None:
    assert {k: types[k] for k in TYPES} == TYPES
    # Every attempt is one JSON object on /events, as the run JSON has it, and the end.
    events = [json.loads(m.data) for _, m in messages["/events"]]
    assert len(events) == len(run["steps"]) + 1 and events[-1]["episode"] == "ended"
    for event, step in zip(events, run["steps"], strict=False):
        assert (event["action"], event.get("object"), event["ok"], event.get("reason")) == (
            step["action"], step.get("object"), step["ok"], step.get("reason"))
        assert event["duration_s"] == pytest.approx(step["duration_s"], abs=1e-3)
    times = [t for t, _ in messages["/events"]]
    assert times == sorted(times)
    assert times[-1] / 1e9 == pytest.approx(run["execution_time_s"], abs=2e-3)
    # The plan's goals: two drives per object (fetch, deliver); each deliver goal is the
    # run JSON's standing position of that object.
    goals = [m for _, m in messages["/plan/goals"]]
    paths = [m for _, m in messages["/plan/path"]]
    assert len(goals) == len(paths) == 2 * len(run["plan"]["order"])
    assert all(g.header.frame_id == "map" for g in goals)
    delivered = goals[1::2]
    for goal, standing in zip(delivered, run["plan"]["standing"], strict=True):
        x, y, theta = standing["pose"]
        p = goal.pose
        # The run JSON rounds to 4 decimals.
        assert (p.position.x, p.position.y) == pytest.approx((x, y), abs=6e-5)
        assert math.remainder(_yaw(p.orientation) - theta, 2 * math.pi) == pytest.approx(
            0.0, abs=6e-5)
    # tf: the base from its start, every object in the map frame, by its name.
    tf = [tr for _, m in messages["/tf"] for tr in m.transforms]
    base = [tr for tr in tf if tr.child_frame_id == "base_link"]
    assert base[0].header.frame_id == "map"
    start = run["scene"]["robot"]["start"]
    assert (base[0].transform.translation.x, base[0].transform.translation.y) == \
        pytest.approx(start[:2], abs=1e-6)
    frames = {tr.child_frame_id for tr in tf}
    assert {o["name"].replace(" ", "_") for o in run["planned"]["objects"]} <= frames
    markers = messages["/objects"][0][1].markers
    assert {m.text for m in markers if m.ns == "objects"} == \
        {o["name"] for o in run["planned"]["objects"]}


def test_a_2d_episode_as_a_ros2_bag(tmp_path: Path) -> None:
    run, types, messages = _bag(tmp_path)
    _check(run, types, messages)
    assert "/scan" not in types


def test_a_mujoco_episode_adds_the_lidar(tmp_path: Path) -> None:
    run, types, messages = _bag(tmp_path, "--simulator", "mujoco", "--seed", "1")
    _check(run, types, messages)
    assert types["/scan"] == "sensor_msgs/msg/LaserScan"
    scans = [m for _, m in messages["/scan"]]
    assert len(scans) > 50 and all(len(s.ranges) == 360 for s in scans)
    assert scans[0].header.frame_id == "laser"
    assert any(math.isfinite(r) and r > 0 for r in scans[0].ranges)


def test_the_message_definitions_are_humbles() -> None:
    from llm_grop.recording.mcap_sink import message_definitions

    store = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    for name, text in message_definitions().items():
        assert text == store.generate_msgdef(name, ros_version=2)[0].strip(), name


@pytest.mark.parametrize(("path", "needle"), [
    ("missing/run.mcap", "does not exist"),
    ("run.bag", "ends in .mcap"),
])
def test_an_unwritable_bag_is_refused_before_any_work(tmp_path: Path, capsys, monkeypatch,
                                                      path: str, needle: str) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--task", "8", "--llm", "openai", "--base-url",
                 "http://127.0.0.1:9/v1", "--mcap", path, "-q"]) == 2
    line = one_line_error(capsys)
    assert "--mcap" in line and needle in line


def test_without_the_extra_mcap_is_one_line(tmp_path: Path) -> None:
    # As where the [ros] extra is not installed: Python finds no mcap_ros2 package.
    args = ["run", "--task", "8", *REPLAY, "--mcap", str(tmp_path / "r.mcap")]
    done = run_without_package("mcap_ros2", args)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert "--mcap: needs the optional [ros] extra" in done.stderr
