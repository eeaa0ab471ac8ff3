"""The ``llm-grop arrange`` command as a user runs it: output files, exit codes, errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from cli_support import REQUEST
from cli_support import one_line_error as _one_line_error
from cli_support import openai_flags as _openai
from llm_grop.cli import main
from scripted import TASK1_GOOD, scripted


def test_arrange_writes_contract_json_and_png(chat_server, tmp_path: Path, capsys,
                                              monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    out_json, out_png = tmp_path / "t.json", tmp_path / "t.png"
    code = main(["arrange", REQUEST, *_openai(chat_server), "--seed", "1",
                 "--json", str(out_json), "--image", str(out_png)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "to the left of" in printed and "dinner knife" in printed
    data = json.loads(out_json.read_text())
    assert data["request"] == REQUEST
    assert data["table"] == {"shape": "rectangle", "size": [0.9, 0.6]}
    assert {o["name"] for o in data["objects"]} == {"dinner plate", "dinner fork", "dinner knife"}
    for o in data["objects"]:
        assert set(o) >= {"name", "x", "y", "yaw", "shape", "size", "on"}
    assert {"subject": "dinner fork", "relation": "to the left of",
            "reference": "dinner plate"} in data["relations"]
    # Template 1, two Template 2 questions and the plate's distance from the diner's edge.
    assert data["llm"]["backend"] == "openai" and data["llm"]["calls"] == 4
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_record_then_replay_is_byte_identical(chat_server, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    rec = tmp_path / "calls.jsonl"
    first = tmp_path / "first.json"
    assert main(["arrange", REQUEST, *_openai(chat_server), "--record", str(rec),
                 "--json", str(first), "-q"]) == 0
    assert len(rec.read_text().splitlines()) == 4
    replays = []
    for k in range(2):
        path = tmp_path / f"replay{k}.json"
        assert main(["arrange", REQUEST, "--llm", "replay", "--replay", str(rec),
                     "--json", str(path), "-q"]) == 0
        replays.append(path.read_bytes())
    assert replays[0] == replays[1]
    recorded, replayed = json.loads(first.read_text()), json.loads(replays[0])
    assert replayed["objects"] == recorded["objects"]
    assert replayed["relations"] == recorded["relations"]
    assert replayed["llm"]["log"] == recorded["llm"]["log"]


@pytest.mark.parametrize(("args", "code", "needle"), [
    (["arrange", ""], 2, "request: empty"),
    (["arrange", "   "], 2, "request: empty"),
    (["arrange", "set the table with a plate and a spork"], 2, "unknown object 'spork'"),
    (["arrange", REQUEST, "--table", "big"], 2, "--table"),
    (["arrange", REQUEST, "--llm", "gpt9"], 2, "unknown backend 'gpt9'"),
    (["arrange", REQUEST, "--llm", "replay"], 2, "--replay FILE"),
    (["arrange", "--task", "9"], 2, "task"),
    (["arrange", REQUEST, "--bogus-flag"], 2, "--bogus-flag"),
])
def test_bad_input_is_one_line_exit_2(args, code, needle, capsys) -> None:
    assert main(args) == code
    assert needle in _one_line_error(capsys)


def test_malformed_catalog_file(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "mine.yaml"
    bad.write_text("objects:\n  - name: saucer\n    shape: circle\n    size: [0.15]\n")
    assert main(["arrange", REQUEST, "--catalog", str(bad)]) == 2
    line = _one_line_error(capsys)
    assert "mine.yaml" in line and "size" in line


def test_unreachable_base_url(capsys, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    assert main(["arrange", REQUEST, "--llm", "openai", "--base-url", "http://127.0.0.1:9/v1",
                 "--retries", "0", "--timeout", "2"]) == 2
    assert "127.0.0.1:9" in _one_line_error(capsys)


def test_garbage_llm_fails_after_attempts(chat_server, capsys, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = lambda body: "Bananas are berries."
    assert main(["arrange", REQUEST, *_openai(chat_server), "--attempts", "2"]) == 2
    assert "no usable spatial relation in 2 attempt" in _one_line_error(capsys)


def test_table_too_small_exit_1(chat_server, capsys, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    assert main(["arrange", REQUEST, *_openai(chat_server), "--table", "0.2x0.2"]) == 1
    assert "too small" in _one_line_error(capsys)


def test_user_catalog_object_can_be_arranged(chat_server, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    mine = tmp_path / "mine.yaml"
    mine.write_text("objects:\n  - name: saucer\n    shape: circle\n    size: [0.15, 0.15]\n"
                    "    height: 0.015\n")
    chat_server.reply = scripted(["Place the dinner plate in the center of the table.\n"
                                  "Place the saucer above and to the right of the dinner plate."])
    out = tmp_path / "t.json"
    assert main(["arrange", "a dinner plate and a saucer", *_openai(chat_server),
                 "--catalog", str(mine), "--json", str(out), "-q"]) == 0
    assert {o["name"] for o in json.loads(out.read_text())["objects"]} == {"dinner plate",
                                                                          "saucer"}


@pytest.mark.embedded
def test_embedded_model_end_to_end(tmp_path: Path) -> None:
    """The real SmolLM2 model, through the installed console command, offline."""
    exe = Path(sys.executable).with_name("llm-grop")
    out_json, out_png = tmp_path / "t.json", tmp_path / "t.png"
    proc = subprocess.run([str(exe), "arrange", "--task", "1", "--seed", "0",
                           "--json", str(out_json), "--image", str(out_png)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    data = json.loads(out_json.read_text())
    assert data["llm"]["backend"] == "embedded"
    assert data["llm"]["model"] == "SmolLM2-135M-Instruct"
    assert {o["name"] for o in data["objects"]} == {"dinner plate", "dinner fork", "dinner knife"}
    assert data["relations"], "the model's consistent relations are kept"
    from llm_grop.arrangement.sampling import violations
    from llm_grop.world.serialize import arrangement_from_dict

    arr = arrangement_from_dict(data)
    from llm_grop.world.arrangement import Configuration

    assert violations(Configuration(arr.placements), arr.relations, arr.table) == []
    assert out_png.stat().st_size > 10_000
