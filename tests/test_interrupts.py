"""Interrupts at any moment, start-up included: one line, exit status 130 (Ctrl-C) or
143 (SIGTERM), and never a traceback, from the command or its workers."""

from __future__ import annotations

import json
import os
import random
import re
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest

from llm_grop.experiment.ray_loopback import RAY_LOOPBACK_SWITCH

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


def test_a_failure_after_an_interrupt_is_reported_as_the_interrupt(tmp_path: Path,
                                                                   capsys) -> None:
    # Raised inside shapely while an affine matrix was being built, an interrupt once came
    # out as "ValueError: Invalid affine transformation matrix", with no KeyboardInterrupt
    # in its chain: the console script says a signal arrived, and that is what is told.
    from llm_grop.cli import main

    missing = str(tmp_path / "missing.json")
    out = str(tmp_path / "p.yaml")
    assert main(["learn", missing, "--exact", "--out", out], signalled=lambda: True) == 130
    assert capsys.readouterr().err == "llm-grop: interrupted\n"
    assert main(["learn", missing, "--exact", "--out", out], signalled=lambda: False) == 2
    assert "missing.json" in capsys.readouterr().err


# -- SIGTERM under every executor: 143, one line, no native stack dump, rows kept ----------

#: A line an interrupted bench prints: the command's own, or the entry point's before it.
INTERRUPTED_LINE = re.compile(r"(interrupted: \d+ finished trial\(s\) are saved in \S+"
                              r"trials\.jsonl; rerun the same command to resume"
                              r"|llm-grop: interrupted)")
#: The executors tried, and their flags (one local worker runs trials in the driver itself).
EXECUTORS = {"local-1": ["--workers", "1"], "local-2": ["--workers", "2"],
             "ray": ["--executor", "ray", "--workers", "2"]}


def _tagged(tag: str) -> list[str]:
    """The command lines of the processes whose environment holds ``tag``: the bench and
    everything it started, Ray's processes included."""
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                if tag.encode() in Path(f"/proc/{entry}/environ").read_bytes():
                    cmd = Path(f"/proc/{entry}/cmdline").read_bytes().replace(b"\0", b" ")
                    found.append(f"{entry} {cmd.decode(errors='replace').strip()}")
            except OSError:  # gone, or a kernel thread
                pass
    return found


def _rows(out: Path) -> list[tuple[int, int, str]]:
    path = out / "trials.jsonl"
    if not path.exists():
        return []
    return [(r["task"], r["trial"], r["method"])
            for r in map(json.loads, path.read_text().splitlines())]


def _wait(until, proc: subprocess.Popen, what: str) -> None:
    deadline = time.monotonic() + 300
    while not until():
        assert proc.poll() is None, f"the bench ended before {what}"
        assert time.monotonic() < deadline, f"no {what} within 300 s"
        time.sleep(0.02)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("executor, moment", [
    ("local-1", "mid-bench"), ("local-2", "mid-bench"), ("ray", "start-up"),
    ("ray", "mid-bench")])
def test_sigterm_is_143_and_one_line_under_every_executor(executor: str, moment: str,
                                                          tmp_path: Path) -> None:
    if executor == "ray":
        pytest.importorskip("ray")
    out = tmp_path / "bench"
    tag = f"llm-grop-test-{uuid.uuid4().hex}"
    # Ray's cluster on loopback only, never on this machine's network address.
    env = dict(os.environ, LLM_GROP_TEST_TAG=tag) | {RAY_LOOPBACK_SWITCH: "0"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "llm_grop", "bench", "--tasks", "1,2", "--trials", "3",
         "--llm", "replay", "--replay", str(RECORDING), "--out", str(out), "--no-images",
         "-q", *EXECUTORS[executor]], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    try:
        if moment == "start-up":
            # Ray's first process is up: ray.init is still starting the cluster.
            _wait(lambda: any("gcs_server" in p for p in _tagged(tag)), proc, "Ray's GCS")
        else:
            _wait(lambda: _rows(out), proc, "a finished trial")
        before = _rows(out)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=180)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    text = err.decode(errors="replace")
    lines = [line for line in text.splitlines() if line.strip()]
    assert proc.returncode == 143, (proc.returncode, text)
    assert len(lines) == 1 and INTERRUPTED_LINE.fullmatch(lines[0]), text
    assert "SIGTERM received" not in text and "PC: @" not in text
    after = _rows(out)
    assert after[:len(before)] == before and len(set(after)) == len(after)
    # Nothing the bench started outlives it (the watchdog of a Ray cluster looks twice a
    # second).
    deadline = time.monotonic() + 30
    while _tagged(tag) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not _tagged(tag)


def test_the_import_systems_lock_callback_counts_as_cleanup() -> None:
    # An interrupt raised there is printed as "Exception ignored in: <function
    # _get_module_lock.<locals>.cb>" with a traceback and lost (seen once in CI).
    import sys

    from llm_grop.entry import _in_cleanup

    space: dict = {"__name__": "_frozen_importlib", "sys": sys}
    exec("def cb(ref=None):\n    return sys._getframe()\n", space)
    assert _in_cleanup(space["cb"]())
    space["__name__"] = "llm_grop.somewhere"
    assert not _in_cleanup(space["cb"]())
