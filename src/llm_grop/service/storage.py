"""When the disk under the service's database refuses writes: it is full, or read-only.

That is the server's condition, neither a client's fault nor a job's. New work is refused
with 503 and ``Retry-After`` (:mod:`.storage_errors`); workers and the supervisor wait
with a bounded exponential backoff, logging one line when such an episode starts and one
when it ends (:class:`Backoff`); and the jobs already accepted run once the disk takes
writes again.
"""

from __future__ import annotations

import errno
import logging
import os
import sqlite3
import time
from pathlib import Path
from typing import Literal

Problem = Literal["full", "read_only"]

#: Free bytes (to an unprivileged writer) below which the disk counts as full: no new job
#: is accepted and no worker claims one, so that what is running can still finish.
MIN_FREE_BYTES = 256 * 1024
#: Seconds a refused client is told to wait (``Retry-After``).
RETRY_AFTER_S = 30
#: The first and the longest wait between a worker's tries, seconds.
FIRST_WAIT_S = 0.1
LONGEST_WAIT_S = 5.0
#: The refusal's one line and its ``code`` per problem.
MESSAGES: dict[str, str] = {
    "full": "storage: the server's disk is full; it takes no new work until space is freed",
    "read_only": "storage: the server's disk is read-only; it takes no new work until it is "
                 "writable again"}
CODES: dict[str, str] = {"full": "storage_full", "read_only": "storage_read_only"}

# SQLite's primary result codes (the low byte of an extended one).
_SQLITE_READONLY, _SQLITE_IOERR, _SQLITE_FULL, _SQLITE_CANTOPEN = 8, 10, 13, 14


class Unwritable(Exception):
    """The disk refuses writes (``problem``), found before any work was accepted."""

    def __init__(self, problem: Problem) -> None:
        super().__init__(MESSAGES[problem])
        self.problem: Problem = problem


def state(where: Path) -> Problem | None:
    """What the file system holding the directory ``where`` refuses: ``"read_only"``,
    ``"full"`` (less than :data:`MIN_FREE_BYTES` free), or ``None``."""
    try:
        found = os.statvfs(where)
    except OSError:
        return None
    if found.f_flag & os.ST_RDONLY:
        return "read_only"
    return "full" if found.f_bavail * found.f_frsize < MIN_FREE_BYTES else None


def problem(exc: BaseException, where: Path) -> Problem | None:
    """Whether ``exc``, or an error it was raised from, is the disk holding ``where``
    refusing a write; which refusal. A failed write SQLite reports only as an I/O error
    counts when the file system is read-only or full."""
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        seen.add(id(current))
        found = _one(current, where)
        if found is not None:
            return found
        current = current.__cause__ or current.__context__
    return None


def _one(exc: BaseException, where: Path) -> Problem | None:
    if isinstance(exc, Unwritable):
        return exc.problem
    if isinstance(exc, sqlite3.Error):
        code = (getattr(exc, "sqlite_errorcode", None) or 0) & 0xFF
        if code == _SQLITE_FULL:
            return "full"
        if code == _SQLITE_READONLY:
            return "read_only"
        return state(where) if code in (_SQLITE_IOERR, _SQLITE_CANTOPEN) else None
    if isinstance(exc, OSError):
        if exc.errno in (errno.ENOSPC, errno.EDQUOT):
            return "full"
        if exc.errno == errno.EROFS:
            return "read_only"
        return state(where) if exc.errno == errno.EIO else None
    return None


class Episode:
    """One process's record of the disk refusing writes, for its log: a warning when an
    episode starts (or its problem changes), one line when it ends, nothing in between.
    ``who`` and ``meanwhile`` make the warning: "worker 12: the disk holding the jobs is
    full; waiting for it"."""

    def __init__(self, who: str, log: logging.Logger, meanwhile: str = "waiting for it"
                 ) -> None:
        self.who, self.log, self.meanwhile = who, log, meanwhile
        self.problem: Problem | None = None
        self._since = 0.0  # time.monotonic() when it started

    def trouble(self, problem: Problem) -> None:
        """The disk refused a write with ``problem`` (logged if the episode is new)."""
        if problem != self.problem:
            if self.problem is None:
                self._since = time.monotonic()
            self.problem = problem
            self.log.warning("%s: the disk holding the jobs is %s; %s", self.who,
                             problem.replace("_", "-"), self.meanwhile)

    def cleared(self) -> None:
        """The disk took a write (logged if that ends an episode)."""
        if self.problem is not None:
            self.log.warning("%s: the disk takes writes again, after %.0f s", self.who,
                             time.monotonic() - self._since)
            self.problem = None


class Backoff(Episode):
    """An :class:`Episode` and the waits between tries in it: from :data:`FIRST_WAIT_S`,
    doubling up to :data:`LONGEST_WAIT_S` seconds."""

    def __init__(self, who: str, log: logging.Logger) -> None:
        super().__init__(who, log)
        self._wait = FIRST_WAIT_S

    def wait_s(self, problem: Problem) -> float:
        """Seconds to wait before the next try, after the disk refused one with
        ``problem``."""
        if self.problem is None:
            self._wait = FIRST_WAIT_S
        self.trouble(problem)
        wait, self._wait = self._wait, min(self._wait * 2, LONGEST_WAIT_S)
        return wait
