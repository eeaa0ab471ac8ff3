"""The service's jobs in one SQLite file (WAL, every commit on disk before it is
acknowledged): what each client asked, its state, its result, its files and its
progress.

A job is ``queued``, then ``running`` under a claim (a fresh random token per attempt),
then ``done``, ``failed`` (with a status and a one-line reason) or ``cancelled``. A
worker's writes name its claim, so a worker whose job was taken from it (the server
restarted, the job timed out) can never write a result twice. :meth:`JobStore.recover`
puts the jobs a dead server left running back in the queue, up to :data:`MAX_ATTEMPTS`
attempts, so every accepted job reaches a terminal state.
"""

from __future__ import annotations

import contextlib
import json
import secrets
import sqlite3
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from llm_grop import database
from llm_grop.database import transaction

JOBS = database.Kind("llm_grop.service", 0x4C475253, "service database",
                     "'llm-grop serve' makes one")
Kind = Literal["arrange", "plan", "run", "learn"]
State = Literal["queued", "running", "done", "failed", "cancelled"]
TERMINAL: frozenset[str] = frozenset({"done", "failed", "cancelled"})
#: Attempts a job gets when its worker or the server dies under it; then it fails.
MAX_ATTEMPTS = 3
#: Ended jobs deleted per transaction when old ones are pruned (their videos with them).
PRUNE_BATCH = 20
#: Queue order: answers a client waits for go before runs.
PRIORITY: dict[str, int] = {"arrange": 0, "plan": 0, "learn": 0, "run": 1}
#: Connections a store has open at most (its calls wait for one while all are in use).
CONNECTIONS = 16


class Overloaded(Exception):
    """The queue is full, or the client has as many jobs as it may: answered with 429 and
    ``Retry-After`` (seconds)."""

    def __init__(self, message: str, retry_after_s: int) -> None:
        super().__init__(message)
        self.retry_after_s = retry_after_s


@dataclass(frozen=True)
class Job:
    """One job as stored. Times are seconds since the epoch; ``status`` is the HTTP status
    of a failure (422 bad input, 409 nothing feasible, 500 internal, 504 over time)."""

    id: str
    kind: Kind
    body: dict[str, Any]
    client: str
    state: State
    attempts: int
    claim: str | None
    worker: int | None
    created: float
    started: float | None
    finished: float | None
    status: int | None
    error: str | None
    result: dict[str, Any] | None
    cancel: bool = False

    @property
    def terminal(self) -> bool:
        """Whether the job has ended (done, failed or cancelled)."""
        return self.state in TERMINAL


def _job(row: sqlite3.Row) -> Job:
    return Job(row["id"], row["kind"], json.loads(row["body"]), row["client"], row["state"],
               row["attempts"], row["claim"], row["worker"], row["created"], row["started"],
               row["finished"], row["status"], row["error"],
               json.loads(row["result"]) if row["result"] is not None else None,
               bool(row["cancel"]))


