"""The README's examples work as written: its scene file loads, and every Python example runs."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from llm_grop.world.scene_file import parse_scene
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
