"""The watchdog of a Ray cluster a bench started on this machine: when the driver dies
(``kill -9``), it kills what the driver had started, so no Ray process outlives it.

It runs as a process of its own (``python -m llm_grop.experiment.ray_watchdog PID``), in
a session of its own so that a Ctrl-C in the terminal leaves it be. Every
:data:`POLL_S` seconds it notes the driver's descendants (each with its start time, so a
reused process id is never mistaken for one of them); once the driver is gone it kills
those still running. Ray's agents outlive their raylet otherwise, as orphans. Linux only
(it reads ``/proc``); elsewhere it returns at once.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import time
from pathlib import Path

#: Seconds between looks at the driver and its descendants.
POLL_S = 0.5


def _stat(pid: int) -> tuple[int, int] | None:
    """``(parent pid, start time in clock ticks)`` of ``pid``, or ``None`` if it is gone
    (or a zombie: dead, only not yet reaped)."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
        # The command name, in parentheses, may hold spaces: fields follow its last ")".
        fields = text[text.rindex(")") + 2:].split()
        if fields[0] in ("Z", "X"):
            return None
        return int(fields[1]), int(fields[19])
    except (OSError, ValueError, IndexError):  # gone, or caught half-written
        return None


def descendants(root: int, skip: int) -> dict[int, int]:
    """Every descendant of ``root`` but ``skip``: pid -> start time."""
    children: dict[int, list[int]] = {}
    started: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            info = _stat(int(entry))
            if info is not None:
                children.setdefault(info[0], []).append(int(entry))
                started[int(entry)] = info[1]
    found: dict[int, int] = {}
    todo = [root]
    while todo:
        for child in children.get(todo.pop(), []):
            if child != skip and child not in found and child in started:
                found[child] = started[child]
                todo.append(child)
    return found


def watch(driver: int) -> None:
    """Wait for ``driver`` to end, then kill the descendants it last had."""
    if not Path("/proc").is_dir():
        return
    me = os.getpid()
    seen: dict[int, int] = {}
    while _stat(driver) is not None:
        # Every process ever seen is kept: one that left the tree (its parent died
        # first) is still the driver's to take down.
        seen |= descendants(driver, me)
        time.sleep(POLL_S)
    for pid, started in seen.items():
        info = _stat(pid)
        if info is not None and info[1] == started:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)


if __name__ == "__main__":
    watch(int(sys.argv[1]))
