"""What the rating website reads and writes: sessions, each rater's next picture, ratings.

A :class:`RatingStore` wraps one connection to a study database (open one per request, as
SQLite connections are cheap and belong to one thread). Every query is scoped to a rater,
so one rater can neither see another's progress nor rate in their name. Refusals raise
:class:`Refused` with the HTTP status the website answers.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import secrets
import sqlite3
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from llm_grop.ratings.db import transaction
from llm_grop.ratings.study import normal_code

#: How long a session lasts after joining, seconds (8 hours: a long rating sitting).
SESSION_TTL_S = 8 * 3600.0
#: Columns of the CSV export, in order.
EXPORT_COLUMNS = ("rater", "item", "task", "trial", "seed", "method", "rating",
                  "automatic_rating", "execution_time_s", "rated_at")


#: Live sessions one rater may have (a phone, a laptop, ...); joining again ends the oldest.
MAX_SESSIONS = 5


class Refused(Exception):
    """A request the website refuses: ``status`` (4xx), a one-line ``message`` and headers
    to send with it (``Retry-After``)."""

    def __init__(self, status: int, message: str,
                 headers: dict[str, str] | None = None) -> None:
        super().__init__(message)
        self.status = status
        self.message = message
        self.headers = headers or {}


@dataclass(frozen=True)
class Session:
    """A rater's session: the cookie's ``token`` (only given when made), the ``csrf``
    token their writes must carry, and when it ends (Unix seconds)."""

    rater_id: int
    rater: str
    csrf: str
    expires_at: float
    token: str = ""


@dataclass(frozen=True)
class NextItem:
    """The rater's next picture (``item`` ``None`` when they have rated them all) and their
    progress: ``done`` of ``total``."""

    item: str | None
    objects: tuple[str, ...]
    done: int
    total: int

    def to_json(self) -> dict[str, Any]:
        """The JSON ``GET /api/next`` answers."""
        return {"item": self.item, "image": None if self.item is None else image_url(self.item),
                "objects": list(self.objects), "done": self.done, "total": self.total}


def export_csv(rows: list[dict[str, Any]]) -> str:
    """The ratings as CSV text, a header of :data:`EXPORT_COLUMNS` first."""
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=EXPORT_COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return out.getvalue()


def image_url(item: str) -> str:
    """Where a picture is served: by its item id alone."""
    return f"/images/{item}"


def _digest(token: str) -> str:
    return hashlib.sha256(token.encode("utf-8")).hexdigest()


class RatingStore:
    """The study database seen by the website; ``clock`` gives Unix seconds."""

    def __init__(self, conn: sqlite3.Connection, *, ttl_s: float = SESSION_TTL_S,
                 clock: Any = time.time) -> None:
        self.conn = conn
        self.ttl_s = ttl_s
        self.clock = clock

    def join(self, code: str) -> Session:
        """A new session for the rater invited with ``code``; :class:`Refused` (401) for a
        code no rater has."""
        row = self.conn.execute("SELECT id, label FROM raters WHERE code = ?",
                                (normal_code(code),)).fetchone()
        if row is None:
            raise Refused(401, "unknown invite code")
        token, csrf = secrets.token_urlsafe(32), secrets.token_urlsafe(32)
        now = self.clock()
        with transaction(self.conn):
            self.conn.execute("DELETE FROM sessions WHERE expires_at <= ?", (now,))
            # A rater keeps at most MAX_SESSIONS live sessions: joining again ends the
            # oldest, so repeated joins cannot grow the table without bound.
            self.conn.execute(
                "DELETE FROM sessions WHERE rater_id = ? AND rowid NOT IN (SELECT rowid FROM "
                "sessions WHERE rater_id = ? ORDER BY expires_at DESC LIMIT ?)",
                (row["id"], row["id"], MAX_SESSIONS - 1))
            self.conn.execute("INSERT INTO sessions (token_hash, rater_id, csrf, expires_at)"
                              " VALUES (?, ?, ?, ?)",
                              (_digest(token), row["id"], csrf, now + self.ttl_s))
        return Session(row["id"], row["label"], csrf, now + self.ttl_s, token)

    def session(self, token: str | None) -> Session:
        """The live session whose cookie holds ``token``; :class:`Refused` (401) when there
        is none or it has expired."""
        if not token:
            raise Refused(401, "not signed in; join with your invite code")
        row = self.conn.execute(
            "SELECT s.rater_id, r.label, s.csrf, s.expires_at FROM sessions s"
            " JOIN raters r ON r.id = s.rater_id WHERE s.token_hash = ?",
            (_digest(token),)).fetchone()
        if row is None:
            raise Refused(401, "not signed in; join with your invite code")
        if row["expires_at"] <= self.clock():
            raise Refused(401, "session expired; join again with your invite code")
        return Session(row["rater_id"], row["label"], row["csrf"], row["expires_at"])

    def end(self, token: str) -> None:
        """End the session whose cookie holds ``token`` (leaving)."""
        with transaction(self.conn):
            self.conn.execute("DELETE FROM sessions WHERE token_hash = ?", (_digest(token),))

    def progress(self, rater_id: int) -> tuple[int, int]:
        """``(done, total)`` of one rater."""
        row = self.conn.execute(
            "SELECT (SELECT count(*) FROM ratings WHERE rater_id = :r),"
            " (SELECT count(*) FROM rater_items WHERE rater_id = :r)", {"r": rater_id}).fetchone()
        return row[0], row[1]

    def next_item(self, rater_id: int) -> NextItem:
        """The first picture in the rater's order they have not rated."""
        done, total = self.progress(rater_id)
        row = self.conn.execute(
            "SELECT i.id, i.objects FROM rater_items ri JOIN items i ON i.id = ri.item_id"
            " WHERE ri.rater_id = ? AND NOT EXISTS (SELECT 1 FROM ratings r"
            " WHERE r.rater_id = ri.rater_id AND r.item_id = ri.item_id)"
            " ORDER BY ri.position LIMIT 1", (rater_id,)).fetchone()
        if row is None:
            return NextItem(None, (), done, total)
        return NextItem(row["id"], tuple(json.loads(row["objects"])), done, total)

    def rate(self, rater_id: int, item: object, rating: object) -> tuple[int, int]:
        """Store the rater's ``rating`` of ``item``; their progress after it.

        :class:`Refused`: 422 unless ``rating`` is an integer 1-5 and ``item`` a string,
        404 for an item not among the rater's pictures, 409 for one already rated.
        """
        if not isinstance(item, str):
            raise Refused(422, "item: expected an item id")
        if type(rating) is not int or not 1 <= rating <= 5:
            raise Refused(422, f"rating: expected an integer from 1 to 5, got {rating!r}")
        mine = self.conn.execute("SELECT 1 FROM rater_items WHERE rater_id = ? AND item_id = ?",
                                 (rater_id, item)).fetchone()
        if mine is None:
            raise Refused(404, "item: no such picture in your study")
        try:
            with transaction(self.conn):
                self.conn.execute("INSERT INTO ratings (rater_id, item_id, rating, rated_at)"
                                  " VALUES (?, ?, ?, ?)",
                                  (rater_id, item, rating,
                                   datetime.now(UTC).isoformat(timespec="milliseconds")))
        except sqlite3.IntegrityError:
            raise Refused(409, "item: you have already rated this picture") from None
        return self.progress(rater_id)

    def picture(self, rater_id: int, item: str) -> bytes:
        """The PNG of one of the rater's pictures; :class:`Refused` (404) for any other."""
        row = self.conn.execute(
            "SELECT i.picture FROM rater_items ri JOIN items i ON i.id = ri.item_id"
            " WHERE ri.rater_id = ? AND ri.item_id = ?", (rater_id, item)).fetchone()
        if row is None:
            raise Refused(404, "no such picture")
        return bytes(row["picture"])

    def admin_progress(self) -> dict[str, Any]:
        """Every rater's progress, for the study's administrator."""
        study = self.conn.execute("SELECT name FROM study").fetchone()
        raters = [{"rater": r["label"], "done": r["done"], "total": r["total"],
                   "last_rated_at": r["last"]} for r in self.conn.execute(
            "SELECT r.label, (SELECT count(*) FROM ratings x WHERE x.rater_id = r.id) AS done,"
            " (SELECT count(*) FROM rater_items x WHERE x.rater_id = r.id) AS total,"
            " (SELECT max(rated_at) FROM ratings x WHERE x.rater_id = r.id) AS last"
            " FROM raters r ORDER BY r.id")]
        items = self.conn.execute("SELECT count(*) FROM items").fetchone()[0]
        return {"study": study["name"] if study else None, "items": items,
                "ratings": sum(r["done"] for r in raters), "raters": raters}

    def export_rows(self) -> list[dict[str, Any]]:
        """Every rating with its trial, in :data:`EXPORT_COLUMNS`, by rater then time."""
        rows = self.conn.execute(
            "SELECT r.label AS rater, i.id AS item, i.task, i.trial, i.seed, i.method,"
            " x.rating, i.automatic_rating, i.execution_time_s, x.rated_at"
            " FROM ratings x JOIN raters r ON r.id = x.rater_id JOIN items i ON i.id = x.item_id"
            " ORDER BY r.id, x.rated_at, i.position")
        return [dict(zip(EXPORT_COLUMNS, tuple(row), strict=True)) for row in rows]
