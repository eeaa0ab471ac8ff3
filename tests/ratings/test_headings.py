"""Every page of the rating site, and the human report, says each heading once: the page's
HTML as served, and the drawing under the rating page's heading without its own title."""

from __future__ import annotations

import io
import json
from collections import Counter
from collections.abc import Iterator
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

from llm_grop.ratings.app import create_app
from llm_grop.ratings.db import connect
from llm_grop.ratings.report import human_report, with_data, write_report
from llm_grop.ratings.store import RatingStore
from ratings_support import ADMIN

#: The Origin a browser sends with the site's own forms (the test client's host).
SAME = {"origin": "http://testserver"}
HEADINGS = ("h1", "h2", "h3", "h4", "h5", "h6", "legend", "caption")


class _Page(HTMLParser):
    """The text of a page's headings and of its table headers, and all its visible text."""

    def __init__(self) -> None:
        super().__init__()
        self.headings: list[str] = []
        self.columns: list[list[str]] = []
        self.text: list[str] = []
        self._open: list[tuple[str, list[str]]] = []
        self._skip = 0

    def handle_starttag(self, tag: str, attrs) -> None:  # type: ignore[no-untyped-def]
        if tag in ("script", "style", "title"):
            self._skip += 1
        if tag == "thead":
            self.columns.append([])
        if tag in HEADINGS or tag == "th":
            self._open.append((tag, []))

    def handle_endtag(self, tag: str) -> None:
        if tag in ("script", "style", "title"):
            self._skip -= 1
        if self._open and self._open[-1][0] == tag:
            _, parts = self._open.pop()
            text = " ".join("".join(parts).split())
            if tag == "th":
                if self.columns:
                    self.columns[-1].append(text)
            else:
                self.headings.append(text)

    def handle_data(self, data: str) -> None:
        if self._skip:
            return
        self.text.append(data)
        for _, parts in self._open:
            parts.append(data)


def page(html: str) -> _Page:
    parsed = _Page()
    parsed.feed(html)
    return parsed


def assert_each_heading_once(html: str) -> _Page:
    parsed = page(html)
    assert parsed.headings, "a page without a heading"
    repeated = [h for h, n in Counter(parsed.headings).items() if n > 1]
    assert repeated == []
    return parsed


@pytest.fixture
def client(study) -> Iterator[TestClient]:
    with TestClient(create_app(study[0], admin_token=ADMIN)) as c:
        yield c


def _csrf(html: str) -> str:
    return html.split('name="csrf" value="', 1)[1].split('"', 1)[0]


def test_each_page_says_each_heading_once(client: TestClient, study) -> None:
    assert_each_heading_once(client.get("/").text)
    assert_each_heading_once(client.post("/join", data={"code": "nope"}, headers=SAME).text)
    guidelines = client.post("/join", data={"code": study[1][0]}, headers=SAME)
    assert assert_each_heading_once(guidelines.text).headings[0] == "How to rate"
    for _ in range(16):
        rate = client.get("/rate").text
        parsed = assert_each_heading_once(rate)
        assert parsed.headings[0].startswith("Requested: ")
        assert "".join(parsed.text).count("Requested") == 1
        item = rate.split('data-item="', 1)[1].split('"', 1)[0]
        after = client.post("/rate", data={"item": item, "rating": "3", "csrf": _csrf(rate)},
                            headers=SAME)
        assert after.status_code == 200
    done = assert_each_heading_once(client.get("/rate").text)
    assert done.headings == ["Thank you"]


def test_a_drawing_is_shown_without_its_title(bench_dir: Path, bench_items) -> None:
    # The bench's drawing lists the request above its plot, as the page's heading does.
    rows = [json.loads(line) for line in (bench_dir / "trials.jsonl").read_text().splitlines()]
    for item, row in zip(bench_items, rows, strict=True):
        assert row.get("render") is None
        with Image.open(bench_dir / row["image"]) as drawn:
            drawn = drawn.convert("RGB")
        with Image.open(io.BytesIO(item.picture)) as shown:
            shown = shown.convert("RGB")
        cut = drawn.height - shown.height
        assert shown.width == drawn.width and 0 < cut < drawn.height // 4
        assert np.array_equal(np.asarray(shown), np.asarray(drawn)[cut:])
        ink = np.asarray(drawn.convert("L")) < 200
        assert ink[:cut].any(), "the band cut off held no title"
        # What is left starts with white space, then the plot's frame: no lettering.
        top = np.asarray(shown.convert("L")) < 200
        first = int(np.argmax(top.any(axis=1)))
        assert first > 0 and top[first].sum() > shown.width // 2


def test_the_report_says_each_heading_once_and_shows_columns_with_data(
        study, tmp_path: Path) -> None:
    db, _ = study
    conn = connect(db)
    try:
        store = RatingStore(conn)
        items = conn.execute("SELECT id FROM items ORDER BY position").fetchall()
        for rater in (1, 2):
            for k, (item,) in enumerate(items):
                store.rate(rater, item, 1 + (k + rater) % 5)
        report = human_report(conn)
    finally:
        conn.close()
    write_report(report, tmp_path)
    parsed = assert_each_heading_once((tmp_path / "report.html").read_text())
    assert parsed.headings[0] == "Human ratings: test study"
    per_method = parsed.columns[0]
    # A study keeps no planning time: that column was all "-", and is left out.
    assert per_method == ["method", "trials", "rating (1-5), mean ± SE",
                          "execution time (s), mean ± SE", "success rate"]
    markdown = (tmp_path / "report.md").read_text()
    assert "planning time" not in markdown and "| method | trials | rating" in markdown
    for table in parsed.columns:
        assert table and all(table)


def test_only_columns_with_data_are_kept() -> None:
    headers = ("method", "time", "note", "p")
    rows = [("a", "1.0", "-", "-"), ("b", "-", " ", "0.5")]
    assert with_data(headers, rows) == (("method", "time", "p"),
                                        [("a", "1.0", "-"), ("b", "-", "0.5")])
    assert with_data(headers, []) == (headers, [])


@pytest.mark.parametrize("size_m", [(0.9, 0.6), (0.6, 1.2), (0.5, 2.0), (2.0, 0.5)])
def test_the_title_is_cut_off_whatever_the_table_shape(size_m: tuple[float, float],
                                                       tmp_path: Path) -> None:
    from llm_grop.ratings.study import below_title
    from llm_grop.render.table import draw_arrangement
    from llm_grop.world.arrangement import Arrangement
    from llm_grop.world.table import Table

    path = tmp_path / "t.png"
    draw_arrangement(Arrangement("x", Table(*size_m), ()), path,
                     title="Requested: dinner plate, dinner fork, dinner knife")
    whole = Image.open(path)
    cut = below_title(whole)
    assert cut.size[0] == whole.size[0] and cut.size[1] < whole.size[1]
    # What is left starts with white space, above the plot frame.
    top = np.asarray(cut.convert("L"))[:5]
    assert (top > 200).all()
