"""One writer at a time: an exclusive lock on a file beside what is written (a results
directory, a service's database), held by an open file descriptor for as long as the
writer runs.

The kernel releases the lock when its process ends however it ends, so a lock left by a
killed process is simply taken by the next writer. The file holds the holder's process id,
which a refused writer names.

This module imports nothing from the package but its errors, so every layer may use it.
"""

from __future__ import annotations

import fcntl
import os
from pathlib import Path

from llm_grop.errors import BadInput


def hold(lock: Path, param: str, value: object, holder: str) -> int:
    """Take the exclusive lock on the file ``lock`` (made if missing); the file descriptor
    that holds it, for :func:`release`. :class:`BadInput` naming the parameter ``param``
    given ``value`` and the holder's process id if another process (``holder``: what it
    is, in words) has it."""
    fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    _take(fd, fcntl.LOCK_EX, param, value, holder)
    os.ftruncate(fd, 0)
    os.write(fd, str(os.getpid()).encode())
    return fd


def check(lock: Path, param: str, value: object, holder: str) -> None:
    """:class:`BadInput` as from :func:`hold` if another process holds the lock on the file
    ``lock`` now; nothing is made or kept (a missing or unreadable file has no holder).
    Cheap, so a writer may ask before any other work and :func:`hold` once it writes."""
    try:
        fd = os.open(lock, os.O_RDONLY)
    except OSError:
        return
    _take(fd, fcntl.LOCK_SH, param, value, holder)
    os.close(fd)


def _take(fd: int, how: int, param: str, value: object, holder: str) -> None:
    """Lock the open file ``fd`` ``how`` (``LOCK_EX`` or ``LOCK_SH``) without waiting;
    if another process holds it, close ``fd`` and raise :func:`hold`'s :class:`BadInput`."""
    try:
        fcntl.flock(fd, how | fcntl.LOCK_NB)
    except BlockingIOError:
        pid = os.read(fd, 32).decode(errors="replace").strip() or "?"
        os.close(fd)
        raise BadInput(f"in use by {holder} (pid {pid}); wait for it to end or stop it",
                       param=param, value=value) from None


def release(fd: int) -> None:
    """Let go of a lock from :func:`hold`."""
    os.close(fd)
