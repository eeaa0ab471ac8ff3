"""What the uptime tests and ``benchmarks/service_uptime.py`` share: a real ``llm-grop serve``
(replayed answers, its jobs in real SQLite) whose thread pool can retire idle threads
sooner than anyio's 10 s, bursts of requests at it, and its open descriptors."""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import httpx

RECORDING = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "embedded_calls.jsonl"


def serve_command(db: Path, port: int, *args: str, thread_idle_s: float | None = None
                  ) -> list[str]:
    """The command line of ``llm-grop serve`` on ``db`` and ``port`` (replayed answers).
    With ``thread_idle_s``, the server's thread pool retires a thread idle that long
    (seconds) at its next request, as anyio does after 10 s: the pool's real retirement,
    sooner."""
    serve = ["serve", "--llm", "replay", "--replay", str(RECORDING), "--db", str(db),
             "--port", str(port), *args]
    if thread_idle_s is None:
        return [sys.executable, "-m", "llm_grop", *serve]
    code = ("import sys\n"
            "from anyio._backends._asyncio import WorkerThread\n"
            f"WorkerThread.MAX_IDLE_TIME = {thread_idle_s!r}\n"
            "from llm_grop.entry import main\n"
            "sys.argv[0] = 'llm-grop'\n"
            "sys.exit(main())\n")
    return [sys.executable, "-c", code, *serve]


def server_env() -> dict[str, str]:
    """The environment a served server runs in."""
    return os.environ | {"MUJOCO_GL": "osmesa"}


def wait_answering(url: str, alive: Callable[[], bool], timeout_s: float = 60) -> None:
    """Wait until ``GET /v1/info`` at ``url`` answers 200; ``RuntimeError`` if the server
    dies (``alive`` false) or does not answer within ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if not alive():
            raise RuntimeError("the server exited before it answered")
        try:
            if httpx.get(f"{url}/v1/info", timeout=1).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.1)
    raise RuntimeError(f"the server did not answer within {timeout_s:g} s")


def descriptors(pid: int, name: str) -> tuple[int, int]:
    """The open file descriptors of process ``pid``, and how many of them are on files
    whose name starts with ``name`` (the database, its WAL)."""
    fds = os.listdir(f"/proc/{pid}/fd")
    on = 0
    for fd in fds:
        with contextlib.suppress(OSError):  # closed meanwhile
            on += os.path.basename(os.readlink(f"/proc/{pid}/fd/{fd}")).startswith(name)
    return len(fds), on


def burst(url: str, requests: int, *, path: str = "/v1/info") -> Counter[int | str]:
    """``requests`` GETs of ``path`` at ``url`` at once, from as many threads; their
    statuses (an exception's name when there was no answer). The connections are closed
    at the end, so that the server's open sockets do not count among its files."""
    statuses: Counter[int | str] = Counter()
    lock = threading.Lock()
    start = threading.Barrier(requests)
    room = httpx.Limits(max_connections=requests, max_keepalive_connections=requests)

    def one(client: httpx.Client) -> None:
        start.wait()
        try:
            status: int | str = client.get(path).status_code
        except httpx.HTTPError as exc:
            status = type(exc).__name__
        with lock:
            statuses[status] += 1

    with httpx.Client(base_url=url, timeout=60, limits=room) as client:
        threads = [threading.Thread(target=one, args=(client,)) for _ in range(requests)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    return statuses


def alive(pid: int) -> bool:
    """Whether process ``pid`` runs (not ended, nor a zombie waiting for its parent)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0] != "Z"
    except OSError:
        return False
