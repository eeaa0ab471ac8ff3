"""SQLite files that llm-grop owns (the rating study, the service's jobs): WAL mode, every
commit on disk before it is acknowledged, the schema kept by versioned migrations.

Each migration is a file ``migrations/NNNN_name.sql`` in the owner's package, applied in
order in one transaction each; the file's ``PRAGMA user_version`` is the last one applied
and ``PRAGMA application_id`` marks whose file it is. A file whose version is newer than
this llm-grop knows, or that belongs to something else, is refused with one line.

A server's threads share a :class:`Pool` of connections, which outlives any thread.

This module imports nothing from the package but its errors, so every layer may use it.
"""

from __future__ import annotations

import contextlib
import os
import re
import sqlite3
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path

from llm_grop.errors import BadInput

#: How long a connection waits for another writer before giving up, milliseconds.
BUSY_TIMEOUT_MS = 10_000
_NAME = re.compile(r"^(\d{4})_[a-z0-9_]+\.sql$")


@dataclass(frozen=True)
class Migration:
    """One schema step: ``version`` (from 1) and its SQL script."""

    version: int
    name: str
    sql: str


@dataclass(frozen=True)
class Kind:
    """A kind of database: the package whose ``migrations`` folder holds its schema, its
    ``PRAGMA application_id``, what to call it in errors ("study database") and how to make
    one (the hint when the file is missing)."""

    package: str
    application_id: int
    label: str
    make_hint: str


@cache
def migrations(package: str) -> tuple[Migration, ...]:
    """The migrations packaged in ``package``, in version order."""
    found = []
    for entry in resources.files(package).joinpath("migrations").iterdir():
        match = _NAME.match(entry.name)
        if match:
            found.append(Migration(int(match.group(1)), entry.name, entry.read_text("utf-8")))
    found.sort(key=lambda m: m.version)
    assert [m.version for m in found] == list(range(1, len(found) + 1)), "migration gap"
    return tuple(found)


def connect(kind: Kind, path: str | Path, *, create: bool = False, upto: int | None = None,
            flag: str = "--db") -> sqlite3.Connection:
    """An open connection to the ``kind`` database at ``path``, migrated to the newest
    schema (or to version ``upto``, for tests of migrations).

    The connection is in autocommit mode (transactions are explicit), with foreign keys
    on and a busy timeout, and rows as :class:`sqlite3.Row`. Raises :class:`BadInput`
    naming ``flag`` if ``path`` does not exist (unless ``create``), is not such a
    database, or was written by a newer llm-grop.
    """
    path = Path(path)
    if not create and not path.is_file():
        raise BadInput(f"{flag} {path}: no such {kind.label}; {kind.make_hint}")
    try:
        conn = _open(path)
    except sqlite3.Error as exc:
        raise BadInput(f"{flag} {path}: cannot open ({exc})") from None
    try:
        _prepare(conn, kind, path, upto, flag)
    except BaseException:
        conn.close()
        raise
    return conn


def _open(path: Path) -> sqlite3.Connection:
    """A connection to ``path`` as :func:`connect` leaves it, without its checks."""
    # A web request may open it in one worker thread and use it in another, one at a time
    # (the rating site, the service's pool); it is never shared by two at once.
    conn = sqlite3.connect(path, isolation_level=None, timeout=BUSY_TIMEOUT_MS / 1000,
                           check_same_thread=False)
    conn.row_factory = sqlite3.Row
    return conn


def _configure(conn: sqlite3.Connection) -> None:
    conn.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
    # Every commit reaches the disk before it is acknowledged: a rating or an accepted job
    # once confirmed survives a power cut.
    conn.execute("PRAGMA synchronous = FULL")
    conn.execute("PRAGMA foreign_keys = ON")


