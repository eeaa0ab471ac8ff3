"""Load test of ``llm-grop serve`` on loopback with the embedded model's recorded answers
replayed (issue 26's figures).

Starts the server in its own process (2 workers by default) and measures:

* ``POST /v1/arrangements`` and ``POST /v1/plans`` latency (p50, p95) and throughput at 1
  and at 20 concurrent clients (threads, each with its own HTTP client), requests drawn
  from the paper's tasks 1-8 with seeds 0-19;
* 5x overload: 100 clients at once (300 requests); every answer must be 200 or 429 (with
  Retry-After);
* the server's resident memory (the server and its workers);
* kill and restart: a burst of runs, ``kill -9`` of the server while they run, a restart,
  and then every accepted job must end in a terminal state exactly once.

    python benchmarks/serve_load.py [--workers 2] [--requests 60] [--burst 40] [--clients 20]
        [--overload 100] [--quick]
"""

from __future__ import annotations

import argparse
import os
import signal
import sqlite3
import subprocess
import threading
import time
from collections import Counter
from pathlib import Path

import httpx
from common import median_p95, parse_args, scratch, start_server

from llm_grop.world.tasks import load_tasks

TERMINAL = ("done", "failed", "cancelled")


def bodies(kind: str, n: int) -> list[dict]:
    """``n`` request bodies over tasks 1-8 and seeds 0-19 (recorded answers exist)."""
    tasks = load_tasks()
    out = []
    for k in range(n):
        task, seed = k % 8 + 1, (k // 8) % 20
        out.append({"request": tasks[task].request, "seed": seed} if kind == "arrange"
                   else {"task": task, "seed": seed})
    return out


def load(url: str, path: str, work: list[dict], clients: int) -> tuple[list[float], Counter,
                                                                       float]:
    """Send ``work`` from ``clients`` threads: latencies (s) of 200s, status counts, wall s."""
    lock = threading.Lock()
    queue = list(enumerate(work))
    latencies: list[float] = []
    codes: Counter = Counter()

    def client() -> None:
        with httpx.Client(base_url=url, timeout=300) as c:
            while True:
                with lock:
                    if not queue:
                        return
                    _, body = queue.pop()
                t0 = time.perf_counter()
                r = c.post(path, json=body)
                dt = time.perf_counter() - t0
                with lock:
                    codes[r.status_code] += 1
                    if r.status_code == 200:
                        latencies.append(dt)
                    if r.status_code == 429:
                        assert r.headers.get("retry-after", "").isdigit()

    t0 = time.perf_counter()
    threads = [threading.Thread(target=client) for _ in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return latencies, codes, time.perf_counter() - t0


def rss_mb(pid: int) -> float:
    """Resident memory of ``pid`` and its children, MB."""
    pids = [pid] + [int(p) for p in subprocess.run(["pgrep", "-P", str(pid)],
                                                   capture_output=True, text=True).stdout.split()]
    total = 0
    for p in pids:
        try:
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1])
        except OSError:
            pass
    return total / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--requests", type=int, default=60)
    parser.add_argument("--burst", type=int, default=40)
    parser.add_argument("--clients", type=int, default=20, help="clients at once, besides 1")
    parser.add_argument("--overload", type=int, default=100,
                        help="clients at once in the overload, 3 requests each")
    args = parse_args(parser, {"workers": 1, "requests": 1, "burst": 2, "clients": 2,
                               "overload": 2})
    tmp = scratch("serve-load")
    # Every client here is 127.0.0.1: the burst of runs is one client's.
    proc, url = start_server(tmp / "jobs.sqlite", "--workers", str(args.workers),
                             "--runs-per-client", "64")
    print(f"llm-grop serve, {args.workers} workers, replayed SmolLM2-135M answers, loopback, "
          f"{os.cpu_count()} cores")
    try:
        for kind, path in (("arrange", "/v1/arrangements"), ("plan", "/v1/plans")):
            load(url, path, bodies(kind, min(8, args.requests)), 2)  # warm the workers up
            for clients in (1, args.clients):
                lat, codes, wall = load(url, path, bodies(kind, args.requests), clients)
                p50, p95 = median_p95(lat)
                print(f"{path:18s} {clients:2d} clients: p50 {p50 * 1000:6.0f} ms  p95 "
                      f"{p95 * 1000:6.0f} ms  {len(lat) / wall:5.2f} req/s  statuses "
                      f"{dict(codes)}")
        print(f"resident memory after the load: {rss_mb(proc.pid):.0f} MB (server and "
              f"workers)")
        lat, codes, wall = load(url, "/v1/arrangements", bodies("arrange", 3 * args.overload),
                                args.overload)
        others = {k: v for k, v in codes.items() if k not in (200, 429)}
        print(f"{args.overload / args.clients:g}x overload ({args.overload} clients, "
              f"{3 * args.overload} requests): {codes[200]} answered, "
              f"{codes[429]} refused with 429 + Retry-After, {sum(others.values())} other "
              f"statuses {others or ''}")
        print(f"resident memory after the overload: {rss_mb(proc.pid):.0f} MB")
        accepted = []
        with httpx.Client(base_url=url, timeout=30) as c:
            for k in range(args.burst):
                r = c.post("/v1/runs", json={"task": k % 8 + 1, "seed": k % 20,
                                             "method": ["llm-grop", "grop"][k % 2]})
                if r.status_code == 202:
                    accepted.append(r.json()["id"])
            time.sleep(1.0)
        at_kill = {i: (st, fin) for i, st, fin in sqlite3.connect(tmp / "jobs.sqlite").execute(
            "SELECT id, state, finished FROM jobs WHERE kind = 'run'")}
        states = Counter(st for st, _ in at_kill.values())
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        print(f"kill -9 with {len(accepted)} runs accepted: {dict(states)} at the kill")
        proc, url = start_server(tmp / "jobs.sqlite", "--workers", str(args.workers),
                             "--runs-per-client", "64")
        deadline = time.monotonic() + 600
        with httpx.Client(base_url=url, timeout=30) as c:
            while time.monotonic() < deadline:
                final = [c.get(f"/v1/runs/{i}").json()["state"] for i in accepted]
                if all(s in TERMINAL for s in final):
                    break
                time.sleep(0.5)
        after = {i: (st, fin, n) for i, st, fin, n in sqlite3.connect(tmp / "jobs.sqlite").execute(
            "SELECT id, state, finished, attempts FROM jobs WHERE kind = 'run'")}
        # A job done before the kill and finished again after it would be done twice.
        twice = sum(at_kill[i][0] == "done" and after[i][1] != at_kill[i][1] for i in accepted)
        rerun = sum(at_kill[i][0] == "running" for i in accepted)
        print(f"after the restart: {len(accepted)} accepted, "
              f"{sum(s in TERMINAL for s in final)} terminal {dict(Counter(final))}, "
              f"{len(after)} stored, {rerun} re-run after the kill, {twice} done twice")
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)


if __name__ == "__main__":
    main()
