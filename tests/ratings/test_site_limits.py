"""The rating site under abuse, in its own process: a 50 MiB chunked body is cut off at
the limit without the server's memory growing with it; a client cannot escape the join
limit by naming another address in X-Forwarded-For; a client that stalls is closed."""

from __future__ import annotations

import socket
from pathlib import Path
from urllib.parse import urlsplit

import httpx
import pytest

from ratings_support import load_benchmark

#: The body sent, bytes, and how much the server's peak memory may grow meanwhile.
BODY_BYTES = 50 * 1024 * 1024
GROWTH_LIMIT_BYTES = 50 * 1024 * 1024


def peak_rss(pid: int) -> int:
    """The process's peak resident memory so far (``VmHWM``), bytes."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    raise AssertionError("no VmHWM")


def test_a_chunked_50_mib_body_is_cut_off(study) -> None:
    load = load_benchmark("ratings_load")
    with load.server_process(study[0]) as (url, proc):
        before = peak_rss(proc.pid)

        def chunks():
            block = b"A" * (1024 * 1024)
            for _ in range(BODY_BYTES // len(block)):
                yield block

        try:
            r = httpx.post(f"{url}api/session", content=chunks(), timeout=60,
                           headers={"content-type": "application/json"})
            assert r.status_code == 413 and "larger than" in r.json()["error"]
        except httpx.HTTPError:
            pass  # the server may close the connection once it has answered
        grown = peak_rss(proc.pid) - before
    print(f"peak memory grew {grown / 2**20:.1f} MiB under a {BODY_BYTES / 2**20:.0f} MiB "
          "chunked body")
    assert grown < GROWTH_LIMIT_BYTES


@pytest.mark.parametrize(("flags", "limited"), [((), True),
                                                (("--forwarded-allow-ips", "127.0.0.1"), False)])
def test_the_join_limit_counts_the_clients_own_address(study, flags, limited) -> None:
    """By default no proxy is trusted: a client on this machine that names a new address
    in X-Forwarded-For on every try still meets the limit (10 failures a minute). A
    proxy named with --forwarded-allow-ips is trusted, so each address it forwards counts
    on its own."""
    load = load_benchmark("ratings_load")
    with load.server_process(study[0], load.ADMIN_TOKEN, *flags) as (url, _):
        codes = [httpx.post(f"{url}api/session", json={"code": "AAAA-BBBB-CCCC"},
                            headers={"x-forwarded-for": f"10.0.0.{k}"}).status_code
                 for k in range(15)]
    if limited:
        assert codes[:10] == [401] * 10 and codes[10:] == [429] * 5
    else:
        assert codes == [401] * 15


def test_a_stalled_client_is_closed(study) -> None:
    load = load_benchmark("ratings_load")
    with load.server_process(study[0], load.ADMIN_TOKEN, "--header-timeout", "1",
                             "--body-timeout", "1") as (url, _):
        where = urlsplit(url)
        answers = []
        for partial in (b"GET / HTTP/1.1\r\nHost: 127", b"POST /api/session HTTP/1.1\r\n"
                        b"Host: 127.0.0.1\r\nContent-Length: 50\r\n\r\n{"):
            with socket.create_connection((where.hostname, where.port), timeout=30) as sock:
                sock.sendall(partial)
                answer = b""
                while chunk := sock.recv(4096):
                    answer += chunk
                answers.append(answer)
        assert httpx.get(url).status_code == 200
    assert [a.split(b"\r\n", 1)[0] for a in answers] == [b"HTTP/1.1 408 Request Timeout"] * 2
