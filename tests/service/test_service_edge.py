"""The service's HTTP edge against a real server: bodies it cannot read are refused in
their own words (never a 500, never "bad_host"), only JSON media types are JSON, stalled
clients are closed while others are answered, a loopback alias is the server's own name,
and the playground counts diners as the API does."""

from __future__ import annotations

import asyncio
import os
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from ratings_support import load_benchmark
from service_support import RECORDING, Server, start_server

DEEP = 300  # pydantic's serializer breaks a little below this


def nested(depth: int, kind: str = "object") -> str:
    """A JSON value whose objects (or arrays) nest ``depth`` deep."""
    if kind == "array":
        return "[" * depth + "]" * depth
    return '{"a": ' * (depth - 1) + "{}" + "}" * (depth - 1)


UNREADABLE = [
    # (body, words): each used to be a 400 "bad_host" or a 500.
    (f'{{"task": 8, "scene": {nested(DEEP)}}}'.encode(), "nested more than 64 deep"),
    (f'{{"arrangement": {nested(DEEP)}}}'.encode(), "nested more than 64 deep"),
    (f'{{"task": 8, "scene": {nested(5000, "array")}}}'.encode(), "nested more than 64 deep"),
    (f'{{"task": 8, "scene": {nested(64)}}}'.encode(), "nested more than 64 deep"),
    (b'{"task": 8, "request": "\xff plate"}', "body: not UTF-8 text"),
    (b'{"task": ' + b"9" * 5000 + b"}", "a number of more than 4300 digits"),
    (b"{not json", "body: not JSON (Expecting property name"),
]


@pytest.mark.parametrize(("body", "words"), UNREADABLE,
                         ids=["deep-scene", "deep-arrangement", "5000-deep", "65-deep",
                              "not-utf8", "huge-int", "malformed"])
def test_a_body_that_cannot_be_read_is_422_bad_json(server: Server, body: bytes,
                                                    words: str) -> None:
    with server.client() as c:
        r = c.post("/v1/plans", content=body, headers={"content-type": "application/json"})
        assert r.status_code == 422, r.text
        assert r.json()["code"] == "bad_json" and words in r.json()["error"]
        assert "\n" not in r.json()["error"]
        assert c.get("/v1/info").json()["limits"]["body_depth"] == 64


def test_a_body_64_deep_is_read(server: Server) -> None:
    """The limit counts the body itself as level 1: a scene 63 deep inside it is read
    (and refused by what it says, not how deep it is)."""
    with server.client() as c:
        r = c.post("/v1/plans", content=f'{{"task": 8, "scene": {nested(63)}}}',
                   headers={"content-type": "application/json"})
    assert r.status_code == 422 and r.json()["code"] == "bad_input", r.text
    assert r.json()["error"].startswith("scene: ")


@pytest.mark.parametrize(("media", "status"), [
    ("application/jsonx", 415), ("text/json", 415), ("application/x-www-form-urlencoded", 415),
    ("application/json; charset=utf-8", 422), ("application/problem+json", 422),
    ("APPLICATION/JSON", 422),
])
def test_only_json_media_types_are_json(server: Server, media: str, status: int) -> None:
    with server.client() as c:
        r = c.post("/v1/arrangements", content=b'{"request": "a plate", "seed": -1}',
                   headers={"content-type": media})
    assert r.status_code == status, r.text
    if status == 415:
        assert r.json() == {"error": f"content-type: send the body as application/json, "
                                     f"got {media!r}", "code": "not_json"}
    else:
        assert r.json()["error"] == "seed: must be at least 0, got -1"