class JobStore:
    """The jobs in the database at ``path`` (made if missing, checked and migrated at
    once). Its methods may be called from any thread: each call borrows a connection of
    its own from a pool of at most ``connections`` (:class:`llm_grop.database.Pool`), so a
    call that waits on another's write (a worker's video) holds up no reader, and the
    server's threads coming and going leave no connection open behind them."""

    def __init__(self, path: Path, *, connections: int = CONNECTIONS) -> None:
        self.path = path
        self._pool = database.Pool(JOBS, path, size=connections, create=True)

    def connection(self) -> contextlib.AbstractContextManager[sqlite3.Connection]:
        """A connection to the database, this thread's alone until the block ends."""
        return self._pool.connection()

    def close(self) -> None:
        """Close the store's connections (those in use as their calls end)."""
        self._pool.close()

    @contextlib.contextmanager
    def _write(self) -> Iterator[sqlite3.Connection]:
        with self._pool.connection() as conn, transaction(conn) as c:
            yield c

    def _rows(self, sql: str, args: tuple[Any, ...] = ()) -> list[sqlite3.Row]:
        with self._pool.connection() as c:
            return c.execute(sql, args).fetchall()

    # ---- clients ------------------------------------------------------------------------

    def submit(self, kind: Kind, body: Mapping[str, Any], client: str, *, queue: int,
               per_client: int | None = None) -> str:
        """Accept a job and return its id; :class:`Overloaded` when ``queue`` jobs wait
        already, or (``per_client``) the client has that many of this kind unfinished."""
        job_id = secrets.token_urlsafe(9)
        with self._write() as c:
            waiting = c.execute("SELECT count(*) FROM jobs WHERE state = 'queued'"
                                ).fetchone()[0]
            if waiting >= queue:
                raise Overloaded(f"the server is busy: {waiting} jobs are waiting; try again "
                                 "shortly", retry_after_s=max(1, waiting // 8))
            if per_client is not None:
                mine = c.execute("SELECT count(*) FROM jobs WHERE client = ? AND kind = ? AND "
                                 "state IN ('queued', 'running')", (client, kind)).fetchone()[0]
                if mine >= per_client:
                    raise Overloaded(f"{mine} of your {kind}s are unfinished, the most one "
                                     f"client may have; wait for one to end",
                                     retry_after_s=5)
            c.execute("INSERT INTO jobs (id, kind, body, client, priority, state, created) "
                      "VALUES (?, ?, ?, ?, ?, 'queued', ?)",
                      (job_id, kind, json.dumps(body), client, PRIORITY[kind], time.time()))
        return job_id

    def get(self, job_id: str) -> Job | None:
        """The job ``job_id``, or ``None``."""
        rows = self._rows("SELECT * FROM jobs WHERE id = ?", (job_id,))
        return _job(rows[0]) if rows else None

    def cancel(self, job_id: str) -> Job | None:
        """Cancel a job: a queued one at once, a running one when its worker is stopped
        (:meth:`to_cancel`); an ended one stays as it is."""
        with self._write() as c:
            c.execute("UPDATE jobs SET state = 'cancelled', finished = ?, error = "
                      "'cancelled by the client' WHERE id = ? AND state = 'queued'",
                      (time.time(), job_id))
            c.execute("UPDATE jobs SET cancel = 1 WHERE id = ? AND state = 'running'",
                      (job_id,))
        return self.get(job_id)

    def file(self, job_id: str, name: str) -> tuple[str, bytes] | None:
        """A job's file: ``(media type, bytes)``, or ``None``."""
        rows = self._rows("SELECT media_type, data FROM files WHERE job = ? AND name = ?",
                          (job_id, name))
        return (rows[0][0], bytes(rows[0][1])) if rows else None

    def files(self, job_id: str) -> list[str]:
        """The names of a job's files."""
        return [r[0] for r in self._rows(
            "SELECT name FROM files WHERE job = ? ORDER BY name", (job_id,))]

    def events(self, job_id: str, after: int = 0) -> list[tuple[int, float, str]]:
        """A job's progress events after number ``after``: ``(seq, time, message)``."""
        return [(r[0], r[1], r[2]) for r in self._rows(
            "SELECT seq, at, message FROM events WHERE job = ? AND seq > ? ORDER BY seq",
            (job_id, after))]

    def recent(self, ids: list[str]) -> list[Job]:
        """The jobs among ``ids`` that exist, newest first."""
        jobs = [j for j in (self.get(i) for i in ids) if j is not None]
        return sorted(jobs, key=lambda j: j.created, reverse=True)

    def counts(self) -> dict[str, int]:
        """How many jobs are in each state."""
        return {r[0]: r[1] for r in self._rows(
            "SELECT state, count(*) FROM jobs GROUP BY state")}

    # ---- workers ------------------------------------------------------------------------

    def claim(self, worker: int) -> Job | None:
        """The next queued job, now running under a fresh claim for process ``worker``."""
        # Idle workers look often: a read takes no lock, so only a likely claim writes.
        if not self._rows("SELECT 1 FROM jobs WHERE state = 'queued' LIMIT 1"):
            return None
        # One transaction, nothing after it: a claim that failed to commit (the disk is
        # full) leaves the job queued, never running under a worker that does not know.
        with self._write() as c:
            row = c.execute("SELECT id FROM jobs WHERE state = 'queued' ORDER BY priority, "
                            "rowid LIMIT 1").fetchone()
            if row is None:
                return None
            c.execute("UPDATE jobs SET state = 'running', claim = ?, worker = ?, started = ?, "
                      "attempts = attempts + 1 WHERE id = ?",
                      (secrets.token_hex(8), worker, time.time(), row[0]))
            job = _job(c.execute("SELECT * FROM jobs WHERE id = ?", (row[0],)).fetchone())
            if job.attempts > 1:
                self._event(c, job, f"attempt {job.attempts} of {MAX_ATTEMPTS}, after the "
                                    "last one was interrupted")
        return job

    def event(self, job: Job, message: str) -> None:
        """Add a progress event to ``job`` (nothing if its claim is no longer held)."""
        with self._write() as c:
            if self._held(c, job):
                self._event(c, job, message)

    @staticmethod
    def _event(c: sqlite3.Connection, job: Job, message: str) -> None:
        c.execute("INSERT INTO events (job, seq, at, message) SELECT ?, coalesce(max(seq), "
                  "0) + 1, ?, ? FROM events WHERE job = ?",
                  (job.id, time.time(), message, job.id))

    def finish(self, job: Job, result: Mapping[str, Any],
               files: Mapping[str, tuple[str, bytes]]) -> bool:
        """Record ``job`` done with ``result`` and ``files`` (name -> media type, bytes);
        ``False`` (nothing written) if its claim is no longer held."""
        with self._write() as c:
            if not self._held(c, job):
                return False
            c.executemany("INSERT OR REPLACE INTO files (job, name, media_type, data) VALUES "
                          "(?, ?, ?, ?)", [(job.id, n, m, d) for n, (m, d) in files.items()])
            c.execute("UPDATE jobs SET state = 'done', result = ?, finished = ? WHERE id = ?",
                      (json.dumps(result), time.time(), job.id))
        return True

    def fail(self, job: Job, status: int, error: str) -> bool:
        """Record ``job`` failed with HTTP ``status`` and the one-line ``error``; ``False``
        if its claim is no longer held."""
        with self._write() as c:
            if not self._held(c, job):
                return False
            c.execute("UPDATE jobs SET state = 'failed', status = ?, error = ?, finished = ? "
                      "WHERE id = ?", (status, error, time.time(), job.id))
        return True

    @staticmethod
    def _held(c: sqlite3.Connection, job: Job) -> bool:
        row = c.execute("SELECT claim, state FROM jobs WHERE id = ?", (job.id,)).fetchone()
        return row is not None and row[0] == job.claim and row[1] == "running"

    # ---- the supervisor -----------------------------------------------------------------

    def running(self) -> list[Job]:
        """Every running job."""
        return [_job(r) for r in self._rows(
            "SELECT * FROM jobs WHERE state = 'running' ORDER BY rowid")]

    def end(self, job: Job, state: Literal["failed", "cancelled"], status: int | None,
            error: str) -> None:
        """End a running job whose worker was stopped (over time, or cancelled)."""
        with self._write() as c:
            c.execute("UPDATE jobs SET state = ?, status = ?, error = ?, finished = ? "
                      "WHERE id = ? AND claim = ? AND state = 'running'",
                      (state, status, error, time.time(), job.id, job.claim))

    def orphaned(self, job: Job, why: str, status: int = 500) -> None:
        """A running job whose attempt was lost (``why``: its worker died): queued again,
        or failed with ``status`` after :data:`MAX_ATTEMPTS` attempts (cancelled if the
        client cancelled it)."""
        with self._write() as c:
            row = c.execute("SELECT attempts, cancel FROM jobs WHERE id = ? AND claim = ? AND "
                            "state = 'running'", (job.id, job.claim)).fetchone()
            if row is None:
                return
            attempts, cancel = row
            if attempts >= MAX_ATTEMPTS or cancel:
                state, status, error = (
                    ("cancelled", None, "cancelled by the client") if cancel else
                    ("failed", status, f"{why} {attempts} times; given up"))
                c.execute("UPDATE jobs SET state = ?, status = ?, error = ?, finished = ? "
                          "WHERE id = ? AND claim = ?",
                          (state, status, error, time.time(), job.id, job.claim))
            else:
                c.execute("UPDATE jobs SET state = 'queued', claim = NULL, worker = NULL "
                          "WHERE id = ? AND claim = ? AND state = 'running'",
                          (job.id, job.claim))

    def prune(self, before: float, batch: int = PRUNE_BATCH) -> int:
        """Forget every ended job that ended before ``before`` (a :func:`time.time`), with
        its files and events; how many. Queued and running jobs are never pruned. Each
        ``batch`` jobs go in a transaction of their own, so that workers and clients wait
        for one batch at most, never for the whole backlog."""
        gone = 0
        while True:
            with self._write() as c:
                n = c.execute("DELETE FROM jobs WHERE rowid IN (SELECT rowid FROM jobs WHERE "
                              "state IN ('done', 'failed', 'cancelled') AND finished < ? "
                              "LIMIT ?)", (before, batch)).rowcount
            gone += n
            if n < batch:
                return gone

    def recover(self) -> int:
        """Re-queue (or fail, after :data:`MAX_ATTEMPTS`) every job a previous server left
        running; how many there were. Call it before any worker starts."""
        left = self.running()
        for job in left:
            self.orphaned(job, "interrupted by a server restart")
        return len(left)
