"""Studies from a bench: pictures blind and clean, per-rater orders, the database's
schema migrations, and refusals."""

from __future__ import annotations

import io
import json
import sqlite3
import struct
from pathlib import Path

import pytest
from PIL import Image

from llm_grop.errors import BadInput
from llm_grop.ratings.db import APPLICATION_ID, connect, migrations, schema_version
from llm_grop.ratings.study import (
    CODE_ALPHABET,
    create_study,
    invite,
    items_from_bench,
    normal_code,
    study_info,
)

METHODS = ("tpra", "latp", "grop", "llm-grop")


def png_chunks(data: bytes) -> list[bytes]:
    """The chunk types of a PNG file."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    kinds, at = [], 8
    while at < len(data):
        length, = struct.unpack(">I", data[at:at + 4])
        kinds.append(data[at + 4:at + 8])
        at += 12 + length
    return kinds


def test_items_are_the_bench_trials_with_their_pictures(bench_dir: Path, bench_items) -> None:
    rows = [json.loads(line) for line in (bench_dir / "trials.jsonl").read_text().splitlines()]
    assert len(bench_items) == len(rows) == 16
    for item, row in zip(bench_items, rows, strict=True):
        assert (item.task, item.trial, item.method) == (row["task"], row["trial"],
                                                        row["method"])
        assert item.picture_source == row["image"]
        assert item.automatic_rating == row["rating"]
        assert list(item.objects) == row["requested"]
        # The picture is kept with no text chunk that could name the method.
        assert set(png_chunks(item.picture)) <= {b"IHDR", b"IDAT", b"IEND", b"PLTE"}


def test_a_study_hides_the_methods(study) -> None:
    db, _ = study
    with sqlite3.connect(db) as conn:
        ids = [r[0] for r in conn.execute("SELECT id FROM items")]
    assert len(set(ids)) == 16
    for item in ids:
        assert len(item) == 16 and all(c in "0123456789abcdef" for c in item)
    info = study_info(db)
    assert (info.items, info.raters, info.ratings) == (16, 3, 0)
    assert set(info.methods) == set(METHODS) and info.tasks == (1, 2)


def test_each_rater_has_an_order_of_their_own_from_the_seed(tmp_path: Path, bench_items
                                                            ) -> None:
    orders = []
    for name in ("a.db", "b.db"):
        db = tmp_path / name
        create_study(db, bench_items, name="s", source="bench", seed=7)
        invite(db, 3)
        with sqlite3.connect(db) as conn:
            positions = {i: p for i, p in conn.execute("SELECT id, position FROM items")}
            orders.append([[positions[i] for (i,) in conn.execute(
                "SELECT item_id FROM rater_items WHERE rater_id = ? ORDER BY position", (r,))]
                for r in (1, 2, 3)])
    assert orders[0] == orders[1]  # the same seed gives the same orders
    first = orders[0]
    assert all(sorted(o) == list(range(16)) for o in first)
    assert len({tuple(o) for o in first}) == 3


def test_invite_codes(study) -> None:
    db, codes = study
    assert len(set(codes)) == 3
    for code in codes:
        assert len(code) == 14 and code.count("-") == 2
        assert all(c in CODE_ALPHABET for c in code.replace("-", ""))
        assert normal_code(code.lower().replace("-", " ")) == code
    more = invite(db, 2)
    assert study_info(db).raters == 5 and not set(more) & set(codes)


@pytest.mark.parametrize("count", [0, -1, 1001])
def test_invite_count_bounds(study, count: int) -> None:
    with pytest.raises(BadInput, match="--count"):
        invite(study[0], count)


def test_create_refuses_an_existing_file(study, bench_items) -> None:
    with pytest.raises(BadInput, match="already exists"):
        create_study(study[0], bench_items, name="x", source="y")


def test_a_bench_without_pictures_is_refused(tmp_path: Path, bench_dir: Path) -> None:
    copy = tmp_path / "bench"
    copy.mkdir()
    rows = (bench_dir / "trials.jsonl").read_text().splitlines()
    (copy / "trials.jsonl").write_text(rows[0] + "\n")
    with pytest.raises(BadInput, match=r"task 1 trial 0 \w+: picture images/.*No such file"):
        items_from_bench(copy)
    row = json.loads(rows[0])
    row.pop("image")
    (copy / "trials.jsonl").write_text(json.dumps(row) + "\n")
    with pytest.raises(BadInput, match="has no picture; run the bench without --no-images"):
        items_from_bench(copy)
    (copy / "trials.jsonl").write_text("")
    with pytest.raises(BadInput, match="holds no trial"):
        items_from_bench(copy)
    with pytest.raises(BadInput, match="no trials.jsonl"):
        items_from_bench(tmp_path / "nowhere")


def test_a_picture_that_is_not_one_is_refused(tmp_path: Path, bench_dir: Path) -> None:
    copy = tmp_path / "bench"
    (copy / "images").mkdir(parents=True)
    row = json.loads((bench_dir / "trials.jsonl").read_text().splitlines()[0])
    (copy / row["image"]).write_text("not a png")
    (copy / "trials.jsonl").write_text(json.dumps(row) + "\n")
    with pytest.raises(BadInput, match="not a picture"):
        items_from_bench(copy)


def test_a_3d_render_is_preferred_to_the_drawing(tmp_path: Path, bench_dir: Path) -> None:
    copy = tmp_path / "bench"
    (copy / "images").mkdir(parents=True)
    row = json.loads((bench_dir / "trials.jsonl").read_text().splitlines()[0])
    (copy / row["image"]).write_bytes((bench_dir / row["image"]).read_bytes())
    Image.new("RGB", (40, 30), (200, 10, 10)).save(copy / "images" / "render.png")
    row["render"] = "images/render.png"
    (copy / "trials.jsonl").write_text(json.dumps(row) + "\n")
    item = items_from_bench(copy)[0]
    assert item.picture_source == "images/render.png"
    with Image.open(io.BytesIO(item.picture)) as picture:
        assert picture.size == (40, 30)


def test_rows_without_requested_objects_read_them_from_the_request(tmp_path: Path,
                                                                   bench_dir: Path) -> None:
    copy = tmp_path / "bench"
    (copy / "images").mkdir(parents=True)
    row = json.loads((bench_dir / "trials.jsonl").read_text().splitlines()[0])
    row.pop("requested")
    (copy / row["image"]).write_bytes((bench_dir / row["image"]).read_bytes())
    (copy / "trials.jsonl").write_text(json.dumps(row) + "\n")
    assert items_from_bench(copy)[0].objects == ("dinner plate", "dinner fork", "dinner knife")


# ---- the database's schema ---------------------------------------------------------------

def test_a_new_database_is_wal_at_the_newest_schema(study) -> None:
    conn = connect(study[0])
    try:
        assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        assert conn.execute("PRAGMA user_version").fetchone()[0] == schema_version() >= 2
        assert conn.execute("PRAGMA application_id").fetchone()[0] == APPLICATION_ID
    finally:
        conn.close()


def test_an_older_schema_is_migrated_keeping_its_data(tmp_path: Path) -> None:
    db = tmp_path / "old.db"
    conn = connect(db, create=True, upto=1)
    conn.execute("INSERT INTO study (name, source, seed, created_at) VALUES ('s', 'b', 0, 'now')")
    assert conn.execute("PRAGMA user_version").fetchone()[0] == 1
    assert not conn.execute("SELECT 1 FROM sqlite_master WHERE name = 'ratings_by_item'"
                            ).fetchone()
    conn.close()
    conn = connect(db)
    try:
        assert conn.execute("PRAGMA user_version").fetchone()[0] == len(migrations())
        assert conn.execute("SELECT 1 FROM sqlite_master WHERE name = 'ratings_by_item'"
                            ).fetchone()
        assert conn.execute("SELECT name FROM study").fetchone()[0] == "s"
    finally:
        conn.close()


def test_a_newer_or_foreign_database_is_refused(tmp_path: Path, study) -> None:
    newer = study[0]
    with sqlite3.connect(newer) as conn:
        conn.execute(f"PRAGMA user_version = {schema_version() + 1}")
    with pytest.raises(BadInput, match="written by a newer llm-grop"):
        connect(newer)
    foreign = tmp_path / "foreign.db"
    with sqlite3.connect(foreign) as conn:
        conn.execute("CREATE TABLE t (x)")
    with pytest.raises(BadInput, match="not an llm-grop study database"):
        connect(foreign)
    text = tmp_path / "text.db"
    text.write_text("hello, this is not SQLite at all, just some text " * 20)
    with pytest.raises(BadInput, match="not an llm-grop study database"):
        connect(text)
    with pytest.raises(BadInput, match="no such study database"):
        connect(tmp_path / "missing.db")
