"""The website's JSON API and pages: the rater flow, and every refusal of issue 14's
security list, each a 4xx status with a one-line JSON error."""

from __future__ import annotations

import csv
import io
import sqlite3
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from llm_grop.ratings.app import COOKIE, CSRF_HEADER, create_app
from ratings_support import ADMIN

METHODS = ("tpra", "latp", "grop", "llm-grop")
BEARER = {"Authorization": f"Bearer {ADMIN}"}
#: The Origin a browser sends with the site's own forms (the test client's host).
SAME = {"origin": "http://testserver"}


@pytest.fixture
def client(study) -> Iterator[TestClient]:
    with TestClient(create_app(study[0], admin_token=ADMIN)) as c:
        yield c


def join(client: TestClient, code: str) -> str:
    """Join as the rater with ``code``; their CSRF token."""
    r = client.post("/api/session", json={"code": code})
    assert r.status_code == 200, r.text
    return r.json()["csrf"]


def refused(response, status: int, needle: str) -> None:
    assert response.status_code == status, response.text
    body = response.json()
    assert list(body) == ["error"] and "\n" not in body["error"]
    assert needle in body["error"]


def test_a_rater_rates_every_picture_once_in_their_order(client: TestClient, study) -> None:
    db, codes = study
    csrf = join(client, codes[0])
    seen = []
    while True:
        nxt = client.get("/api/next").json()
        assert nxt["done"] == len(seen) and nxt["total"] == 16
        if nxt["item"] is None:
            break
        assert nxt["image"] == f"/images/{nxt['item']}"
        assert nxt["objects"] in (["dinner plate", "dinner fork", "dinner knife"],
                                  ["bread plate", "water cup", "bread"])
        r = client.post("/api/ratings", json={"item": nxt["item"], "rating": 1 + len(seen) % 5},
                        headers={CSRF_HEADER: csrf})
        assert r.status_code == 201 and r.json()["done"] == len(seen) + 1
        seen.append(nxt["item"])
    assert len(set(seen)) == 16
    with sqlite3.connect(db) as conn:
        order = [r[0] for r in conn.execute(
            "SELECT item_id FROM rater_items WHERE rater_id = 1 ORDER BY position")]
    assert seen == order
    assert client.get("/api/next").json() == {"item": None, "image": None, "objects": [],
                                              "done": 16, "total": 16}


def test_nothing_a_rater_sees_names_the_method(client: TestClient, study) -> None:
    csrf = join(client, study[1][0])
    for _ in range(16):
        nxt = client.get("/api/next")
        page = client.get("/rate")
        picture = client.get(nxt.json()["image"])
        for text in (nxt.text, page.text):
            for method in METHODS:
                assert method not in text.lower()
        assert picture.headers["content-type"] == "image/png"
        assert "content-disposition" not in picture.headers
        assert all(m.encode() not in picture.content for m in METHODS)
        assert client.post("/api/ratings", json={"item": nxt.json()["item"], "rating": 3},
                           headers={CSRF_HEADER: csrf}).status_code == 201


def _page_csrf(html: str) -> str:
    return html.split('name="csrf-token" content="', 1)[1].split('"', 1)[0]


def test_leaving_and_coming_back_resumes(study) -> None:
    db, codes = study
    with TestClient(create_app(db, admin_token=ADMIN)) as first:
        csrf = join(first, codes[0])
        for _ in range(5):
            item = first.get("/api/next").json()["item"]
            first.post("/api/ratings", json={"item": item, "rating": 4},
                       headers={CSRF_HEADER: csrf})
        sixth = first.get("/api/next").json()["item"]
        r = first.delete("/api/session", headers={CSRF_HEADER: csrf})
        assert r.status_code == 200
        refused(first.get("/api/next"), 401, "not signed in")
    with TestClient(create_app(db, admin_token=ADMIN)) as again:
        join(again, codes[0].lower())
        nxt = again.get("/api/next").json()
        assert (nxt["item"], nxt["done"]) == (sixth, 5)
        assert "6 / 16" in again.get("/rate").text