def test_stalled_clients_are_closed_while_others_are_answered(tmp_path: Path) -> None:
    stalled = load_benchmark("stalled_connections")
    s = start_server(tmp_path / "jobs.sqlite", "--header-timeout", "1", "--body-timeout", "2")
    try:
        port = int(s.url.rsplit(":", 1)[1])

        async def everything():
            idle = asyncio.create_task(stalled.stall(port, b"", 30))
            results, normal = await stalled.attack(s.url, 24, 30)
            return results, normal, await idle

        results, normal, idle = asyncio.run(everything())
        # Headers longer than the server reads, never ended: 431 at once.
        with socket.create_connection(("127.0.0.1", port), timeout=30) as sock:
            sock.sendall(b"GET /v1/info HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Long: "
                         + b"a" * 70_000)
            answer = sock.recv(4096)
        # A client slow but within the deadlines is answered.
        with socket.create_connection(("127.0.0.1", port), timeout=30) as sock:
            sock.sendall(b"GET /v1/info HTTP/1.1\r\n")
            time.sleep(0.5)
            sock.sendall(b"Host: 127.0.0.1\r\n\r\n")
            slow = sock.recv(4096)
    finally:
        s.stop()
    for kind, timeout_s in (("partial headers", 1), ("partial body", 2)):
        times = [c.closed_after_s for c in results[kind]]
        assert None not in times, f"{kind}: {times.count(None)} connections still open"
        assert max(times) < 10 * timeout_s, (kind, max(times))
        assert {c.status for c in results[kind]} == {"HTTP/1.1 408 Request Timeout"}
    assert idle.closed_after_s is not None and idle.status == "(nothing)"
    assert normal and all(status == 200 for _, status in normal)
    assert answer.startswith(b"HTTP/1.1 431 ") and b'"code": "too_large"' in answer
    assert slow.startswith(b"HTTP/1.1 200 ")


def test_a_408_names_what_was_late(tmp_path: Path) -> None:
    s = start_server(tmp_path / "jobs.sqlite", "--header-timeout", "1")
    try:
        with socket.create_connection(("127.0.0.1", int(s.url.rsplit(":", 1)[1])),
                                      timeout=30) as sock:
            sock.sendall(b"GET /v1/info HTTP/1.1\r\nHost: 1")
            answer = b""
            while chunk := sock.recv(4096):
                answer += chunk
    finally:
        s.stop()
    head, _, body = answer.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 408 ") and b"connection: close" in head
    assert body == (b'{"error": "headers: not received within 1 s; the connection is '
                    b'closed", "code": "timeout"}')


def test_a_loopback_alias_is_the_servers_own_name(tmp_path: Path) -> None:
    db = tmp_path / "jobs.sqlite"
    log = tmp_path / "serve.log"
    with log.open("wb") as out:
        proc = subprocess.Popen(
            [sys.executable, "-m", "llm_grop", "serve", "--llm", "replay", "--replay",
             str(RECORDING), "--db", str(db), "--host", "127.0.0.2", "--port", "0"],
            env=os.environ | {"MUJOCO_GL": "osmesa"}, stdout=out, stderr=out)
    try:
        url = None
        for _ in range(300):
            found = re.search(r"http://127\.0\.0\.2:(\d+)/", log.read_text())
            if found and found.group(1) != "0":
                url = found.group(0).rstrip("/")
                try:
                    if httpx.get(f"{url}/v1/info", timeout=1).status_code == 200:
                        break
                except httpx.HTTPError:
                    pass
            assert proc.poll() is None, log.read_text()
            time.sleep(0.1)
        assert url is not None, log.read_text()
        r = httpx.get(f"{url}/v1/info")  # Host: 127.0.0.2:PORT
        assert r.status_code == 200, r.text
        r = httpx.post(f"{url}/v1/arrangements", json={"request": "a dinner plate"},
                       timeout=60)
        assert r.status_code == 200, r.text
        r = httpx.get(f"{url}/v1/info", headers={"host": "evil.example"})
        assert r.status_code == 400 and r.json()["code"] == "bad_host"
    finally:
        proc.terminate()
        proc.wait(timeout=15)


@pytest.mark.parametrize(("diners", "words"), [
    ("0", "diners: must be at least 1, got 0"), ("-1", "diners: must be at least 1, got -1"),
    ("13", "diners: must be at most 12, got 13"), ("2.5", "diners: expected a whole number")])
def test_the_playground_counts_diners_as_the_api_does(server: Server, diners: str,
                                                      words: str) -> None:
    form = {"request": "a dinner plate", "action": "arrange", "diners": diners}
    with server.client() as c:
        page = c.post("/play", data=form, headers={"origin": server.url})
        api = c.post("/v1/arrangements", json={"request": "a dinner plate",
                                                "diners": float(diners) if "." in diners
                                                else int(diners)})
    assert page.status_code == 422 and words in page.text
    assert api.status_code == 422 and api.json()["error"].startswith(words)
