"""Slow clients against ``llm-grop serve`` on loopback (issue 37's figures): how long a
connection that stalls half-way through a request is held, and whether everyone else is
still answered meanwhile.

Starts the server in its own process (1 worker, the embedded model's recorded answers
replayed), then opens at once ``--connections`` connections that send a request's line
and part of its headers and stop, and as many that send whole headers and part of a body
and stop. While they wait, a normal client asks ``GET /v1/info`` every half second.
Printed: how many stalled connections the server closed within ``--watch`` seconds, the
time from a connection's last byte to its closing (median and max), what the server
said before closing, and the normal requests' latency (median and max).

The server's deadlines are its ``--header-timeout`` and ``--body-timeout`` (defaults 10 s
and 30 s); a version of llm-grop without them is run as it is, and the figures then show
how long it held on.

    python benchmarks/stalled_connections.py [--connections 300] [--watch 60] [--quick]
    PYTHONPATH=../other-checkout/src python benchmarks/stalled_connections.py  # before
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import httpx
from common import parse_args, scratch, start_server

#: What each kind of stalled client sends before it stops: a request line and one header
#: (no blank line), or whole headers announcing 100 bytes of body and 10 of them.
PARTIAL = {
    "partial headers": b"POST /v1/arrangements HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                       b"Content-Type: application/json\r\n",
    "partial body": b"POST /v1/arrangements HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                    b"Content-Type: application/json\r\nContent-Length: 100\r\n\r\n"
                    b'{"request"',
}


@dataclass(frozen=True)
class Stalled:
    """One stalled connection: seconds from its last byte to the server closing it
    (``None``: still open when the watch ended), and the status line it got first."""

    closed_after_s: float | None
    status: str


def has_deadlines() -> bool:
    """Whether the llm-grop on the path has ``serve --header-timeout``."""
    done = subprocess.run([sys.executable, "-m", "llm_grop", "serve", "--help"],
                          capture_output=True, text=True)
    return "--header-timeout" in done.stdout


async def stall(port: int, sent: bytes, watch_s: float) -> Stalled:
    """Connect, send ``sent`` and nothing more, and wait up to ``watch_s`` seconds for the
    server to close the connection."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(sent)
    await writer.drain()
    since = time.monotonic()
    got = b""
    try:
        async with asyncio.timeout(watch_s):
            while chunk := await reader.read(4096):
                got += chunk
        closed: float | None = time.monotonic() - since
    except TimeoutError:
        closed = None
    except ConnectionError:
        closed = time.monotonic() - since
    writer.close()
    status = got.split(b"\r\n", 1)[0].decode("latin-1") if got else "(nothing)"
    return Stalled(closed, status)


async def meanwhile(url: str, done: asyncio.Event) -> list[tuple[float, int]]:
    """``GET /v1/info`` every half second until ``done``: (latency s, status) each."""
    out = []
    async with httpx.AsyncClient(base_url=url, timeout=30) as client:
        while not done.is_set():
            start_t = time.monotonic()
            try:
                status = (await client.get("/v1/info")).status_code
            except httpx.HTTPError:
                status = 0
            out.append((time.monotonic() - start_t, status))
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(done.wait(), 0.5)
    return out


async def attack(url: str, connections: int, watch_s: float
                 ) -> tuple[dict[str, list[Stalled]], list[tuple[float, int]]]:
    """``connections`` of each kind in :data:`PARTIAL` at once, and a normal client
    meanwhile: what became of each stalled connection, and the normal requests."""
    port = int(url.rsplit(":", 1)[1])
    done = asyncio.Event()
    normal = asyncio.create_task(meanwhile(url, done))
    kinds = {kind: [asyncio.create_task(stall(port, sent, watch_s))
                    for _ in range(connections)] for kind, sent in PARTIAL.items()}
    results = {kind: list(await asyncio.gather(*tasks)) for kind, tasks in kinds.items()}
    done.set()
    return results, await normal


def report(kind: str, stalled: list[Stalled], watch_s: float) -> str:
    times = [s.closed_after_s for s in stalled if s.closed_after_s is not None]
    statuses = sorted({s.status for s in stalled})
    if not times:
        return (f"{kind}: 0 of {len(stalled)} closed within {watch_s:g} s (all still "
                f"open); answered: {', '.join(statuses)}")
    return (f"{kind}: {len(times)} of {len(stalled)} closed within {watch_s:g} s; time to "
            f"close median {statistics.median(times):.2f} s, max {max(times):.2f} s; "
            f"answered: {', '.join(statuses)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--connections", type=int, default=300,
                        help="stalled connections of each kind")
    parser.add_argument("--watch", type=float, default=60.0,
                        help="seconds to wait for the server to close them")
    parser.add_argument("--header-timeout", type=float, default=None,
                        help="the server's --header-timeout (default: its own)")
    parser.add_argument("--body-timeout", type=float, default=None,
                        help="the server's --body-timeout (default: its own)")
    parser.add_argument("--db", type=Path, default=None,
                        help="the server's database (default: a scratch directory)")
    args = parse_args(parser, quick={"connections": 10, "watch": 4.0, "header_timeout": 1.0,
                                     "body_timeout": 1.0})
    db = args.db or scratch("stalled") / "jobs.sqlite"
    deadlines = has_deadlines()
    flags: list[str] = []
    if deadlines:
        for flag, value in (("--header-timeout", args.header_timeout),
                            ("--body-timeout", args.body_timeout)):
            if value is not None:
                flags += [flag, f"{value:g}"]
    proc, url = start_server(db, "--workers", "1", *flags)
    try:
        results, normal = asyncio.run(attack(url, args.connections, args.watch))
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
    server = " ".join(flags) or ("its default deadlines" if deadlines else
                                 "no read deadlines (a version before them)")
    print(f"llm-grop serve with {server}; {args.connections} stalled connections of each "
          "kind at once, on loopback")
    for kind, stalled in results.items():
        print(report(kind, stalled, args.watch))
    latencies = [t for t, status in normal if status == 200]
    failed = len(normal) - len(latencies)
    if latencies:
        print(f"a normal request meanwhile (GET /v1/info, {len(normal)} tries): median "
              f"{statistics.median(latencies) * 1000:.0f} ms, max {max(latencies) * 1000:.0f} "
              f"ms; {failed} not answered 200")
    else:
        print(f"a normal request meanwhile: none of {len(normal)} answered 200")


if __name__ == "__main__":
    main()
