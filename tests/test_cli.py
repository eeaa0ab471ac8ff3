"""The ``llm-grop arrange`` command as a user runs it: output files, exit codes, errors."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import threading
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
            "reference": "dinner plate", "source": "llm"} in data["relations"]
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
        # Without the cache: a second run answered from it would say so in its log.
        assert main(["arrange", REQUEST, "--llm", "replay", "--replay", str(rec),
                     "--json", str(path), "--no-cache", "-q"]) == 0
        replays.append(path.read_bytes())
    assert replays[0] == replays[1]
    recorded, replayed = json.loads(first.read_text()), json.loads(replays[0])
    assert replayed["objects"] == recorded["objects"]
    assert replayed["relations"] == recorded["relations"]
    assert replayed["llm"]["log"] == recorded["llm"]["log"]


@pytest.mark.parametrize(("args", "code", "needle"), [
    (["arrange", ""], 2, "request: empty"),
    (["arrange", "   "], 2, "request: empty"),
    (["arrange", "happiness and a spork"], 2, "unknown object 'happiness'"),
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
                 "--retries", "0", "--timeout", "2"]) == 3  # unavailable: not bad input
    assert "127.0.0.1:9" in _one_line_error(capsys)


def test_garbage_llm_fails_after_attempts(chat_server, capsys, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = lambda body: "Bananas are berries."
    assert main(["arrange", REQUEST, *_openai(chat_server), "--attempts", "2"]) == 2
    assert "no usable spatial relation in 2 attempt" in _one_line_error(capsys)


def test_table_too_small_exit_1(chat_server, tmp_path: Path, capsys, monkeypatch) -> None:
    # The smallest table --table accepts (30 cm a side) still cannot hold a 45 cm tray.
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    mine = tmp_path / "mine.yaml"
    mine.write_text("objects:\n  - name: serving tray\n    shape: box\n"
                    "    size: [0.45, 0.35]\n    height: 0.02\n")
    chat_server.reply = scripted(["Place the serving tray in the center of the table.\n"
                                  "Place the dinner fork to the left of the serving tray."])
    assert main(["arrange", "a serving tray and a dinner fork", *_openai(chat_server),
                 "--catalog", str(mine), "--table", "30x30cm"]) == 1
    assert "0.3 x 0.3 m table is too small for serving tray" in _one_line_error(capsys)


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
    from llm_grop.contract.serialize import arrangement_from_dict

    arr = arrangement_from_dict(data)
    from llm_grop.world.arrangement import Configuration

    assert violations(Configuration(arr.placements), arr.relations, arr.table) == []
    assert out_png.stat().st_size > 10_000


# -- --table: units and plausible sizes -----------------------------------------------------

RECORDING = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "embedded_calls.jsonl"
REPLAY = ["--llm", "replay", "--replay", str(RECORDING)]


def test_a_table_far_too_large_is_bad_input_not_a_memory_error(capsys) -> None:
    # It used to reach the layout, which tried a billion push steps: MemoryError, exit 3.
    assert main(["arrange", "--task", "1", "--table", "1000000000x1000000000", *REPLAY]) == 2
    assert _one_line_error(capsys) == ("llm-grop: error: --table: 1e+09 x 1e+09 m is not a "
                                       "dining table (each side between 0.3 and 10 m)")


def test_a_table_in_centimetres(chat_server, tmp_path: Path, capsys, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    out = tmp_path / "t.json"
    assert main(["arrange", REQUEST, *_openai(chat_server), "--table", "120x80",
                 "--json", str(out)]) == 2
    assert _one_line_error(capsys) == (
        "llm-grop: error: --table: 120 x 80 m is not a dining table (each side between 0.3 "
        "and 10 m); did you mean 120x80cm?")
    assert not chat_server.requests and not out.exists()
    assert main(["arrange", REQUEST, *_openai(chat_server), "--table", "120x80cm",
                 "--json", str(out), "-q"]) == 0
    assert json.loads(out.read_text())["table"] == {"shape": "rectangle", "size": [1.2, 0.8]}


def test_every_command_has_the_same_table_flag() -> None:
    from llm_grop.cli import cli

    flags = [next(p for p in cli.commands[c].params if p.name == "table")
             for c in ("arrange", "run", "bench")]
    for flag in flags:
        assert flag.opts == ["--table"] and flag.metavar == "WxD|round:D"
        assert flag.help == flags[0].help and flag.callback is flags[0].callback
    assert "120x80cm" in (flags[0].help or "") and "round:120cm" in (flags[0].help or "")


# -- outputs: checked before the LLM is paid for, written all or none -----------------------

@pytest.mark.parametrize(("flags", "needle"), [
    (["--json", "{tmp}/missing/t.json"], "--json {tmp}/missing/t.json: directory "
                                         "{tmp}/missing does not exist"),
    (["--json", "{tmp}"], "is a directory"),
    (["--json", "{tmp}/t.json", "--image", "{tmp}/t.xyz"],
     "--image {tmp}/t.xyz: only PNG pictures are made; use a name ending in .png"),
    (["--json", "{tmp}/t.json", "--image", "{tmp}/missing/t.png"],
     "--image {tmp}/missing/t.png: directory {tmp}/missing does not exist"),
    (["--json", "{tmp}/t.json", "--record", "{tmp}/missing/calls.jsonl"],
     "--record {tmp}/missing/calls.jsonl: directory {tmp}/missing does not exist"),
    (["--json", "{tmp}/t.json", "--image", "{tmp}/" + "n" * 300 + ".png"], "File name too long"),
])
def test_a_bad_output_is_refused_before_any_llm_call(chat_server, tmp_path: Path, capsys,
                                                     monkeypatch, flags: list[str],
                                                     needle: str) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    args = [f.format(tmp=tmp_path) for f in flags]
    assert main(["arrange", REQUEST, *_openai(chat_server), *args]) == 2
    assert needle.format(tmp=tmp_path) in _one_line_error(capsys)
    assert chat_server.requests == []  # nothing was paid for
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # and nothing was written


def test_a_bad_image_keeps_the_users_json(chat_server, tmp_path: Path, capsys,
                                          monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    mine = tmp_path / "t.json"
    mine.write_text("my own notes\n")
    assert main(["arrange", REQUEST, *_openai(chat_server), "--json", str(mine),
                 "--image", str(tmp_path / "t.jpg")]) == 2
    assert "--image" in _one_line_error(capsys)
    assert mine.read_text() == "my own notes\n" and not chat_server.requests
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.json"]


def test_outputs_with_long_names_are_written(tmp_path: Path) -> None:
    # Temporary files beside them keep short names, whatever the output's.
    name = "n" * 240
    out_json, out_png = tmp_path / f"{name}.json", tmp_path / f"{name}.png"
    assert main(["arrange", "--task", "1", *REPLAY, "--json", str(out_json),
                 "--image", str(out_png), "-q"]) == 0
    assert json.loads(out_json.read_text())["objects"]
    assert sorted(p.name for p in tmp_path.iterdir()) == [out_json.name, out_png.name]


def test_staged_outputs_are_written_all_or_none(tmp_path: Path) -> None:
    from llm_grop.cli.options import StagedOutputs
    from llm_grop.errors import BadInput
    from llm_grop.files.jsonio import write_json

    first, second = tmp_path / "a.json", tmp_path / "b.json"
    first.write_text("old\n")
    with pytest.raises(BadInput, match=r"^--image: .*b\.json: cannot write"), \
            StagedOutputs() as outputs:
        outputs.write("json", first, lambda p: write_json(p, {"new": True}))
        # A real writer that fails: its directory does not exist.
        outputs.write("image", second,
                      lambda p: write_json(tmp_path / "gone" / second.name, {}))
        outputs.commit()
    assert first.read_text() == "old\n"  # the user's file is kept, never half replaced
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]  # no temporary file left
    with StagedOutputs() as outputs:
        outputs.write("json", first, lambda p: write_json(p, {"new": True}))
        outputs.write("json", second, lambda p: write_json(p, {"two": 2}))
        outputs.commit()
    assert json.loads(first.read_text()) == {"new": True}
    assert json.loads(second.read_text()) == {"two": 2}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "b.json"]


def _read_fifo(path: Path) -> tuple[threading.Thread, list[bytes]]:
    """A reader of the named pipe ``path``, started: what it read lands in the list."""
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(path.read_bytes()), daemon=True)
    reader.start()
    return reader, got


def test_outputs_write_through_links_and_into_pipes(tmp_path: Path) -> None:
    """A link stays a link (its target is replaced) and a pipe stays a pipe (written
    into), whichever writer: ``--json /dev/stdout`` must never replace ``/dev/stdout``."""
    from llm_grop.cli.options import StagedOutputs
    from llm_grop.files.jsonio import write_json

    target, link = tmp_path / "target.json", tmp_path / "link.json"
    target.write_text("old\n")
    link.symlink_to(target)
    write_json(link, {"one": 1})
    with StagedOutputs() as outputs:
        outputs.write("json", link, lambda p: write_json(p, {"two": 2}))
        outputs.commit()
    assert link.is_symlink() and json.loads(target.read_text()) == {"two": 2}
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    for write in (lambda: write_json(fifo, {"three": 3}), lambda: _staged(fifo)):
        reader, got = _read_fifo(fifo)
        write()
        reader.join(10)
        assert json.loads(got[0]) in ({"three": 3}, {"four": 4})
        assert stat.S_ISFIFO(fifo.stat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.json", "pipe.json",
                                                          "target.json"]


def _staged(path: Path) -> None:
    from llm_grop.cli.options import StagedOutputs
    from llm_grop.files.jsonio import write_json

    with StagedOutputs() as outputs:
        outputs.write("json", path, lambda p: write_json(p, {"four": 4}))
        outputs.commit()


def test_learn_writes_into_a_pipe_without_force(tmp_path: Path, capsys) -> None:
    from learning_support import LEFT_HANDED, write_example

    example = write_example(tmp_path / "left.json", LEFT_HANDED, 1)
    fifo = tmp_path / "prefs.yaml"
    os.mkfifo(fifo)
    reader, got = _read_fifo(fifo)
    assert main(["learn", str(example), "--out", str(fifo), "--exact", "-q"]) == 0
    reader.join(10)
    assert got[0].startswith(b"# Preferences learned") and stat.S_ISFIFO(fifo.stat().st_mode)


def test_write_json_is_atomic_and_keeps_the_files_mode(tmp_path: Path) -> None:
    from llm_grop.errors import BadInput
    from llm_grop.files.jsonio import write_json

    path = tmp_path / "t.json"
    path.write_text("old\n")
    path.chmod(0o640)
    (tmp_path / ".t.json.tmp").write_text("a user's file with write_json's old temp name\n")
    with pytest.raises(TypeError):
        write_json(path, {"x": object()})  # cannot be JSON: nothing is touched
    write_json(path, {"x": 1})
    assert json.loads(path.read_text()) == {"x": 1} and path.stat().st_mode & 0o777 == 0o640
    with pytest.raises(BadInput, match="cannot write"):
        write_json(tmp_path, {"x": 1})  # a directory
    assert sorted(p.name for p in tmp_path.iterdir()) == [".t.json.tmp", "t.json"]


# -- warnings -------------------------------------------------------------------------------

def test_arrange_prints_warnings_on_stderr_unless_quiet(tmp_path: Path, capsys) -> None:
    out = tmp_path / "t.json"
    assert main(["arrange", "--task", "1", *REPLAY, "--json", str(out)]) == 0
    printed = capsys.readouterr()
    warnings = json.loads(out.read_text())["warnings"]
    assert warnings and "warning:" not in printed.out
    assert [line for line in printed.err.splitlines() if line.startswith("warning: ")] == \
        [f"warning: {w}" for w in warnings]
    assert main(["arrange", "--task", "1", *REPLAY, "-q"]) == 0
    printed = capsys.readouterr()
    assert printed.out == "" and "warning" not in printed.err


def test_a_long_warning_is_one_short_line() -> None:
    from llm_grop.cli.console import WARNING_CHARS, one_line

    text = "the other relations keep\nthe dinner fork " + "far away " * 60
    line = one_line(text)
    assert "\n" not in line and len(line) == WARNING_CHARS and line.endswith("…")
    assert one_line("short  and\nplain") == "short and plain"


def test_a_request_in_brackets_is_printed_as_written(chat_server, capsys, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD])
    request = "[/the] a dinner plate, a dinner fork and a dinner knife [the]"
    assert main(["arrange", request, *_openai(chat_server)]) == 0
    assert f"Request: {request}" in capsys.readouterr().out


def test_objects_the_matcher_cannot_read_are_read_by_the_llm(chat_server, tmp_path: Path,
                                                             capsys, monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD], reading=(
        'diners: 1\nobject: 1 dinner plate | "a dinner plate"\n'
        'object: 1 dinner fork | "cutlery"\nobject: 1 dinner knife | "cutlery"'))
    out = tmp_path / "t.json"
    assert main(["arrange", "a dinner plate and cutlery", *_openai(chat_server),
                 "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["request_read_by"] == "llm"
    assert [(o["kind"], o["source"], o["words"]) for o in data["objects"]] == [
        ("dinner plate", "request", "a dinner plate"), ("dinner fork", "llm", "cutlery"),
        ("dinner knife", "llm", "cutlery")]
    err = capsys.readouterr().err
    assert ("warning: the openai LLM chose what the request does not say: 1 dinner fork "
            "(for 'cutlery'), 1 dinner knife (for 'cutlery'); --no-guess refuses this") in err
    assert main(["arrange", "a dinner plate and cutlery", *_openai(chat_server),
                 "--no-guess"]) == 2
    assert "--no-guess forbids it" in _one_line_error(capsys)


@pytest.mark.parametrize(("request_text", "start"), [
    ("happiness", "request: unknown object 'happiness'"),
    ("стол с тарелкой", "request: unknown object"),
    ("x" * 5000, "request: 5000 characters"),
    ("a table for 13", "request: 'for 13': between 1 and 12 diners"),
    ("13 forks", "request: '13 forks': at most 12 of one object"),
    ("the fork -2 cm to the left of the plate", "request: '-2 cm': a distance must not be"),
    ("the fork 3 metres to the left of the plate", "request: 'the fork 3 metres to the left "
                                                   "of the plate': 300 cm does not fit"),
    ("the mug 70 cm behind the plate", "request: 'the mug 70 cm behind the plate': 70 cm does "
                                       "not fit on the 0.9 x 0.6 m table"),
    ("the fork to the left of the plate and the plate to the left of the fork",
     "request: the request's relations contradict each other: 'the fork to the left of the "
     "plate' (the request); 'the plate to the left of the fork' (the request)"),
    # The LLM is asked (here a recording of no call, so it cannot answer).
    ("set the table with ² dinner plates and ①", "no_calls.jsonl: no recorded response for "
                                                 "prompt 'A robot sets a dining table"),
])
def test_requests_nothing_can_read_are_one_line_errors(request_text: str, start: str,
                                                       capsys) -> None:
    code = main(["arrange", request_text, "--llm", "replay", "--replay",
                 str(Path(__file__).parent / "arrangement" / "no_calls.jsonl")])
    assert code == 2
    assert _one_line_error(capsys).startswith(f"llm-grop: error: {start}")


@pytest.mark.parametrize(("reading", "start"), [
    ('{"diners": 1, "objects": [], "relations": []}',
     "request: the openai LLM read no object in 'set the table with happiness'; name the "
     "objects to set"),
    ('{"diners": 1, "objects": [{"name": "salt shaker", "count": 1, "words": "happiness"}], '
     '"relations": []}', "request: the openai LLM's reading: unknown object 'salt shaker'"),
    ('{"diners": 13, "objects": [{"name": "plate", "count": 1, "words": "table"}], '
     '"relations": []}', "request: the openai LLM's reading: 13 diners; between 1 and 12"),
])
def test_what_the_llm_reads_is_checked_on_the_command_line(reading: str, start: str,
                                                           chat_server, capsys,
                                                           monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.reply = scripted([TASK1_GOOD], reading=reading)
    code = main(["arrange", "set the table with happiness", *_openai(chat_server)])
    assert code == 2
    assert _one_line_error(capsys).startswith(f"llm-grop: error: {start}")


def test_a_request_that_is_not_utf8_is_one_line(tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, "-m", "llm_grop", "arrange", b"a plate \xff",
                           "--llm", "replay", "--replay",
                           str(Path(__file__).parent / "arrangement" / "no_calls.jsonl")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "not UTF-8 text" in done.stderr


def test_a_step_row_counts_failed_attempts() -> None:
    """The execution table says "failed attempts", as the result line does, never
    "failures" beside a success."""
    from llm_grop.cli.console import _attempts
    from llm_grop.world.plan import ExecutedStep

    failed = ExecutedStep("place", False, 2.0, "mug", reason="no_ik")
    done = ExecutedStep("place", True, 2.0, "mug", attempt=2)
    assert _attempts([failed, done]) == "ok after 1 failed attempt (no ik)"
    assert _attempts([failed, failed, done]) == "ok after 2 failed attempts (no ik)"
    assert _attempts([done]) == "ok"
