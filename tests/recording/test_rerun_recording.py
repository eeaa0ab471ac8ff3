"""Rerun recordings of episodes (``--rerun``), read back with Rerun's own reader and
``rerun rrd verify``: the room, the objects in their kinds' colours, the robot over
simulated time, the plan and every attempt, in 2D and in MuJoCo; a recording changes
nothing in the run; bad input is one line before any work."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from cli_support import one_line_error
from llm_grop.cli import main
from llm_grop.world.kind_colors import kind_color
from recording_support import REPLAY, Recording, entity, run_without_package, verify

pytest.importorskip("rerun")


def _run(tmp_path: Path, *flags: str) -> tuple[dict[str, Any], Recording]:
    out, rrd = tmp_path / "run.json", tmp_path / "run.rrd"
    assert main(["run", "--task", "8", *REPLAY, "--json", str(out), "--rerun", str(rrd), "-q",
                 *flags]) == 0
    verify(rrd, tmp_path)
    return json.loads(out.read_text()), Recording(rrd)


def _rgba(color: str) -> int:
    """A ``#rrggbb`` colour as Rerun stores it (``0xRRGGBBAA``)."""
    return int(color.lstrip("#") + "ff", 16)


def _common(run: dict[str, Any], rec: Recording) -> None:
    """What every episode's recording holds, checked against its run JSON."""
    scene = run["scene"]
    statics = {entity("world", "room", "floor"), entity("world", "room", "walls"),
               entity("world", "plan", "paths"), entity("world", "plan", "standing"),
               entity("world", "plan", "targets"), "/plan", entity("plan", "relations"),
               entity("world", "robot", "body")}
    statics |= {entity("world", "tables", t["name"]) for t in scene["tables"]}
    statics |= {entity("world", "chairs", c.get("name") or f"chair {k + 1}")
                for k, c in enumerate(scene["chairs"])}
    assert statics <= rec.static, statics - rec.static
    # Each object: its shape in its kind's colour with its name, and its pose over time.
    for obj in run["planned"]["objects"]:
        path = entity("world", "objects", obj["name"])
        shape = "Cylinders3D" if obj["shape"] == "circle" else "Boxes3D"
        assert rec.column(path, f"{shape}:labels") == [[obj["name"]]]
        assert rec.column(path, f"{shape}:colors") == [[_rgba(kind_color(obj["kind"]))]]
        times = rec.times(path)
        assert times[0] == 0.0 and times == sorted(times)
    # The plan's numbers, as the run JSON has them.
    plan = run["plan"]
    assert rec.column("/plan", "expected_utility") == [[pytest.approx(plan["expected_utility"],
                                                                      abs=1e-3)]]
    assert rec.column("/plan", "feasibility") == [[pytest.approx(plan["feasibility"],
                                                                 abs=1e-4)]]
    assert rec.column("/plan", "expected_cost_s") == [[pytest.approx(plan["expected_cost_s"],
                                                                     abs=1e-3)]]
    relations = rec.column(entity("plan", "relations"), "TextDocument:text")[0][0]
    assert relations.count("\n- ") + 1 == len(run["planned"]["relations"])
    # Every attempt is an event at the time it ended, a failed one with its reason.
    texts = [t[0] for t in rec.column("/events", "TextLog:text")]
    steps = run["steps"]
    assert len(texts) == len(steps) + 1 and texts[-1].startswith("episode ended: ")
    for step, text in zip(steps, texts, strict=False):
        assert text.startswith(f"{step['action']} {step.get('object') or ''}".strip())
        if not step["ok"]:
            assert f"failed, {step['reason']}" in text
    ends = rec.times("/events")
    assert ends == sorted(ends)
    assert ends[-1] == pytest.approx(run["execution_time_s"], abs=2e-3)
    # The base over simulated time: from its start to where the episode ended.
    robot = rec.times(entity("world", "robot"))
    assert robot[0] == 0.0 and robot[-1] == pytest.approx(run["execution_time_s"], abs=0.3)
    start = rec.column(entity("world", "robot"), "Transform3D:translation")[0][0]
    assert start[:2] == pytest.approx(scene["robot"]["start"][:2], abs=1e-6)
    assert rec.times(entity("world", "trajectory"))


def test_a_2d_episode_is_recorded_on_simulated_time(tmp_path: Path) -> None:
    run, rec = _run(tmp_path)
    _common(run, rec)
    # No simulator streams in 2D: each drive is drawn along its path, 5 poses a second.
    driving = sum(s["duration_s"] for s in run["steps"] if s["action"] == "navigate")
    assert len(rec.times(entity("world", "robot"))) >= 4 * driving
    assert not {"/world/arm", "/world/scan"} & rec.entities


