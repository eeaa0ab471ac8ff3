"""The LLM layer's files on disk are read and written only as regular files: a FIFO or a
device named as the replay file, the record file or the embedded model is refused with
one line, at once, instead of holding the run (a FIFO waits for a peer for ever) or
reading without end (``/dev/zero`` would fill the memory)."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from llm_grop.cli import main
from llm_grop.errors import BadInput, LLMError, LLMUnavailable
from llm_grop.llm.base import BackendOptions
from llm_grop.llm.embedded import EmbeddedLLM
from llm_grop.llm.record import LLMCallRecord, append_record, load_records

#: Seconds a refusal may take before the test calls the code stuck (it takes milliseconds).
STUCK_S = 20.0


@pytest.fixture
def fifo(tmp_path: Path) -> Iterator[Path]:
    path = tmp_path / "calls.jsonl"
    os.mkfifo(path)
    yield path


def _unstick(fifo: Path) -> None:
    """Open the FIFO's other end, so that a call blocked opening it returns (and the test
    fails on its result rather than hanging)."""
    for flags in (os.O_RDONLY | os.O_NONBLOCK, os.O_WRONLY | os.O_NONBLOCK):
        with contextlib.suppress(OSError):
            os.close(os.open(fifo, flags))


def _within(call: Callable[[], object], fifo: Path) -> BaseException | object:
    """What ``call`` raised or returned, failing the test if it took over ``STUCK_S``."""
    outcome: list[BaseException | object] = []

    def run() -> None:
        try:
            outcome.append(call())
        except BaseException as exc:  # the test inspects it
            outcome.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(STUCK_S)
    stuck = thread.is_alive()
    while thread.is_alive():
        _unstick(fifo)
        thread.join(0.1)
    assert not stuck, f"still blocked on the FIFO after {STUCK_S:g} s"
    return outcome[0]


def test_a_fifo_as_the_replay_file_is_refused_at_once(fifo: Path) -> None:
    got = _within(lambda: load_records(fifo), fifo)
    assert isinstance(got, LLMError)
    assert str(got) == f"{fifo}: cannot read replay file: not a regular file (a FIFO)"


def test_a_fifo_as_the_record_file_is_refused_at_once(fifo: Path) -> None:
    record = LLMCallRecord("openai", "m", "p", "r", 0.1, seed=1)
    got = _within(lambda: append_record(fifo, record), fifo)
    assert isinstance(got, BadInput)
    assert str(got) == (f"{fifo}: cannot append the LLM call record: not a regular file "
                        "(a FIFO)")


def test_arrange_with_a_fifo_as_its_replay_file_says_so_in_one_line(fifo: Path,
                                                                     capsys) -> None:
    code = _within(lambda: main(["arrange", "a dinner plate and a dinner fork", "--llm",
                                 "replay", "--replay", str(fifo), "--no-cache"]), fifo)
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err == f"llm-grop: error: {fifo}: cannot read replay file: not a regular file (a FIFO)"


#: Loads a replay file in a fresh process whose memory is capped at 1 GiB, so that code
#: which reads a device to its end fails there, not on the machine.
_LOAD_CAPPED = """
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
from pathlib import Path
from llm_grop.errors import LLMError
from llm_grop.llm.record import load_records
try:
    load_records(Path(sys.argv[1]))
except LLMError as exc:
    print(exc)
"""


@pytest.mark.parametrize("how", ["the device", "a link to it"])
def test_an_endless_device_as_the_replay_file_is_never_read(tmp_path: Path, how: str) -> None:
    path = Path("/dev/zero")
    if how == "a link to it":
        path = tmp_path / "calls.jsonl"
        path.symlink_to("/dev/zero")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    done = subprocess.run([sys.executable, "-c", _LOAD_CAPPED, str(path)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-500:]
    assert done.stdout.strip() == (f"{path}: cannot read replay file: not a regular file "
                                   "(a character device)")


def test_an_embedded_model_that_is_no_regular_file_is_named_so(fifo: Path) -> None:
    with pytest.raises(LLMUnavailable) as err:
        EmbeddedLLM(BackendOptions(model=str(fifo)))
    assert str(err.value) == (f"embedded backend: model file {str(fifo)!r} is not a regular "
                              "file (a FIFO)")
    with pytest.raises(LLMUnavailable, match="not found"):
        EmbeddedLLM(BackendOptions(model=str(fifo.with_name("absent.gguf"))))
