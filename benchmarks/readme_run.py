"""Regenerates the README's `llm-grop run` example, console and JSON, from one run.

Runs the README's main job (Task 8, seed 0, the default method and simulator) with the
embedded model's answers replayed from ``benchmarks/data/embedded_calls.jsonl`` (the same
answers the model gives live, without loading it), writes ``docs/run.png``, and replaces
the README's blocks between the ``run example: console`` and ``run example: json``
markers: the console as printed (100 columns), and an excerpt of the run JSON.
``tests/test_readme.py`` checks that the two blocks agree with each other and with a
fresh run. ``--quick`` does all of it but writing: README.md and docs/run.png are left as
they are.
Run: .venv/bin/python benchmarks/readme_run.py [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from common import RECORDING, parse_args, scratch

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
COMMAND = ["run", "--task", "8", "--llm", "replay", "--replay", str(RECORDING)]
#: Width of the console the example is printed on, characters.
COLUMNS = 100


def _short(value: Any, points: int = 3) -> str:
    """``value`` as compact JSON, a long path cut to its first ``points`` points."""
    if isinstance(value, list) and len(value) > points and all(
            isinstance(v, list) for v in value):
        return json.dumps(value[:points], separators=(", ", ": "))[:-1] + ", ...]"
    return json.dumps(value, separators=(", ", ": "))


def _step(step: dict[str, Any]) -> str:
    return "{" + ", ".join(f'"{k}": {_short(v)}' for k, v in step.items()) + "}"


def excerpt(run: dict[str, Any]) -> str:
    """The README's excerpt of the run JSON ``run``: its own values, long parts elided."""
    plan = run["plan"]
    top = ", ".join(f'"{k}": {json.dumps(run[k])}' for k in ("method", "task", "seed"))
    chair = run["scene"].get("chairs") or []
    lines = [
        "{",
        f'  {top}, "request": "set the table with ...",',
        f'  "success": {json.dumps(run["success"])}, "execution_time_s": '
        f'{run["execution_time_s"]}, "planning_time_s": {run["planning_time_s"]},',
        f'  "failures": {run["failures"]}, "unplaced": {json.dumps(run["unplaced"])}, '
        f'"unplaced_reasons": {json.dumps(run.get("unplaced_reasons") or {})},',
        '  "steps": [',
        *(f"    {_step(s)}," for s in run["steps"][:4]),
        "    ...",
        "  ],",
        '  "final": {"request": "...", "table": ' + json.dumps(run["final"]["table"])
        + ', "objects": [' + _step(run["final"]["objects"][0]) + ", ...], "
        '"relations": [...]},',
        f'  "plan": {{"order": {json.dumps(plan["order"])},',
        f'           "standing": [{_step(plan["standing"][0])}, ...],',
        f'           "configuration_index": {plan["configuration_index"]}, "configurations": '
        f'{plan["configurations"]}, "expected_utility": {plan["expected_utility"]},',
        f'           "feasibility": {plan["feasibility"]}, "expected_cost_s": '
        f'{plan["expected_cost_s"]}, "expected_duration_s": {plan["expected_duration_s"]}}},',
        '  "planned": {"request": "...", "objects": [...], "relations": [...], "llm": {...}},',
        f'  "simulator": {json.dumps(run["simulator"])},',
        f'  "scene": {{"name": {json.dumps(run["scene"].get("name"))}, "room": '
        f'{json.dumps(run["scene"]["room"])}, "tables": [...], "chairs": '
        f'{json.dumps(chair[:1])}, ...}}',
        "}",
    ]
    return "\n".join(lines)


def replace_block(text: str, name: str, body: str, fence: str) -> str:
    """``text`` with the block between the ``run example: name`` markers set to ``body``."""
    pattern = re.compile(rf"(<!-- run example: {name} -->\n).*?(<!-- /run example: {name} -->)",
                         re.S)
    if not pattern.search(text):
        raise SystemExit(f"README.md has no 'run example: {name}' markers")
    return pattern.sub(lambda m: f"{m[1]}```{fence}\n{body}\n```\n{m[2]}", text)


def main() -> None:
    args = parse_args(argparse.ArgumentParser(description=__doc__.splitlines()[0]))
    image = scratch("readme-run") / "run.png" if args.quick else ROOT / "docs" / "run.png"
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run.json"
        env = os.environ | {"COLUMNS": str(COLUMNS), "NO_COLOR": "1"}
        done = subprocess.run([sys.executable, "-m", "llm_grop", *COMMAND, "--json", str(out),
                               "--image", str(image)], cwd=tmp, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              check=True)
        run = json.loads(out.read_text())
    console = done.stdout.replace(str(out), "run.json") \
        .replace(str(image), "run.png").rstrip()
    text = README.read_text()
    text = replace_block(text, "console", console, "")
    text = replace_block(text, "json", excerpt(run), "json")
    if not args.quick:
        README.write_text(text)
    print(console)


if __name__ == "__main__":
    main()
