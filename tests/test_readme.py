"""The README's examples work as written: its scene file loads, and every Python example runs."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from llm_grop.files.scene_file import parse_scene
from scripted import scripted

README = Path(__file__).resolve().parents[1] / "README.md"

TASK8 = (
    "Place the dinner plate in the center of the table.\n"
    "Place the dinner fork to the left of the dinner plate.\n"
    "Place the dinner knife to the right of the dinner plate.\n"
    "Place the mug lid above and to the right of the dinner plate.\n"
    "Place the mug on top of the mug lid."
)

#: Runs each block of a JSON list in a fresh namespace, in order, naming the block on failure.
RUNNER = """\
import json, sys
for i, code in enumerate(json.load(open(sys.argv[1], encoding="utf-8")), 1):
    exec(compile(code, f"README.md python example {i}", "exec"), {"__name__": "__main__"})
"""


def blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README.read_text(), flags=re.S)


def test_readme_scene_example_loads() -> None:
    scenes = [b for b in blocks("yaml") if b.startswith("room:")]
    assert scenes
    for text in scenes:
        scene = parse_scene(text, "README.md")
        assert scene.target == "dining table" and scene.chairs


@pytest.mark.embedded
def test_every_python_example_runs(chat_server, tmp_path: Path) -> None:
    """In order, in one fresh process, in an empty directory; `llm="openai"` talks to a
    local OpenAI-compatible server, the rest uses the embedded model, as a new user's would."""
    examples = blocks("python")
    assert len(examples) >= 4
    chat_server.reply = scripted([TASK8])
    (tmp_path / "examples.json").write_text(json.dumps(examples), encoding="utf-8")
    env = {**os.environ, "OPENAI_BASE_URL": chat_server.url, "OPENAI_API_KEY": "test"}
    done = subprocess.run([sys.executable, "-c", RUNNER, "examples.json"], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert (tmp_path / "run.png").stat().st_size > 0
    assert chat_server.requests, "the openai example never reached the server"


def _block(name: str) -> str:
    text = README.read_text()
    m = re.search(rf"<!-- run example: {name} -->\n```\w*\n(.*?)```", text, flags=re.S)
    assert m, f"README.md has no 'run example: {name}' block"
    return m[1]


def test_run_example_console_and_json_agree_with_each_other_and_a_fresh_run(
        tmp_path: Path) -> None:
    """The README's run example: its console and its JSON excerpt come from one run, and the
    README's command (the embedded model's answers replayed) still gives that run."""
    from llm_grop.cli import main

    console, excerpt = _block("console"), _block("json")
    config = re.search(r"configuration (\d+) of (\d+)", console)
    result = re.search(r"Result: (\w+), rated [1-5]/5; execution time ([\d.]+) s .*?; "
                       r"failed attempts (\d+)", console)
    assert config and result
    number = lambda key: re.search(rf'"{key}": ([\d.]+)', excerpt)[1]  # noqa: E731
    assert int(config[1]) == int(number("configuration_index"))  # one numbering, from 0
    assert int(config[2]) == int(number("configurations"))
    assert result[1] == ("success" if '"success": true' in excerpt else "failed")
    assert result[2] == f"{float(number('execution_time_s')):.1f}"
    assert result[3] == number("failures")
    out = tmp_path / "run.json"
    recording = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / \
        "embedded_calls.jsonl"
    assert main(["run", "--task", "8", "--llm", "replay", "--replay", str(recording),
                 "--json", str(out), "-q"]) == 0
    run = json.loads(out.read_text())
    assert run["plan"]["configuration_index"] == int(number("configuration_index"))
    assert run["execution_time_s"] == float(number("execution_time_s"))
    assert run["failures"] == int(number("failures"))
    assert json.dumps(run["steps"][0]["goal"]) in excerpt