def test_session_cookie_is_http_only_and_strict(client: TestClient, study) -> None:
    r = client.post("/api/session", json={"code": study[1][0]})
    cookie = r.headers["set-cookie"]
    assert f"{COOKIE}=" in cookie and "HttpOnly" in cookie and "SameSite=strict" in cookie
    assert "Max-Age=28800" in cookie
    assert r.headers["content-security-policy"].startswith("default-src 'self'")
    assert r.headers["cache-control"] == "no-store"


# ---- refusals ------------------------------------------------------------------------------

def test_joining_needs_a_known_code(client: TestClient) -> None:
    refused(client.post("/api/session", json={"code": "AAAA-BBBB-CCCC"}), 401,
            "unknown invite code")
    refused(client.post("/api/session", json={"code": 5}), 422, "code")
    refused(client.post("/api/session", json={}), 422, "code: required, but missing")
    refused(client.post("/api/session", content=b"code=x",
                        headers={"content-type": "application/x-www-form-urlencoded"}), 422, "")
    refused(client.post("/api/session", json={"code": "x" * 101}), 422, "code")


@pytest.mark.parametrize(("body", "words"), [
    (b'{"code": "\xff"}', "body: not UTF-8 text"),
    (b'{"code": ' + b"9" * 5000 + b"}", "a number of more than 4300 digits"),
    (b'{"code": ' + b"[" * 5000 + b"]" * 5000 + b"}", "nested more than 8 deep"),
    (b'{"code": ' + b"[" * 8 + b"]" * 8 + b"}", "nested more than 8 deep"),
    (b"{code", "body: not JSON"),
])
def test_a_body_that_cannot_be_read_is_422(client: TestClient, body: bytes,
                                           words: str) -> None:
    refused(client.post("/api/session", content=body,
                        headers={"content-type": "application/json"}), 422, words)


def test_the_api_needs_a_live_session(client: TestClient, study) -> None:
    db, codes = study
    refused(client.get("/api/next"), 401, "not signed in")
    refused(client.post("/api/ratings", json={"item": "x", "rating": 3}), 401, "not signed in")
    client.cookies.set(COOKIE, "forged-token")
    refused(client.get("/api/next"), 401, "not signed in")
    client.cookies.clear()
    join(client, codes[0])
    with sqlite3.connect(db) as conn:
        conn.execute("UPDATE sessions SET expires_at = 0")
    refused(client.get("/api/next"), 401, "session expired")
    page = client.get("/rate")
    assert page.status_code == 401 and "session expired" in page.text


def test_writes_need_the_sessions_csrf_token(client: TestClient, study) -> None:
    codes = study[1]
    csrf = join(client, codes[0])
    item = client.get("/api/next").json()["item"]
    body = {"item": item, "rating": 3}
    refused(client.post("/api/ratings", json=body), 403, "CSRF")
    refused(client.post("/api/ratings", json=body, headers={CSRF_HEADER: "wrong"}), 403, "CSRF")
    # A second browser on the same server (its lifespan is the first client's).
    other_csrf = join(TestClient(client.app), codes[1])
    refused(client.post("/api/ratings", json=body, headers={CSRF_HEADER: other_csrf}), 403,
            "CSRF")
    form = client.post("/rate", data={"item": item, "rating": "3", "csrf": "wrong"},
                       headers=SAME)
    assert form.status_code == 403 and "CSRF" in form.text
    refused(client.delete("/api/session"), 403, "CSRF")
    assert client.post("/api/ratings", json=body, headers={CSRF_HEADER: csrf}).status_code == 201


@pytest.mark.parametrize("rating", [0, 6, -1, 3.0, 3.5, "3", True, None, [3]])
def test_a_rating_must_be_an_integer_from_1_to_5(client: TestClient, study, rating) -> None:
    csrf = join(client, study[1][0])
    item = client.get("/api/next").json()["item"]
    refused(client.post("/api/ratings", json={"item": item, "rating": rating},
                        headers={CSRF_HEADER: csrf}), 422, "rating")
    assert client.get("/api/next").json()["done"] == 0