def test_a_mujoco_episode_also_records_the_arm_lidar_and_a_camera(tmp_path: Path) -> None:
    run, rec = _run(tmp_path, "--simulator", "mujoco", "--seed", "1",
                    "--sim-option", "record_cameras=[robot]")
    assert run["simulator"] == "mujoco"
    _common(run, rec)
    arm = rec.times("/world/arm")
    assert len(arm) >= run["execution_time_s"] / 0.2 - 5 and arm == sorted(arm)
    assert len(rec.column("/world/arm", "LineStrips3D:strips")[0][0]) == 8
    joints = {e for e in rec.entities if e.startswith("/arm/joints/")}
    assert joints == {f"/arm/joints/{j}" for j in ("shoulder_pan", "shoulder_lift", "elbow",
                                                   "wrist_1", "wrist_2", "wrist_3")}
    scans = rec.column("/world/scan", "Points3D:positions")
    assert len(scans) > 50 and max(len(s) for s in scans) > 100
    frames = rec.times(entity("cameras", "robot"))
    assert len(frames) >= run["execution_time_s"] / 5 - 2  # one every 5 simulated s


def test_a_recording_changes_nothing_in_the_run(tmp_path: Path) -> None:
    plain = tmp_path / "plain.json"
    assert main(["run", "--task", "8", *REPLAY, "--json", str(plain), "-q"]) == 0
    recorded, _ = _run(tmp_path)
    before = json.loads(plain.read_text())
    for doc in (before, recorded):
        doc.pop("planning_time_s")
        for call in (doc.get("llm") or {}).get("calls", []):
            call.pop("latency_s", None)
    assert before == recorded


def test_bench_records_each_trial_under_its_results(tmp_path: Path) -> None:
    out = tmp_path / "bench"
    assert main(["bench", "--tasks", "8", "--trials", "2", "--methods", "grop", *REPLAY,
                 "--no-images", "--rerun", "--out", str(out), "-q"]) == 0
    rows = [json.loads(line) for line in (out / "trials.jsonl").read_text().splitlines()]
    assert [r["recording"] for r in rows] == [f"recordings/task8_trial{k:02d}_grop.rrd"
                                              for k in range(2)]
    for row in rows:
        rec = Recording(out / row["recording"])
        assert len(rec.column("/events", "TextLog:text")) == len(row["steps"]) + 1


def test_a_simulator_never_loads_rerun() -> None:
    code = ("import sys; import llm_grop.simulation.mujoco.simulator, llm_grop.execution, "
            "llm_grop.simulation.kinematic2d, llm_grop.recording.stream; "
            "print('rerun' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, env=os.environ | {"MUJOCO_GL": "osmesa"})
    assert done.stdout.strip() == "False", done.stderr


@pytest.mark.parametrize(("path", "needle"), [
    ("missing/run.rrd", "does not exist"),
    ("run.txt", "ends in .rrd"),
    (".", "is a directory"),
])
def test_an_unwritable_recording_is_refused_before_any_work(tmp_path: Path, capsys,
                                                            monkeypatch, path: str,
                                                            needle: str) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--task", "8", "--llm", "openai", "--base-url",
                 "http://127.0.0.1:9/v1", "--rerun", path, "-q"]) == 2
    line = one_line_error(capsys)
    assert "--rerun" in line and needle in line


def test_without_the_extra_rerun_is_one_line(tmp_path: Path) -> None:
    # As where the [viz] extra is not installed: Python finds no rerun package.
    args = ["run", "--task", "8", *REPLAY, "--rerun", str(tmp_path / "r.rrd")]
    done = run_without_package("rerun", args)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert "--rerun: needs the optional [viz] extra" in done.stderr
    assert not (tmp_path / "r.rrd").exists()


@pytest.mark.parametrize(("make", "needle"), [
    (lambda d: d / "none.rrd", "no such file"),
    (lambda d: d, "is a directory"),
    (lambda d: (d / "x.rrd").write_text("not a recording") and d / "x.rrd",
     "not a Rerun recording"),
])
def test_view_refuses_what_is_no_recording(tmp_path: Path, capsys, make: Any,
                                           needle: str) -> None:
    assert main(["view", str(make(tmp_path))]) == 2
    assert needle in one_line_error(capsys)


def test_the_drive_is_filled_in_along_its_path() -> None:
    from llm_grop.recording.episode import along

    path = [(0.0, 0.0), (1.0, 0.0), (1.0, 3.0)]
    assert along(path, 0.0).x == 0.0
    mid = along(path, 0.5)
    assert (mid.x, mid.y) == pytest.approx((1.0, 1.0)) and mid.theta == pytest.approx(
        math.pi / 2)
    end = along(path, 1.0)
    assert (end.x, end.y) == pytest.approx((1.0, 3.0))
