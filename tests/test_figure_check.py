"""The README's figures check (``benchmarks/figure_versions.py --check``): each figure names
its version and what made it, and the version is the project's major and minor."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "figure_versions.py"


@pytest.fixture(scope="module")
def figures():
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        import figure_versions
    finally:
        sys.path.remove(str(SCRIPT.parent))
    return figure_versions


def _problems(figures, text: str, current: str = "0.17.0") -> list[str | None]:
    return [figures.problem(f, current, ROOT) for f in figures.inventory(text)]


def test_a_current_figure_with_its_script_passes(figures) -> None:
    text = ("Intro.\n\nMeasured (`benchmarks/sampler.py`, version 0.17.0; version 0.9.0 "
            "took twice as long): 3 ms.\n\n![a table](docs/table.png)\n\n"
            "(Printed by `llm-grop arrange`, version 0.17.2.)\n")
    assert _problems(figures, text) == [None, None, None]


@pytest.mark.parametrize(("text", "why"), [
    ("Measured with version 0.16.0 (`benchmarks/sampler.py`): 3 ms.", "measured with 0.16.0"),
    ("Measured with version 0.17.0: 3 ms.", "names no script"),
    ("Measured with version 0.17.0 (`benchmarks/no_such_script.py`).", "does not exist"),
    ("Before.\n\n![a table](docs/table.png)\n\nAfter.", "names no version"),
    ("Slow clients (`benchmarks/stalled_connections.py`): closed after 9.8 s.",
     "names no version"),
    ("Screenshots: [phone](docs/serve/phone.png), version 0.12.0 of `llm-grop serve`.",
     "measured with 0.12.0"),
])
def test_a_stale_or_unnamed_figure_fails(figures, text: str, why: str) -> None:
    problems = _problems(figures, text)
    assert len(problems) == 1 and problems[0] is not None and why in problems[0]


def test_names_may_break_across_lines(figures) -> None:
    text = "Measured (`llm-grop\nrun --task 8`, version\n0.17.0): 3 ms."
    (figure,) = figures.inventory(text)
    assert figure.versions == ("0.17.0",) and figure.makers == ("llm-grop run",)


def test_a_version_in_a_code_block_belongs_to_its_paragraph(figures) -> None:
    text = "```\nline\n\nversion 0.17.0 (`benchmarks/sampler.py`)\n```\n"
    assert [f.line for f in figures.inventory(text)] == [1]


def test_the_readme_passes() -> None:
    done = subprocess.run([sys.executable, str(SCRIPT), "--check"], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr
