"""``llm-grop run``: the run JSON, the picture, the summary, warnings and bad input; and
``llm-grop bench``'s output directory and warnings."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from cli_support import REQUEST
from cli_support import one_line_error as _one_line_error
from cli_support import openai_flags as _openai
from llm_grop.cli import main
from scripted import TASK1_GOOD, scripted


def test_run_writes_run_json_and_picture(chat_server, tmp_path: Path, capsys,
                                         monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    out_json, out_png = tmp_path / "run.json", tmp_path / "run.png"
    code = main(["run", "--task", "1", *_openai(chat_server), "--seed", "2",
                 "--json", str(out_json), "--image", str(out_png)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "execution time" in printed and "planning" in printed
    assert re.search(r"rated [1-5]/5", printed) and "failed attempts" in printed
    data = json.loads(out_json.read_text())
    for key in ("method", "task", "seed", "success", "execution_time_s", "planning_time_s",
                "steps", "final"):
        assert key in data
    assert data["method"] == "llm-grop" and data["task"] == 1 and data["seed"] == 2
    assert data["steps"][0]["action"] == "navigate"
    assert {"table", "objects"} <= set(data["final"])
    assert len(data["scene"]["chairs"]) == 1
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_baseline_runs_without_an_llm(tmp_path: Path) -> None:
    out = tmp_path / "run.json"
    assert main(["run", REQUEST, "--method", "grop", "--llm", "openai",
                 "--base-url", "http://127.0.0.1:9", "--json", str(out), "-q"]) == 0
    assert json.loads(out.read_text())["method"] == "grop"


def _scene(tmp_path: Path, text: str) -> str:
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    return str(path)


ROOM = """
name: test
room: {width: 6.0, depth: 4.0}
tables:
  - {name: dining table, center: [3.0, 2.0], size: [0.9, 0.6]}
  - {name: counter, center: [0.4, 2.0], size: [0.5, 1.2]}
