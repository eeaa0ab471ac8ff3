"""The rating site under abuse, in its own process: a 50 MiB chunked body is cut off at
the limit without the server's memory growing with it."""

from __future__ import annotations

from pathlib import Path

import httpx

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
