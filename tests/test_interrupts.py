"""Interrupts at any moment, start-up included: one line, exit status 130 (Ctrl-C) or
143 (SIGTERM), and never a traceback, from the command or its workers."""

from __future__ import annotations

import random
import signal
import subprocess
import sys
import time
from pathlib import Path

RECORDING = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "embedded_calls.jsonl"
#: Moments tried (seconds after start) and the signal sent at each; seeded, so repeatable.
MOMENTS = [(round(random.Random(k).uniform(0.02, 4.0), 3),
            signal.SIGTERM if k % 5 == 4 else signal.SIGINT) for k in range(20)]


def test_interrupts_at_random_moments_print_one_line_and_no_traceback(tmp_path: Path) -> None:
    report = []
    for k, (after_s, sig) in enumerate(MOMENTS):
        out = tmp_path / f"bench{k}"
        proc = subprocess.Popen(
            [sys.executable, "-m", "llm_grop", "bench", "--tasks", "1", "--trials", "2",
             "--workers", "2", "--llm", "replay", "--replay", str(RECORDING), "--out",
             str(out), "--no-images", "-q"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        time.sleep(after_s)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=120)
        text = err.decode(errors="replace")
        report.append((after_s, sig.name, proc.returncode, text.strip()))
        assert "Traceback" not in text and "Error" not in text, report[-1]
        interrupted = 143 if sig == signal.SIGTERM else 130
        assert proc.returncode in (0, interrupted), report[-1]
        if proc.returncode:
            lines = [line for line in text.splitlines() if line.strip()]
            assert len(lines) == 1 and "interrupted" in lines[0], report[-1]
    print("\n".join(f"{t:5.2f} s {name:7s} exit {code}: {err}" for t, name, code, err in report))


def test_an_interrupt_inside_an_extensions_start_counts_as_an_interrupt() -> None:
    from llm_grop.errors import interrupted

    # pybind11 modules (mujoco's) stopped by Ctrl-C while they initialise raise this.
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as stop:
            raise ImportError("initialization failed") from stop
    except ImportError as exc:
        assert interrupted(exc)
    assert not interrupted(ImportError("No module named 'ray'"))
    assert interrupted(KeyboardInterrupt())
