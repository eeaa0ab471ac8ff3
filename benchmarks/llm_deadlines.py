"""Issue 37's figure: the longest LLM call against each hostile server, with ``--timeout``.

Starts, one after another, a loopback server that misbehaves in one way:

* ``trickled headers``: the status line and headers one byte every 2 s;
* ``trickled body``: whole headers, then the body one byte every 0.5 s;
* ``silent``: reads the request and never answers;
* ``Retry-After: 100000``: answers 429 at once, asking to be asked again in 28 hours;

and runs ``llm-grop arrange "a dinner plate and a dinner fork" --llm openai --timeout T
--retries 1 --no-cache`` against it in a fresh process, stopped at ``--cap`` seconds. It
prints each call's wall time and the command's last line. ``--src DIR`` runs another
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
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from common import parse_args

Behaviour = Callable[[socket.socket, threading.Event], None]


def _trickle(conn: socket.socket, data: bytes, every_s: float, stop: threading.Event) -> None:
    for byte in data:
        if stop.wait(every_s):
            return
        conn.sendall(bytes([byte]))


def headers(conn: socket.socket, stop: threading.Event) -> None:
    _trickle(conn, b"HTTP/1.1 200 OK\r\nX-Slow: " + b"a" * 100_000, 2.0, stop)


def body(conn: socket.socket, stop: threading.Event) -> None:
    conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Type: application/json\r\n"
                 b"Content-Length: 100000\r\n\r\n")
    _trickle(conn, b"{" + b" " * 99_999, 0.5, stop)


def silent(conn: socket.socket, stop: threading.Event) -> None:
    stop.wait(3600)


def retry_after(conn: socket.socket, stop: threading.Event) -> None:
    text = b'{"error": {"message": "busy", "type": "rate_limit"}}'
    conn.sendall(b"HTTP/1.1 429 Too Many Requests\r\nContent-Type: application/json\r\n"
                 b"Retry-After: 100000\r\nContent-Length: " + str(len(text)).encode()
                 + b"\r\n\r\n" + text)
    stop.wait(3600)


HOSTILE: dict[str, Behaviour] = {"trickled headers": headers, "trickled body": body,
                                 "silent": silent, "Retry-After: 100000": retry_after}


@contextlib.contextmanager
def hostile(behaviour: Behaviour) -> Iterator[str]:
    """A loopback server that answers every connection with ``behaviour``; its /v1 URL."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(16)
    stop = threading.Event()

    def one(conn: socket.socket) -> None:
        with conn, contextlib.suppress(OSError):
            conn.recv(65536)
            behaviour(conn, stop)

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


def call(url: str, timeout_s: float, cap_s: float, src: Path | None) -> tuple[float, str]:
    """Seconds the CLI's call took against ``url`` (stopped at ``cap_s``), and its last
    line."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("OPENAI_")}
    if src is not None:
        env["PYTHONPATH"] = str(src)
    command = [sys.executable, "-m", "llm_grop", "arrange", "a dinner plate and a dinner fork",
               "--llm", "openai", "--base-url", url, "--timeout", f"{timeout_s:g}",
               "--retries", "1", "--no-cache"]
    start = time.monotonic()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=cap_s, env=env)
    except subprocess.TimeoutExpired:
        return time.monotonic() - start, f"(still running at {cap_s:g} s; stopped)"
    lines = [line for line in (done.stderr + done.stdout).splitlines() if line.strip()]
    return time.monotonic() - start, f"exit {done.returncode}: {lines[-1] if lines else ''}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=5.0, help="--timeout, seconds")
    parser.add_argument("--cap", type=float, default=60.0,
                        help="seconds after which a call is stopped")
    parser.add_argument("--src", type=Path, help="another checkout's src directory")
    parser.add_argument("--only", help="comma-separated behaviours (default: all)")
    args = parse_args(parser, {"timeout": 1.0, "cap": 20.0, "only": "trickled headers,silent"})
    chosen = [b.strip() for b in args.only.split(",")] if args.only else list(HOSTILE)
    print(f"LLM calls against hostile loopback servers, --timeout {args.timeout:g} "
          f"--retries 1 (stopped at {args.cap:g} s); package from {args.src or 'this checkout'}")
    for name in chosen:
        with hostile(HOSTILE[name]) as url:
            took, last = call(url, args.timeout, args.cap, args.src)
        print(f"  {name:22s} {took:6.1f} s   {last[:150]}")


if __name__ == "__main__":
    main()