def test_a_rating_is_for_an_item_of_the_study_at_most_once(client: TestClient, study,
                                                           tmp_path: Path, bench_items) -> None:
    from llm_grop.ratings.study import create_study
    other = tmp_path / "other.db"
    create_study(other, bench_items, name="other", source="bench")
    with sqlite3.connect(other) as conn:
        foreign = conn.execute("SELECT id FROM items").fetchone()[0]
    csrf = join(client, study[1][0])
    headers = {CSRF_HEADER: csrf}
    refused(client.post("/api/ratings", json={"item": foreign, "rating": 3}, headers=headers),
            404, "no such picture")
    refused(client.post("/api/ratings", json={"item": "../../etc/passwd", "rating": 3},
                        headers=headers), 404, "no such picture")
    item = client.get("/api/next").json()["item"]
    assert client.post("/api/ratings", json={"item": item, "rating": 2},
                       headers=headers).status_code == 201
    refused(client.post("/api/ratings", json={"item": item, "rating": 5}, headers=headers),
            409, "already rated")
    with sqlite3.connect(study[0]) as conn:
        assert conn.execute("SELECT rating FROM ratings").fetchall() == [(2,)]


def test_a_rater_cannot_rate_as_another(client: TestClient, study) -> None:
    csrf = join(client, study[1][0])
    item = client.get("/api/next").json()["item"]
    for extra in ({"rater": "r2"}, {"rater_id": 2}, {"session": "x"}):
        refused(client.post("/api/ratings", json={"item": item, "rating": 3} | extra,
                            headers={CSRF_HEADER: csrf}), 422, "unknown key")
    assert client.post("/api/ratings", json={"item": item, "rating": 3},
                       headers={CSRF_HEADER: csrf}).status_code == 201
    with sqlite3.connect(study[0]) as conn:
        assert conn.execute("SELECT rater_id FROM ratings").fetchall() == [(1,)]


def test_a_rater_sees_only_their_own_progress_and_pictures(client: TestClient, study) -> None:
    csrf = join(client, study[1][0])
    item = client.get("/api/next").json()["item"]
    client.post("/api/ratings", json={"item": item, "rating": 3}, headers={CSRF_HEADER: csrf})
    other = TestClient(client.app)
    join(other, study[1][1])
    assert other.get("/api/next").json()["done"] == 0
    refused(other.get("/api/admin/progress"), 401, "Bearer")


def test_pictures_are_served_by_id_only(client: TestClient, study) -> None:
    refused(client.get("/images/anything"), 401, "not signed in")
    join(client, study[1][0])
    for path in ("/images/..%2F..%2Fetc%2Fpasswd", "/images/%2Fetc%2Fpasswd",
                 "/images/0000000000000000", "/images/study.db"):
        r = client.get(path)
        assert r.status_code == 404 and r.headers["content-type"] == "application/json"
    assert client.get("/images/../../etc/passwd").status_code == 404
    assert client.get("/static/../../db.py").status_code == 404


def test_admin_endpoints_need_the_token(client: TestClient, study) -> None:
    for path in ("/api/admin/progress", "/api/admin/export.csv"):
        refused(client.get(path), 401, "Bearer")
        refused(client.get(path, headers={"Authorization": "Bearer wrong"}), 401, "Bearer")
        refused(client.get(path, headers={"Authorization": ADMIN}), 401, "Bearer")
        refused(client.get(path, headers={"Authorization": f"Basic {ADMIN}"}), 401, "Bearer")
    csrf = join(client, study[1][2])
    item = client.get("/api/next").json()["item"]
    client.post("/api/ratings", json={"item": item, "rating": 5}, headers={CSRF_HEADER: csrf})
    progress = client.get("/api/admin/progress", headers=BEARER).json()
    assert progress["items"] == 16 and progress["ratings"] == 1
    assert [(r["rater"], r["done"], r["total"]) for r in progress["raters"]] == [
        ("r1", 0, 16), ("r2", 0, 16), ("r3", 1, 16)]
    rows = list(csv.DictReader(io.StringIO(
        client.get("/api/admin/export.csv", headers=BEARER).text)))
    assert len(rows) == 1 and rows[0]["rater"] == "r3" and rows[0]["rating"] == "5"
    assert rows[0]["item"] == item and rows[0]["method"] in METHODS


