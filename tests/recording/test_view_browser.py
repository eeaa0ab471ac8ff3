"""``llm-grop view --web``: Rerun's bundled web viewer, served on 127.0.0.1, opened in
Debian's Chromium (software rendering, no network beyond loopback), shows the recording
of a run: the viewer's state (read from the page) has it open, with views of its
entities. The screenshot goes to
``$LLM_GROP_SCREENSHOTS`` (the README's is made so)."""

from __future__ import annotations

import contextlib
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from browser_support import CHROMIUM, DESKTOP, FLAGS, screenshots  # noqa: F401 - a fixture
from llm_grop.cli import main
from recording_support import REPLAY, rerun_env

pytest.importorskip("rerun")
sync_api = pytest.importorskip("playwright.sync_api")

#: Chromium with no name resolution but loopback (the page asks for web fonts), drawing
#: WebGL with its software rasteriser.
VIEWER_FLAGS = [*FLAGS, '--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1',
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
#: Seconds the viewer may take to start, load its WebAssembly and the recording.
LOAD_S = 120.0


@pytest.fixture(scope="module")
def chromium() -> Iterator[object]:
    assert CHROMIUM.exists(), "Debian's chromium is missing: run scripts/setup.sh --dev"
    with sync_api.sync_playwright() as pw:
        launched = pw.chromium.launch(executable_path=str(CHROMIUM), args=VIEWER_FLAGS)
        yield launched
        launched.close()


def strings(data: bytes) -> list[str]:
    """Every text field of a protobuf message (the viewer's encoded state), nested
    messages included: a length-delimited field whose bytes parse as a message is read
    as one, else kept as text when it is UTF-8."""
    found: list[str] = []

    def varint(k: int) -> tuple[int, int]:
        value = shift = 0
        while True:
            byte = data[k]
            value |= (byte & 0x7F) << shift
            k += 1
            if byte < 0x80:
                return value, k
            shift += 7

    def walk(lo: int, hi: int) -> bool:
        k, out = lo, []
        try:
            while k < hi:
                key, k = varint(k)
                wire = key & 7
                if wire == 0:
                    _, k = varint(k)
                elif wire == 1:
                    k += 8
                elif wire == 5:
                    k += 4
                elif wire == 2:
                    n, k = varint(k)
                    if k + n > hi:
                        return False
                    out.append((k, k + n))
                    k += n
                else:
                    return False
        except IndexError:
            return False
        if k != hi:
            return False
        for a, b in out:
            if not (b > a and walk(a, b)):
                with contextlib.suppress(UnicodeDecodeError):
                    found.append(data[a:b].decode("utf-8"))
        return True

    walk(0, len(data))
    return found


def test_the_web_viewer_shows_a_runs_recording(chromium, screenshots: Path,  # noqa: F811
                                               tmp_path: Path) -> None:
    rrd = tmp_path / "run.rrd"
    assert main(["run", "--task", "8", *REPLAY, "--rerun", str(rrd), "-q"]) == 0
    viewer = subprocess.Popen([sys.executable, "-m", "llm_grop", "view", "--web", str(rrd)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env=rerun_env(tmp_path))
    try:
        line = viewer.stdout.readline() if viewer.stdout else ""
        assert line.startswith("Rerun web viewer: http://127.0.0.1:"), line
        url = line.split(": ", 1)[1].strip()
        assert "url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A" in url
        page = chromium.new_page(viewport=DESKTOP)
        page.goto(url)
        page.wait_for_function("() => window._handle !== undefined", timeout=LOAD_S * 1000)
        deadline, seen = time.monotonic() + LOAD_S, []
        while time.monotonic() < deadline:
            state = bytes(page.evaluate("() => Array.from(window._handle.viewer_state())"))
            seen = strings(state)
            if {"/world", "/plan", "TextLog"} <= set(seen):
                break
            time.sleep(0.5)
        # The recording is open, and its views show the room in 3D (/world), the attempts
        # (a log) and the plan (a document).
        assert any(s.startswith("Recording:llm-grop:") for s in seen), seen
        assert {"3D", "/world", "TextLog", "/events", "TextDocument", "/plan"} <= set(seen), \
            seen
        time.sleep(2)  # a few frames drawn before the picture
        page.screenshot(path=screenshots / "rerun_web.png")
    finally:
        viewer.terminate()
        viewer.wait(timeout=30)
    assert viewer.returncode in (0, 143, -15)
