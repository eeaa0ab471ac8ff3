"""A study: the pictures of one bench's trials, made into a database raters can rate.

:func:`items_from_bench` reads a bench directory's trials and their pictures (the 3D
render where the bench ran in MuJoCo, the drawing otherwise); :func:`create_study` writes
them into a new database, each picture under a random id and stripped of its metadata, so
nothing a rater sees names or hints at the method. A drawing loses its title band (the
request, which the rating page shows once, as its heading, above every picture).
:func:`invite` adds raters, each with an invite code and an order of their own, drawn from
the study's seed (stage ``ratings.order``, path: the rater's number from 0).
"""

from __future__ import annotations

import io
import json
import os
import secrets
import sqlite3
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from llm_grop import seeds
from llm_grop.contract.models import TrialRow
from llm_grop.errors import BadInput
from llm_grop.experiment.rows import ROWS, read_rows
from llm_grop.experiment.sweep import cell_dirs
from llm_grop.language.request import parse_request
from llm_grop.ratings.db import connect, transaction
from llm_grop.world.catalog import Catalog

#: Letters of invite codes: no 0/O, 1/I/L or U/V to confuse.
CODE_ALPHABET = "ABCDEFGHJKMNPQRSTWXYZ23456789"
#: Characters in an invite code (about 58 bits), written in groups of four.
CODE_CHARS = 12
#: At most this many raters are invited at once.
MAX_INVITES = 1000
#: At most this many of a sweep's cells are listed in a message.
LISTED_CELLS = 6
#: White space kept above a drawing's plot frame when its title band is cut off, pixels.
TITLE_CUT_MARGIN_PX = 12
#: The plot frame's top edge spans at least 1/FRAME_FRACTION of a drawing's width, even
#: for a deep table's narrow plot; no run of lettering is that long.
FRAME_FRACTION = 8


@dataclass(frozen=True)
class StudyItem:
    """One picture to rate: a bench trial's final table and what it is kept with.

    ``objects`` are the requested objects the page lists above it; ``picture`` is PNG
    bytes; ``execution_time_s`` is simulated seconds (``None`` without a plan);
    ``automatic_rating`` is the automatic rater's 1-5 score.
    """

    task: int
    trial: int
    seed: int
    method: str
    objects: tuple[str, ...]
    automatic_rating: int
    execution_time_s: float | None
    success: bool
    picture: bytes
    picture_source: str


@dataclass(frozen=True)
class StudyInfo:
    """What a study database holds: its ``name``, the bench it came from, how many
    pictures, raters and ratings, and its methods and tasks."""

    name: str
    source: str
    items: int
    raters: int
    ratings: int
    methods: tuple[str, ...]
    tasks: tuple[int, ...]


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def clean_png(data: bytes, where: str, *, drop_title: bool = False) -> bytes:
    """``data`` (any picture Pillow reads) as PNG with no text, time or software chunks;
    ``drop_title`` cuts off a bench drawing's title band (:func:`below_title`)."""
    try:
        with Image.open(io.BytesIO(data)) as img:
            img.load()
            pixels = img.convert("RGBA" if "A" in img.getbands() else "RGB")
    except (UnidentifiedImageError, OSError, ValueError):
        raise BadInput(f"{where}: not a picture") from None
    if drop_title:
        pixels = below_title(pixels)
    out = io.BytesIO()
    pixels.save(out, format="PNG", optimize=False)
    return out.getvalue()


