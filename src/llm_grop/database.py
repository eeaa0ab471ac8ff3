"""SQLite files that llm-grop owns (the rating study, the service's jobs): WAL mode, every
commit on disk before it is acknowledged, the schema kept by versioned migrations.

Each migration is a file ``migrations/NNNN_name.sql`` in the owner's package, applied in
order in one transaction each; the file's ``PRAGMA user_version`` is the last one applied
and ``PRAGMA application_id`` marks whose file it is. A file whose version is newer than
this llm-grop knows, or that belongs to something else, is refused with one line.

This module imports nothing from the package but its errors, so every layer may use it.
"""

from __future__ import annotations

import contextlib
import re
import sqlite3
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
        # A web request may open it in one worker thread and use it in another, one at a
        # time (the rating site); it is never shared by two at once (the service's job
        # store gives each thread a connection of its own).
        conn = sqlite3.connect(path, isolation_level=None, timeout=BUSY_TIMEOUT_MS / 1000,
                               check_same_thread=False)
    except sqlite3.Error as exc:
        raise BadInput(f"{flag} {path}: cannot open ({exc})") from None
    conn.row_factory = sqlite3.Row
    try:
        _prepare(conn, kind, path, upto, flag)
    except BaseException:
        conn.close()
        raise
    return conn


def _prepare(conn: sqlite3.Connection, kind: Kind, path: Path, upto: int | None,
             flag: str) -> None:
    try:
        conn.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
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
    # Every commit reaches the disk before it is acknowledged: a rating or an accepted job
    # once confirmed survives a power cut.
    conn.execute("PRAGMA synchronous = FULL")
    conn.execute("PRAGMA foreign_keys = ON")
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
    except BaseException:
        conn.execute("ROLLBACK")
        raise
    conn.execute("COMMIT")
