"""Load test of the rating website: concurrent raters on loopback (issue 14's figures).

Makes a study of synthetic pictures, invites the raters, starts ``llm-grop ratings serve``
in its own process, and lets each rater (a thread with its own HTTP client) fetch its next
picture and rate it, as the page does, until every rater has rated its share. Prints the
ratings per second, the latency of a rating (median, p95, max) and of fetching the next
picture, and how many ratings the database holds: each must be stored exactly once.

    python benchmarks/ratings_load.py [--raters 20] [--ratings 2000] [--timeout 120]
        [--quick]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import os
import re
import sqlite3
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import httpx
from common import parse_args
from PIL import Image

from llm_grop.ratings.study import StudyItem, create_study, invite

ADMIN_TOKEN = "load-test-admin-token-0123456789"
_LISTENING = re.compile(r"at (http://\S+/)")


def synthetic_study(db: Path, pictures: int) -> None:
    """A study of ``pictures`` small pictures, tasks 1-8 by the paper's four methods."""
    methods = ("tpra", "latp", "grop", "llm-grop")
    items = []
    for k in range(pictures):
        buf = io.BytesIO()
        Image.new("RGB", (64, 48), (k % 256, 90, 160)).save(buf, format="PNG")
        items.append(StudyItem(task=k // 4 % 8 + 1, trial=k // 32, seed=k // 32,
                               method=methods[k % 4], objects=("dinner plate", "dinner fork"),
                               automatic_rating=1 + k % 5, execution_time_s=100.0 + k,
                               success=True, picture=buf.getvalue(), picture_source=f"{k}.png"))
    create_study(db, items, name="load test", source="synthetic", seed=0)


@contextlib.contextmanager
def serving(db: Path, token: str = ADMIN_TOKEN, *extra: str) -> Iterator[str]:
    """``llm-grop ratings serve`` on a free loopback port in its own process; its URL."""
    with server_process(db, token, *extra) as (url, _):
        yield url


@contextlib.contextmanager
def server_process(db: Path, token: str = ADMIN_TOKEN, *extra: str
                   ) -> Iterator[tuple[str, subprocess.Popen[str]]]:
    """:func:`serving`, with the server's process too."""
    exe = Path(sys.executable).with_name("llm-grop")
    proc = subprocess.Popen([str(exe), "ratings", "serve", "--db", str(db), "--port", "0",
                             "--admin-token", token, *extra],
                            stderr=subprocess.PIPE, text=True,
                            env=os.environ | {"LLM_GROP_ADMIN_TOKEN": ""})
    try:
        assert proc.stderr is not None
        line = proc.stderr.readline()
        match = _LISTENING.search(line)
        if match is None:
            raise RuntimeError(f"the server did not start: {line}{proc.stderr.read()}")
        url = match.group(1)
        for _ in range(200):  # uvicorn accepts once its lifespan has started
            with contextlib.suppress(httpx.TransportError):
                httpx.get(url, timeout=1.0)
                break
            time.sleep(0.05)
        yield url, proc
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@dataclass
class Load:
    """What the raters saw: per-request latencies (seconds) and refusals."""

    rate_s: list[float] = field(default_factory=list)
    next_s: list[float] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    wall_s: float = 0.0
    lock: threading.Lock = field(default_factory=threading.Lock)


def _rater(url: str, code: str, count: int, load: Load, deadline: float) -> None:
    try:
        _rate_all(url, code, count, load, deadline)
    except httpx.HTTPError as exc:
        with load.lock:
            load.errors.append(f"{type(exc).__name__}: {exc}")


def _rate_all(url: str, code: str, count: int, load: Load, deadline: float) -> None:
    rate_s: list[float] = []
    next_s: list[float] = []
    with httpx.Client(base_url=url, timeout=30.0) as client:
        joined = client.post("/api/session", json={"code": code})
        if joined.status_code != 200:
            with load.lock:
                load.errors.append(f"join: {joined.status_code} {joined.text}")
            return
        csrf = joined.json()["csrf"]
        for _ in range(count):
            if time.monotonic() > deadline:
                with load.lock:
                    load.errors.append("time limit reached")
                break
            t0 = time.perf_counter()
            nxt = client.get("/api/next").json()
            t1 = time.perf_counter()
            if nxt["item"] is None:
                break
            sent = client.post("/api/ratings", json={"item": nxt["item"], "rating": 3},
                               headers={"X-CSRF-Token": csrf})
            t2 = time.perf_counter()
            next_s.append(t1 - t0)
            rate_s.append(t2 - t1)
            if sent.status_code != 201:
                with load.lock:
                    load.errors.append(f"rate: {sent.status_code} {sent.text}")
    with load.lock:
        load.rate_s += rate_s
        load.next_s += next_s


def drive(url: str, codes: list[str], per_rater: int, timeout_s: float = 120.0) -> Load:
    """Every rater in ``codes`` rates ``per_rater`` pictures at once; what they saw."""
    load = Load()
    deadline = time.monotonic() + timeout_s
    threads = [threading.Thread(target=_rater, args=(url, c, per_rater, load, deadline))
               for c in codes]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    load.wall_s = time.perf_counter() - t0
    return load


def stored(db: Path) -> tuple[int, int]:
    """``(ratings, distinct (rater, picture) pairs)`` in the database."""
    with contextlib.closing(sqlite3.connect(db)) as conn:
        return conn.execute("SELECT count(*), count(DISTINCT rater_id || '/' || item_id)"
                            " FROM ratings").fetchone()


def _percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[max(math.ceil(q * len(ordered)) - 1, 0)] if ordered else math.nan


def main(argv: list[str] | None = None) -> int:
    """Run the load test and print its figures; exit status 1 if a rating was lost."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--raters", type=int, default=20)
    parser.add_argument("--ratings", type=int, default=2000, help="ratings in all")
    parser.add_argument("--timeout", type=float, default=120.0, help="time limit, seconds")
    args = parse_args(parser, {"raters": 2, "ratings": 6}, argv)
    per_rater = math.ceil(args.ratings / args.raters)
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "study.db"
        synthetic_study(db, per_rater)
        codes = invite(db, args.raters)
        with serving(db) as url:
            load = drive(url, codes, per_rater, args.timeout)
        count, distinct = stored(db)
    expected = per_rater * args.raters
    ms = 1000.0
    print(f"{args.raters} concurrent raters on loopback, {per_rater} pictures each "
          f"({expected} ratings)")
    print(f"wall time: {load.wall_s:.2f} s; ratings per second: {count / load.wall_s:.0f}")
    if not load.rate_s:
        print(f"no rating was made: {load.errors[:3]}")
        return 1
    print(f"POST /api/ratings latency: median {_percentile(load.rate_s, 0.5) * ms:.1f} ms, "
          f"p95 {_percentile(load.rate_s, 0.95) * ms:.1f} ms, max {max(load.rate_s) * ms:.1f} ms")
    print(f"GET /api/next latency: median {_percentile(load.next_s, 0.5) * ms:.1f} ms, "
          f"p95 {_percentile(load.next_s, 0.95) * ms:.1f} ms")
    print(f"stored: {count} ratings, {distinct} distinct (rater, picture) pairs; "
          f"refusals: {len(load.errors)}")
    for error in sorted(set(load.errors))[:5]:
        print(f"  {error}")
    return 0 if count == distinct == expected and not load.errors else 1


if __name__ == "__main__":
    sys.exit(main())
