"""Benchmarks cannot rot: every script under ``benchmarks/`` runs its ``--quick`` mode (a
tiny case of its real code path, a few seconds, figures printed as usual) in a subprocess
from the repository root, exits 0, prints no traceback and leaves the working tree as it
was. Scripts that need what a test machine lacks (an LLM server, the model) run with the
local stand-ins the other tests use: the embedded model's recorded answers replayed, a
loopback HTTP server."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"
#: Modules under benchmarks/ that are shared helpers, not scripts.
HELPERS = frozenset({"common.py"})
#: Scripts whose quick mode cannot run under the tests, with why (none today).
SKIPPED: dict[str, str] = {}
#: Seconds after which a quick run counts as hung: a safety net, not a timing assertion
#: (a quick run takes seconds).
HUNG_S = 300
SCRIPTS = sorted(p.name for p in BENCHMARKS.glob("*.py") if p.name not in HELPERS)


def _tree_state() -> str | None:
    """``git status`` of the working tree (``None`` outside a git checkout)."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        return None
    done = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=ROOT,
                          capture_output=True, text=True)
    return done.stdout if done.returncode == 0 else None


def test_every_script_is_found() -> None:
    assert len(SCRIPTS) >= 30 and "planning_time.py" in SCRIPTS


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda s: s.removesuffix(".py"))
def test_quick_mode_runs(script: str) -> None:
    if script in SKIPPED:
        pytest.skip(SKIPPED[script])
    before = _tree_state()
    try:
        done = subprocess.run([sys.executable, str(BENCHMARKS / script), "--quick"], cwd=ROOT,
                              env=os.environ | {"MUJOCO_GL": "osmesa"}, capture_output=True,
                              text=True, timeout=HUNG_S)
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f"benchmarks/{script} --quick still ran after {HUNG_S} s: {exc.stdout!r}")
    output = f"{done.stdout}\n{done.stderr}"
    assert done.returncode == 0, (
        f"benchmarks/{script} --quick exited {done.returncode}:\n{output[-4000:]}")
    assert "Traceback (most recent call last)" not in output, (
        f"benchmarks/{script} --quick printed a traceback:\n{output[-4000:]}")
    assert done.stdout.strip(), f"benchmarks/{script} --quick printed no figures"
    assert _tree_state() == before, f"benchmarks/{script} --quick changed the working tree"
