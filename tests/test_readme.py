"""The README's scene example is a valid scene file."""

from __future__ import annotations

import re
from pathlib import Path

from llm_grop.world.scene_file import parse_scene

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_scene_example_loads() -> None:
    blocks = re.findall(r"```yaml\n(.*?)```", README.read_text(), flags=re.S)
    scenes = [b for b in blocks if b.startswith("room:")]
    assert scenes
    for text in scenes:
        scene = parse_scene(text, "README.md")
        assert scene.target == "dining table" and scene.chairs