target: dining table
robot: {start: [1.5, 0.6, 0.0]}
"""


@pytest.mark.parametrize(("scene", "extra", "code", "needle"), [
    (ROOM + "sources:\n  - {object: diner plate, table: counter, position: [0.4, 2.0]}\n",
     [], 2, "sources[0] ('diner plate').object: unknown object; did you mean 'dinner plate'"),
    (ROOM + "sources:\n  - {object: dinner plate, table: counter, position: [0.4, 2.0]}\n"
     "  - {object: dinner fork, table: counter, position: [0.41, 2.0]}\n",
     [], 2, "sources[1] ('dinner fork').position"),
    (ROOM.replace("target: dining table", "target: kitchen table"), [], 2, "target"),
    (ROOM + "sources:\n  - {object: dinner plate, table: counter, position: [0.4, 3.99]}\n",
     [], 2, "sources[0]"),
    (ROOM + "walls:\n  - {center: [0.4, 3.0], size: [0.6, 0.1]}\n"
     "sources:\n  - {object: dinner plate, table: counter, position: [0.4, 3.0]}\n",
     [], 2, "sources[0]"),
    (ROOM + "chairs:\n  - {center: [3.0, 2.55], size: [1.6, 0.4]}\n"
     "  - {center: [3.0, 1.45], size: [1.6, 0.4]}\n"
     "  - {center: [2.3, 2.0], size: [0.4, 0.8]}\n"
     "  - {center: [3.7, 2.0], size: [0.4, 0.8]}\n", [], 1, "dining table"),
])
def test_bad_scenes(tmp_path: Path, capsys, scene: str, extra: list[str], code: int,
                    needle: str) -> None:
    args = ["run", REQUEST, "--method", "grop", "--scene", _scene(tmp_path, scene), "-q"]
    assert main(args + extra) == code
    assert needle in _one_line_error(capsys)


def test_object_out_of_every_reach(tmp_path: Path, capsys) -> None:
    # One object, 85 cm from the diner's edge by preference (no LLM call is needed): on a
    # 2.4 x 2 m table that is near the centre, 1 m from every edge, beyond the arm's reach
    # from any side.
    scene = _scene(tmp_path, ROOM.replace("[0.9, 0.6]", "[2.4, 2.0]")
                   .replace("[1.5, 0.6, 0.0]", "[0.6, 0.4, 0.0]"))
    args = ["run", "set the table with a fruit bowl", "--scene", scene, "--llm", "openai",
            "--base-url", "http://127.0.0.1:9", "--prefer",
            "the fruit bowl 85 cm from the diner's edge", "-q"]
    assert main(args) == 1
    assert "no standing position can reach 'fruit bowl'" in _one_line_error(capsys)


@pytest.mark.parametrize(("args", "needle"), [
    (["run"], "give a REQUEST or --task N"),
    (["run", REQUEST, "--method", "magic"], "unknown method 'magic'"),
    (["run", REQUEST, "--scene", "/nonexistent/scene.yaml"], "scene.yaml"),
    (["run", REQUEST, "--simulator", "gazebo"],
     "--simulator: unknown simulator 'gazebo' (available: kinematic2d"),
    (["run", REQUEST, "--llm", "claude"], "--llm: unknown backend 'claude' (available: embedded"),
])
def test_bad_flags(capsys, args: list[str], needle: str) -> None:
    assert main(args) == 2
    assert needle in _one_line_error(capsys)


# -- warnings and outputs (run and bench) ---------------------------------------------------

RECORDING = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "embedded_calls.jsonl"
REPLAY = ["--llm", "replay", "--replay", str(RECORDING)]


def test_run_prints_the_planned_warnings_on_stderr_unless_quiet(tmp_path: Path,
                                                                capsys) -> None:
    out = tmp_path / "run.json"
    assert main(["run", "--task", "1", *REPLAY, "--json", str(out)]) == 0
    printed = capsys.readouterr()
    warnings = json.loads(out.read_text())["planned"]["warnings"]
    assert warnings and "warning:" not in printed.out
    assert [line for line in printed.err.splitlines() if line.startswith("warning: ")] == \
        [f"warning: {w}" for w in warnings]
    assert main(["run", "--task", "1", *REPLAY, "-q"]) == 0
    printed = capsys.readouterr()
    assert printed.out == "" and "warning" not in printed.err


@pytest.mark.parametrize(("flags", "needle"), [
    (["--json", "{tmp}/run.json", "--image", "{tmp}/run.xyz"],
     "--image {tmp}/run.xyz: only PNG pictures are made; use a name ending in .png"),
    (["--json", "{tmp}/run.json", "--table-image", "{tmp}/table.jpg"],
     "--table-image {tmp}/table.jpg: only PNG pictures are made"),
    (["--json", "{tmp}/run.json", "--video", "{tmp}/episode.avi"],
     "--video {tmp}/episode.avi: the video must be an .mp4 file"),
    (["--json", "{tmp}/run.json", "--record", "{tmp}/no/calls.jsonl"],
     "--record {tmp}/no/calls.jsonl: directory {tmp}/no does not exist"),
])
def test_run_refuses_a_bad_output_before_any_llm_call(chat_server, tmp_path: Path, capsys,
                                                      monkeypatch, flags: list[str],
                                                      needle: str) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    args = [f.format(tmp=tmp_path) for f in flags]
    assert main(["run", "--task", "1", *_openai(chat_server), *args]) == 2
    assert needle.format(tmp=tmp_path) in _one_line_error(capsys)
    assert chat_server.requests == []
    assert list(tmp_path.iterdir()) == []  # the JSON was not written either


def test_run_in_centimetres_and_a_hint_for_metres(tmp_path: Path, capsys) -> None:
    assert main(["run", "--task", "1", *REPLAY, "--table", "round:120", "-q"]) == 2
    assert one_line_error_text(capsys).endswith("did you mean round:120cm?")
    out = tmp_path / "run.json"
    assert main(["run", "--task", "1", *REPLAY, "--table", "round:120cm", "-q",
                 "--json", str(out)]) == 0
    assert json.loads(out.read_text())["final"]["table"] == {"shape": "circle",
                                                             "size": [1.2, 1.2]}


def one_line_error_text(capsys) -> str:  # type: ignore[no-untyped-def]
    """The one error line, without its ``llm-grop: error:`` prefix."""
    return _one_line_error(capsys).removeprefix("llm-grop: error: ")


@pytest.mark.parametrize(("out", "needle"), [
    ("{tmp}/file", "'{tmp}/file' is a file"),  # click's own check
    ("{tmp}/file/bench", "--out {tmp}/file/bench: {tmp}/file is a file, so the directory "
                         "cannot be made"),
])
def test_bench_refuses_a_bad_out_before_any_llm_call(chat_server, tmp_path: Path, capsys,
                                                     monkeypatch, out: str,
                                                     needle: str) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    (tmp_path / "file").write_text("mine\n")
    assert main(["bench", "--tasks", "1", "--trials", "1", "--methods", "llm-grop",
                 *_openai(chat_server), "--out", out.format(tmp=tmp_path)]) == 2
    assert needle.format(tmp=tmp_path) in _one_line_error(capsys)
    assert chat_server.requests == []
    assert (tmp_path / "file").read_text() == "mine\n"


def test_bench_prints_each_trials_warnings(tmp_path: Path, capsys) -> None:
    out = tmp_path / "bench"
    assert main(["bench", "--tasks", "1", "--trials", "1", "--methods", "llm-grop", *REPLAY,
                 "--out", str(out), "--no-images"]) == 0
    err = capsys.readouterr().err
    row = json.loads((out / "trials.jsonl").read_text().splitlines()[0])
    warnings = row["planned"]["warnings"]
    assert warnings
    for w in warnings:
        assert f"warning: task 1 trial 0 llm-grop: {w}" in err.splitlines()


def test_cached_llm_calls_are_shown_as_cached(tmp_path: Path, chat_server,  # type: ignore[no-untyped-def]
                                              capsys: pytest.CaptureFixture[str]) -> None:
    """A second arrangement of the same task comes from the LLM cache, and the console
    says so rather than reporting the first call's latency as this run's."""
    chat_server.reply = scripted([TASK1_GOOD])
    flags = ["arrange", "--task", "1", *_openai(chat_server), "--cache-dir",
             str(tmp_path / "c")]
    assert main(flags) == 0
    first = capsys.readouterr().out
    assert main(flags) == 0
    second = capsys.readouterr().out
    assert "from the LLM cache" not in first
    assert re.search(r"LLM: openai / \S+, \d+ calls?, [\d.]+ s", first)
    assert re.search(r"\d+ calls?, all from the LLM cache \(answered at once; [\d.]+ s when "
                     r"first asked\)", " ".join(second.split()))