def below_title(img: Image.Image) -> Image.Image:
    """``img``, a bench's drawing, from just above its plot frame down: without the title
    and the list of objects over it. The frame is the first dark line across
    1/:data:`FRAME_FRACTION` of the picture's width, in its upper half (no lettering is
    one unbroken line); a picture without one (a table ten times deeper than wide) is kept
    whole."""
    ink = np.asarray(img.convert("L")) < 200
    height, width = ink.shape
    for y in range(height // 2):
        # The longest unbroken run of ink in the row, from where runs start and end.
        edges = np.flatnonzero(np.diff(np.concatenate(([0], ink[y].astype(np.int8), [0]))))
        if edges.size and int((edges[1::2] - edges[::2]).max()) >= width // FRAME_FRACTION:
            top = y - TITLE_CUT_MARGIN_PX
            return img.crop((0, top, width, height)) if top > 0 else img
    return img


def requested_objects(row: TrialRow, where: str) -> tuple[str, ...]:
    """The objects the trial's picture lists at its top: the task's objects (read from
    the request, by the packaged catalog, in rows written before rows kept them)."""
    if row.requested is not None:
        return tuple(row.requested)
    try:
        return tuple(i.kind for i in parse_request(row.request, Catalog.load()).items)
    except BadInput:
        raise BadInput(f"{where}: the row does not list its requested objects; run the "
                       "bench again with this llm-grop") from None


def items_from_bench(bench: Path, on_picture: Callable[[int, int], None] | None = None
                     ) -> list[StudyItem]:
    """Every trial of the bench directory ``bench`` as a :class:`StudyItem`, in the
    bench's order; ``on_picture(k, n)`` after the k-th of n pictures is read. Raises
    :class:`BadInput` for a directory without trials (listing the cells of a sweep's
    directory), or a trial without a picture."""
    if not (bench / ROWS).is_file():
        cells = cell_dirs(bench)
        if cells:
            more = len(cells) - LISTED_CELLS
            raise BadInput(f"--bench {bench}: a sweep directory; choose one of its cells: "
                           + ", ".join(map(str, cells[:LISTED_CELLS]))
                           + (f" and {more} more" if more > 0 else ""))
        raise BadInput(f"--bench {bench}: no {ROWS}; give a directory 'llm-grop bench "
                       "--out' wrote")
    rows = read_rows(bench)
    failed = sum(r.status == "llm-failed" for r in rows)
    if failed:
        # Their empty tables say nothing of the methods: people do not rate them.
        raise BadInput(f"--bench {bench}: {failed} trial(s) got no LLM answer "
                       "(status llm-failed); rerun the bench to retry them first")
    if not rows:
        raise BadInput(f"--bench {bench}: {ROWS} holds no trial")
    items = []
    for row in rows:
        where = f"--bench {bench}: task {row.task} trial {row.trial} {row.method}"
        relative = row.render or row.image
        if relative is None:
            raise BadInput(f"{where}: has no picture; run the bench without --no-images")
        path = bench / relative
        try:
            data = path.read_bytes()
        except OSError as exc:
            raise BadInput(f"{where}: picture {relative}: {exc.strerror or exc}") from None
        items.append(StudyItem(
            task=row.task, trial=row.trial, seed=row.seed, method=row.method,
            objects=requested_objects(row, where), automatic_rating=row.rating,
            execution_time_s=row.execution_time_s, success=row.success,
            picture=clean_png(data, f"{where}: picture {relative}",
                              drop_title=row.render is None),
            picture_source=relative))
        if on_picture is not None:
            on_picture(len(items), len(rows))
    return items


def create_study(db: Path, items: Sequence[StudyItem], *, name: str, source: str,
                 seed: int = 0) -> StudyInfo:
    """Write a new study database at ``db`` holding ``items``; its summary.

    The file is written beside ``db`` and renamed into place, so a failure leaves nothing.
    Raises :class:`BadInput` if ``db`` exists, or ``items`` is empty or repeats a trial.
    """
    if db.exists():
        raise BadInput(f"--db {db}: already exists; a study is made once, in a new file")
    if not items:
        raise BadInput("a study needs at least one picture")
    keys = [(i.task, i.trial, i.method) for i in items]
    if len(set(keys)) != len(keys):
        raise BadInput("a study's pictures must be distinct trials")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{db.name[:40]}.", suffix=".tmp", dir=db.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        tmp.unlink()
        conn = connect(tmp, create=True)
        try:
            _fill(conn, items, name=name, source=source, seed=seed)
            conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
        finally:
            conn.close()
        os.replace(tmp, db)
    finally:
        for leftover in (tmp, Path(f"{tmp}-wal"), Path(f"{tmp}-shm")):
            leftover.unlink(missing_ok=True)
    return study_info(db)


def _fill(conn: sqlite3.Connection, items: Sequence[StudyItem], *, name: str, source: str,
          seed: int) -> None:
    with transaction(conn):
        cur = conn.execute("INSERT INTO study (name, source, seed, created_at)"
                           " VALUES (?, ?, ?, ?)", (name, source, seed, _now()))
        conn.executemany(
            "INSERT INTO items (id, study_id, position, task, trial, seed, method, objects,"
            " automatic_rating, execution_time_s, success, picture, picture_source)"
            " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            [(secrets.token_hex(8), cur.lastrowid, position, item.task, item.trial, item.seed,
              item.method, json.dumps(list(item.objects)), item.automatic_rating,
              item.execution_time_s, int(item.success), item.picture, item.picture_source)
             for position, item in enumerate(items)])