def test_forms_from_another_site_are_refused(client: TestClient, study) -> None:
    for origin in ("https://evil.example", "null", None):
        headers = {"origin": origin} if origin else {}
        r = client.post("/join", data={"code": study[1][0]}, headers=headers,
                        follow_redirects=False)
        assert r.status_code == 403 and "another site" in r.text
    r = client.post("/join", data={"code": study[1][0]}, headers=SAME,
                    follow_redirects=False)
    assert r.status_code == 303 and r.headers["location"] == "/guidelines"
    page = client.get("/rate")
    item = page.text.split('data-item="', 1)[1].split('"', 1)[0]
    for path, data in (("/rate", {"item": item, "rating": "4", "csrf": _page_csrf(page.text)}),
                       ("/leave", {"csrf": _page_csrf(page.text)})):
        r = client.post(path, data=data, headers={"origin": "null"})
        assert r.status_code == 403, path


def test_a_huge_body_is_refused_unread(client: TestClient, study) -> None:
    refused(client.post("/api/session", content=b'{"code": "' + b"A" * 100_000 + b'"}',
                        headers={"content-type": "application/json"}), 413, "larger than")

    def chunks():
        for _ in range(100):
            yield b"A" * 1024

    # Chunked: no length is declared; the server stops reading at its limit.
    refused(client.post("/api/session", content=chunks(),
                        headers={"content-type": "application/json"}), 413, "larger than")


def test_join_attempts_are_limited_per_address(client: TestClient, study) -> None:
    from llm_grop.ratings.app import JOINS_PER_MINUTE

    for _ in range(JOINS_PER_MINUTE):
        refused(client.post("/api/session", json={"code": "WRONG-CODE"}), 401, "unknown")
    r = client.post("/api/session", json={"code": study[1][0]})
    refused(r, 429, "too many failed join attempts from this address")
    assert 1 <= int(r.headers["retry-after"]) <= 60
    r = client.post("/join", data={"code": study[1][0]}, headers=SAME, follow_redirects=False)
    assert r.status_code == 429 and r.headers["retry-after"].isdigit()


def test_a_rater_keeps_at_most_five_sessions(study) -> None:
    from llm_grop.ratings.store import MAX_SESSIONS

    db, codes = study
    with TestClient(create_app(db, admin_token=ADMIN)) as c:
        for _ in range(8):
            c.cookies.clear()
            join(c, codes[0])
    with sqlite3.connect(db) as conn:
        assert conn.execute("SELECT count(*) FROM sessions").fetchone()[0] == MAX_SESSIONS


def test_unknown_routes_and_methods_are_json_errors(client: TestClient) -> None:
    refused(client.get("/api/nothing"), 404, "Not Found")
    refused(client.put("/api/ratings"), 405, "Method Not Allowed")


def test_pages_without_javascript(client: TestClient, study) -> None:
    assert "Invite code" in client.get("/").text
    r = client.post("/join", data={"code": "nope"}, headers=SAME)
    assert r.status_code == 401 and "unknown invite code" in r.text
    guidelines = client.post("/join", data={"code": study[1][0]}, headers=SAME)
    assert guidelines.status_code == 200 and "experienced human waiter" in guidelines.text
    page = client.get("/rate")
    assert "1 / 16" in page.text
    item = page.text.split('data-item="', 1)[1].split('"', 1)[0]
    after = client.post("/rate", data={"item": item, "rating": "4",
                                       "csrf": _page_csrf(page.text)}, headers=SAME)
    assert after.status_code == 200 and "2 / 16" in after.text
    bad = client.post("/rate", data={"item": item, "rating": "four",
                                     "csrf": _page_csrf(page.text)}, headers=SAME)
    assert bad.status_code == 422 and "rating" in bad.text
    left = client.post("/leave", data={"csrf": _page_csrf(page.text)}, headers=SAME)
    assert left.status_code == 200 and "Invite code" in left.text
    assert client.get("/rate").status_code == 401