def _prepare(conn: sqlite3.Connection, kind: Kind, path: Path, upto: int | None,
             flag: str) -> None:
    try:
        _configure(conn)
        app_id = conn.execute("PRAGMA application_id").fetchone()[0]
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        tables = conn.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]
    except sqlite3.DatabaseError:
        raise BadInput(f"{flag} {path}: not an llm-grop {kind.label}") from None
    if app_id != kind.application_id and (tables or version):
        raise BadInput(f"{flag} {path}: not an llm-grop {kind.label}")
    steps = migrations(kind.package)
    if version > len(steps):
        raise BadInput(f"{flag} {path}: written by a newer llm-grop (schema {version}, this "
                       f"one knows {len(steps)}); upgrade llm-grop")
    conn.execute("PRAGMA journal_mode = WAL")
    for step in steps[version:upto]:
        try:
            conn.executescript(f"BEGIN IMMEDIATE;\n{step.sql}\n"
                               f"PRAGMA application_id = {kind.application_id};\n"
                               f"PRAGMA user_version = {step.version};\nCOMMIT;")
        except sqlite3.Error as exc:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            # Another process may have applied it meanwhile.
            if conn.execute("PRAGMA user_version").fetchone()[0] >= step.version:
                continue
            raise BadInput(f"{flag} {path}: migration {step.name} failed ({exc})") from None


@contextlib.contextmanager
def transaction(conn: sqlite3.Connection) -> Iterator[sqlite3.Connection]:
    """``BEGIN IMMEDIATE`` ... ``COMMIT`` on ``conn``, rolled back if the block raises."""
    conn.execute("BEGIN IMMEDIATE")
    try:
        yield conn
        conn.execute("COMMIT")
    except BaseException:
        # A COMMIT that failed (the disk is full) may leave the transaction open, holding
        # the write lock for as long as the connection lives.
        if conn.in_transaction:
            with contextlib.suppress(sqlite3.Error):
                conn.execute("ROLLBACK")
        raise


class Pool:
    """Connections to the ``kind`` database at ``path``, each lent to one thread at a time
    (:meth:`connection`) and tied to no thread's life: a thread pool that retires its
    threads leaves no connection behind.

    At most ``size`` connections are open at once (a caller waits while all are lent out):
    the first is opened (checked and migrated, :func:`connect`) at once, the others when
    they are first needed, and all are kept for the next callers, except one opened while
    the file could not be written (SQLite opens it read-only, and it would stay so). When
    a use raises :class:`sqlite3.Error`, its connection and the idle ones are closed, to
    be opened afresh: the disk under them may have changed.
    """

    def __init__(self, kind: Kind, path: str | Path, *, size: int = 16, create: bool = False,
                 flag: str = "--db") -> None:
        self.path = Path(path)
        self._slots = threading.BoundedSemaphore(size)
        self._lock = threading.Lock()
        self._closed = False
        self._read_only: set[sqlite3.Connection] = set()
        self._idle: list[sqlite3.Connection] = []
        self._give_back(self._checked(connect(kind, self.path, create=create, flag=flag)))

    @contextlib.contextmanager
    def connection(self) -> Iterator[sqlite3.Connection]:
        """A connection of this thread's own until the block ends."""
        with self._slots:
            with self._lock:
                conn = self._idle.pop() if self._idle else None
            if conn is None:
                conn = self._checked(_open(self.path))
                try:
                    _configure(conn)
                except BaseException:
                    self._close(conn)
                    raise
            try:
                yield conn
            except sqlite3.Error:
                self._close(conn)
                self._drain()
                raise
            except BaseException:
                self._give_back(conn)
                raise
            self._give_back(conn)

    def _checked(self, conn: sqlite3.Connection) -> sqlite3.Connection:
        if not os.access(self.path, os.W_OK):
            with self._lock:
                self._read_only.add(conn)
        return conn

    def _give_back(self, conn: sqlite3.Connection) -> None:
        with self._lock:
            if not (self._closed or conn.in_transaction or conn in self._read_only):
                self._idle.append(conn)
                return
        self._close(conn)

    def _close(self, conn: sqlite3.Connection) -> None:
        with self._lock:
            self._read_only.discard(conn)
        conn.close()

    def close(self) -> None:
        """Close the idle connections; those lent out are closed when they come back."""
        with self._lock:
            self._closed = True
        self._drain()

    def _drain(self) -> None:
        with self._lock:
            idle, self._idle = self._idle, []
        for conn in idle:
            self._close(conn)