def study_info(db: Path) -> StudyInfo:
    """The summary of the study in ``db``."""
    conn = connect(db)
    try:
        study = conn.execute("SELECT name, source FROM study").fetchone()
        if study is None:
            raise BadInput(f"--db {db}: holds no study")
        count = {t: conn.execute(f"SELECT count(*) FROM {t}").fetchone()[0]
                 for t in ("items", "raters", "ratings")}
        methods = tuple(r[0] for r in conn.execute(
            "SELECT method FROM items GROUP BY method ORDER BY min(position)"))
        tasks = tuple(r[0] for r in conn.execute("SELECT DISTINCT task FROM items ORDER BY task"))
    finally:
        conn.close()
    return StudyInfo(study["name"], study["source"], count["items"], count["raters"],
                     count["ratings"], methods, tasks)


def new_code() -> str:
    """A fresh invite code, such as ``"K7QH-2MZP-R9WA"``."""
    raw = "".join(secrets.choice(CODE_ALPHABET) for _ in range(CODE_CHARS))
    return "-".join(raw[i:i + 4] for i in range(0, CODE_CHARS, 4))


def normal_code(text: str) -> str:
    """An invite code as typed (any case, spaces or dashes) in its stored form."""
    raw = "".join(c for c in text.upper() if c.isalnum())
    return "-".join(raw[i:i + 4] for i in range(0, len(raw), 4))


def invite(db: Path, count: int) -> list[str]:
    """Invite ``count`` new raters to the study in ``db``; their invite codes.

    Each rater gets the study's pictures in an order of their own, drawn from the study's
    seed and the rater's number, so the same study and count give the same orders.
    """
    if not 1 <= count <= MAX_INVITES:
        raise BadInput(f"--count {count}: invite between 1 and {MAX_INVITES} raters at a time")
    conn = connect(db)
    try:
        with transaction(conn):
            study = conn.execute("SELECT id, seed FROM study").fetchone()
            if study is None:
                raise BadInput(f"--db {db}: holds no study")
            items = [r[0] for r in conn.execute("SELECT id FROM items ORDER BY position")]
            first = conn.execute("SELECT count(*) FROM raters").fetchone()[0]
            codes = []
            for number in range(first, first + count):
                code = new_code()
                cur = conn.execute("INSERT INTO raters (study_id, code, label, created_at)"
                                   " VALUES (?, ?, ?, ?)",
                                   (study["id"], code, f"r{number + 1}", _now()))
                order = seeds.stream(study["seed"], "ratings.order", number).permutation(
                    len(items))
                conn.executemany("INSERT INTO rater_items (rater_id, position, item_id)"
                                 " VALUES (?, ?, ?)",
                                 [(cur.lastrowid, k, items[i]) for k, i in enumerate(order)])
                codes.append(code)
    finally:
        conn.close()
    return codes
