"""Issue 37's figures: whether ``llm-grop serve`` holds for weeks.

* Open descriptors over idle cycles: bursts of 40 ``GET /v1/info`` at once, each followed
  by quiet long enough for the server's thread pool to retire its threads. anyio retires a
  thread idle 10 s, at the next request; the main run configures that to ``--idle`` s
  (the pool's real retirement, sooner) for ``--cycles`` cycles, then does ``--real-cycles``
  cycles with anyio's own 10 s and 10.5 s of quiet. Descriptors are counted in
  ``/proc/PID/fd`` (those on the database apart), after each quiet.
* The same bursts under ``ulimit -n 256`` (``--limited-cycles``): answers other than 200.
* A 1.5 MB disk (a tmpfs in a user namespace): 2 runs accepted, then the disk filled;
  ``--submissions`` more runs submitted (their statuses), the disk left full ``--full-s``
  seconds, then freed; how many of the accepted runs finished, and the tracebacks in the
  server's log.

    python benchmarks/service_uptime.py [--cycles 50] [--idle 0.2] [--real-cycles 3]
        [--limited-cycles 10] [--submissions 60] [--full-s 10] [--quick]

Against an older checkout: ``PYTHONPATH=/path/to/it/src python benchmarks/service_uptime.py``
(the server runs that checkout's code).
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import httpx
from common import parse_args, scratch

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from service_support import free_port  # noqa: E402
from small_disk import SmallDisk, unavailable  # noqa: E402
from uptime_support import (  # noqa: E402
    alive,
    burst,
    descriptors,
    serve_command,
    server_env,
    wait_answering,
)

#: Requests at once in a burst.
BURST = 40


def cycles(tmp: Path, count: int, quiet_s: float, idle_s: float | None,
           files: int = 4096) -> tuple[list[tuple[int, int]], Counter[int | str], int]:
    """``count`` bursts each followed by ``quiet_s`` of quiet, on a fresh server whose pool
    retires threads idle ``idle_s`` (``None``: anyio's 10 s) and that may open ``files``
    descriptors: the descriptors (all, on the database) before the first burst and after
    each quiet, the statuses, and the threads at the end."""
    db, port = tmp / f"jobs-{time.monotonic_ns()}.sqlite", free_port()

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_NOFILE, (files, files))

    proc = subprocess.Popen(serve_command(db, port, "--workers", "1", thread_idle_s=idle_s),
                            env=server_env(), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, preexec_fn=limit)
    url = f"http://127.0.0.1:{port}"
    try:
        wait_answering(url, lambda: proc.poll() is None)
        counts = [descriptors(proc.pid, db.name)]
        statuses: Counter[int | str] = Counter()
        for _ in range(count):
            statuses += burst(url, BURST)
            time.sleep(quiet_s)
            counts.append(descriptors(proc.pid, db.name))
        threads = len(list(Path(f"/proc/{proc.pid}/task").iterdir()))
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    return counts, statuses, threads


def report_cycles(label: str, counts: list[tuple[int, int]], statuses: Counter[int | str],
                  threads: int) -> None:
    every = ", ".join(str(total) for total, _ in counts[1:])
    print(f"  {label}: descriptors {counts[0][0]} before the first burst, {counts[-1][0]} "
          f"after the last ({counts[-1][1]} on the database), {threads} threads; answers "
          f"{dict(statuses)}")
    print(f"    after each quiet: {every}")


def small_disk(tmp: Path, submissions: int, full_s: float) -> None:
    why = unavailable()
    if why is not None:
        print(f"1.5 MB disk: skipped, {why}")
        return
    log = tmp / "disk-serve.log"
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    with SmallDisk(tmp / "disk", 1536) as disk:
        pid = disk.start(serve_command(disk.where / "jobs.sqlite", port, "--workers", "1"),
                         log, server_env())
        wait_answering(url, lambda: alive(pid))
        with httpx.Client(base_url=url, timeout=60) as c:
            accepted = [c.post("/v1/runs", json={"task": 8, "seed": seed}).json()["id"]
                        for seed in range(2)]
            disk.fill()
            statuses: Counter[int | str] = Counter()
            retry_after = 0
            for k in range(submissions):
                try:
                    r = c.post("/v1/runs", json={"task": 8, "seed": 2 + k % 18})
                    statuses[r.status_code] += 1
                    retry_after += "retry-after" in r.headers
                except httpx.HTTPError as exc:
                    statuses[type(exc).__name__] += 1
            time.sleep(full_s)
            while_full = _tracebacks(log)
            states = Counter(_state(c, i) for i in accepted)
            disk.free()
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline:
                final = [_state(c, i) for i in accepted]
                if all(s in ("done", "failed", "cancelled") for s in final):
                    break
                time.sleep(0.5)
    print(f"1.5 MB disk, filled after 2 runs were accepted: {submissions} more submissions "
          f"answered {dict(sorted(statuses.items(), key=str))} ({retry_after} with "
          f"Retry-After); accepted runs while full {dict(states)}; {while_full} tracebacks "
          f"in the server's log in {full_s:g} s full")
    print(f"  after space returned: {final.count('done')} of {len(accepted)} accepted runs "
          f"done (states {dict(Counter(final))}); {_tracebacks(log)} tracebacks in the log "
          f"in all")


def _state(client: httpx.Client, job_id: str) -> str:
    try:
        return str(client.get(f"/v1/runs/{job_id}").json()["state"])
    except (httpx.HTTPError, ValueError, KeyError):
        return "no answer"


def _tracebacks(log: Path) -> int:
    return log.read_text(errors="replace").count("Traceback (most recent call last)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=50, help="idle cycles, retirement "
                        "configured to --idle")
    parser.add_argument("--idle", type=float, default=0.2,
                        help="seconds idle after which the pool retires a thread (anyio: 10)")
    parser.add_argument("--real-cycles", type=int, default=3,
                        help="idle cycles with anyio's own 10 s and 10.5 s of quiet")
    parser.add_argument("--limited-cycles", type=int, default=10,
                        help="idle cycles under ulimit -n 256")
    parser.add_argument("--submissions", type=int, default=60,
                        help="runs submitted while the disk is full")
    parser.add_argument("--full-s", type=float, default=10.0,
                        help="seconds the disk stays full")
    args = parse_args(parser, {"cycles": 3, "real_cycles": 0, "limited_cycles": 0,
                               "submissions": 5, "full_s": 1.0})
    tmp = scratch("service-uptime")
    print(f"llm-grop serve, 1 worker, bursts of {BURST} GET /v1/info, loopback")
    report_cycles(f"{args.cycles} idle cycles, threads retired after {args.idle:g} s "
                  f"(quiet {2 * args.idle:g} s)",
                  *cycles(tmp, args.cycles, 2 * args.idle, args.idle))
    if args.real_cycles:
        report_cycles(f"{args.real_cycles} idle cycles of 10.5 s, anyio's own retirement",
                      *cycles(tmp, args.real_cycles, 10.5, None))
    if args.limited_cycles:
        report_cycles(f"{args.limited_cycles} idle cycles under ulimit -n 256",
                      *cycles(tmp, args.limited_cycles, 2 * args.idle, args.idle, 256))
    small_disk(tmp, args.submissions, args.full_s)


if __name__ == "__main__":
    main()
