"""Issue 37's figure: the longest LLM call against each hostile server, with ``--timeout``.

Starts, one after another, a loopback server that misbehaves in one way:

* ``trickled headers``: the status line and headers one byte every 0.4 T s (2 s at
  ``--timeout 5``), within httpx's timeout for each read;
* ``trickled body``: whole headers, then the body one byte every 0.1 T s;
* ``silent``: reads the request and never answers;
* ``Retry-After: 100000``: answers 429 at once, asking to be asked again in 28 hours;

and runs ``llm-grop arrange "a dinner plate and a dinner fork" --llm openai --timeout T
--retries 1 --no-cache`` against it in a fresh process, stopped at ``--cap`` seconds. It
prints each call's wall time and the command's last line; then, but for ``--quick``, the
wall time of ``llm-grop bench`` with ``--max-failed 3`` over 3 trials against the trickled
headers (stopped at twice the cap). ``--src DIR`` runs another
checkout's package (``git worktree add --detach /tmp/old 2ae1355``, then ``--src
/tmp/old/src``) for the figures before.
Run: .venv/bin/python benchmarks/llm_deadlines.py [--timeout 5] [--cap 60] [--src DIR] [--quick]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from common import parse_args

#: What a hostile server does with a connection whose request it read, given the interval
#: in seconds between the bytes it trickles.
Behaviour = Callable[[socket.socket, threading.Event, float], None]


def _trickle(conn: socket.socket, data: bytes, every_s: float, stop: threading.Event) -> None:
    for byte in data:
        if stop.wait(every_s):
            return
        conn.sendall(bytes([byte]))


def headers(conn: socket.socket, stop: threading.Event, every_s: float) -> None:
    _trickle(conn, b"HTTP/1.1 200 OK\r\nX-Slow: " + b"a" * 100_000, every_s, stop)


def body(conn: socket.socket, stop: threading.Event, every_s: float) -> None:
    conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Type: application/json\r\n"
                 b"Content-Length: 100000\r\n\r\n")
    _trickle(conn, b"{" + b" " * 99_999, every_s / 4, stop)


def silent(conn: socket.socket, stop: threading.Event, every_s: float) -> None:
    stop.wait(3600)


def retry_after(conn: socket.socket, stop: threading.Event, every_s: float) -> None:
    text = b'{"error": {"message": "busy", "type": "rate_limit"}}'
    conn.sendall(b"HTTP/1.1 429 Too Many Requests\r\nContent-Type: application/json\r\n"
                 b"Retry-After: 100000\r\nContent-Length: " + str(len(text)).encode()
                 + b"\r\n\r\n" + text)
    stop.wait(3600)


HOSTILE: dict[str, Behaviour] = {"trickled headers": headers, "trickled body": body,
                                 "silent": silent, "Retry-After: 100000": retry_after}


@contextlib.contextmanager
def hostile(behaviour: Behaviour, every_s: float = 2.0) -> Iterator[str]:
    """A loopback server that answers every connection with ``behaviour``, trickling a byte
    every ``every_s`` seconds; its /v1 URL."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(16)
    stop = threading.Event()

    def one(conn: socket.socket) -> None:
        with conn, contextlib.suppress(OSError):
            conn.recv(65536)
            behaviour(conn, stop, every_s)

    def serve() -> None:
        with contextlib.suppress(OSError):
            while True:
                conn, _ = srv.accept()
                threading.Thread(target=one, args=(conn,), daemon=True).start()

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield f"http://127.0.0.1:{srv.getsockname()[1]}/v1"
    finally:
        stop.set()
        srv.close()


def call(url: str, timeout_s: float, cap_s: float, src: Path | None
         ) -> tuple[float | None, str]:
    """Seconds the CLI's call took against ``url`` (``None``: still running at ``cap_s``,
    when it is stopped), and its last line."""
    return run_cli(["arrange", "a dinner plate and a dinner fork", "--llm", "openai",
                    "--base-url", url, "--timeout", f"{timeout_s:g}", "--retries", "1",
                    "--no-cache"], cap_s, src)


def bench(url: str, timeout_s: float, trials: int, cap_s: float, src: Path | None
          ) -> tuple[float | None, str]:
    """Seconds a bench of ``trials`` llm-grop trials of task 1 took against ``url``, with
    ``--max-failed`` ``trials`` (``None``: still running at ``cap_s``), and its last line."""
    with tempfile.TemporaryDirectory() as out:
        return run_cli(["bench", "--tasks", "1", "--trials", str(trials), "--methods",
                        "llm-grop", "--llm", "openai", "--base-url", url, "--timeout",
                        f"{timeout_s:g}", "--retries", "1", "--max-failed", str(trials),
                        "--no-cache", "--no-images", "--executor", "local", "--out", out],
                       cap_s, src)


def run_cli(arguments: list[str], cap_s: float, src: Path | None) -> tuple[float | None, str]:
    """Seconds ``llm-grop ARGUMENTS`` took in a fresh process (``None``: still running at
    ``cap_s``, when it is stopped), and its last line."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("OPENAI_")}
    if src is not None:
        env["PYTHONPATH"] = str(src)
    command = [sys.executable, "-m", "llm_grop", *arguments]
    start = time.monotonic()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=cap_s, env=env)
    except subprocess.TimeoutExpired:
        return None, "(still running; stopped)"
    lines = [line for line in (done.stderr + done.stdout).splitlines() if line.strip()]
    return time.monotonic() - start, f"exit {done.returncode}: {lines[-1] if lines else ''}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=5.0, help="--timeout, seconds")
    parser.add_argument("--cap", type=float, default=60.0,
                        help="seconds after which a call is stopped")
    parser.add_argument("--src", type=Path, help="another checkout's src directory")
    parser.add_argument("--only", help="comma-separated behaviours (default: all)")
    parser.add_argument("--bench-trials", type=int, default=3,
                        help="trials of a bench against the trickled headers (0: none)")
    args = parse_args(parser, {"timeout": 1.0, "cap": 20.0, "only": "trickled headers,silent",
                               "bench_trials": 0})
    chosen = [b.strip() for b in args.only.split(",")] if args.only else list(HOSTILE)
    print(f"LLM calls against hostile loopback servers, --timeout {args.timeout:g} "
          f"--retries 1 (stopped at {args.cap:g} s); package from {args.src or 'this checkout'}")
    took: list[float | None] = []
    for name in chosen:
        with hostile(HOSTILE[name], 0.4 * args.timeout) as url:
            seconds, last = call(url, args.timeout, args.cap, args.src)
        took.append(seconds)
        print(f"  {name:22s} {_seconds(seconds, args.cap):>8s}   {last[:150]}")
    longest = None if None in took else max(t for t in took if t is not None)
    print(f"longest call: {_seconds(longest, args.cap)} (--timeout {args.timeout:g})")
    if args.bench_trials:
        cap = 2 * args.cap
        with hostile(headers, 0.4 * args.timeout) as url:
            seconds, last = bench(url, args.timeout, args.bench_trials, cap, args.src)
        print(f"bench of {args.bench_trials} trials against the trickled headers, --max-failed "
              f"{args.bench_trials}: {_seconds(seconds, cap)}   {last[:150]}")


def _seconds(took: float | None, cap_s: float) -> str:
    return f">{cap_s:g} s" if took is None else f"{took:.1f} s"


if __name__ == "__main__":
    main()
