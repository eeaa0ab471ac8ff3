"""Worker processes that behave: they die with the process that started them, and they
leave Ctrl-C to it.

This module imports nothing from the package, so every layer may use it.
"""

from __future__ import annotations

import contextlib
import ctypes
import signal
import sys
import threading
from collections.abc import Iterator

_PR_SET_PDEATHSIG = 1


def die_with_parent() -> None:
    """Have the kernel kill this process (SIGKILL) when its parent dies, as with a
    ``kill -9`` of the driver, so it neither lingers nor prints a broken pipe's traceback
    (Linux; elsewhere nothing)."""
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL("libc.so.6", use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)


@contextlib.contextmanager
def ctrl_c_ignored_by_children() -> Iterator[None]:
    """Within the block, processes started ignore SIGINT from their first instruction:
    they inherit an ignored SIGINT, and Python leaves one it finds ignored so. A Ctrl-C
    in the terminal (sent to every process of the group) then reaches only this one,
    which stops its workers itself, and no worker prints a ``KeyboardInterrupt`` while it
    is still starting. Outside the main thread nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
