"""A real ``llm-grop serve`` for the service tests (:func:`start_server`): a subprocess on
a free loopback port, answering with the embedded model's recorded answers (replay), its
jobs in a temporary SQLite file."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import httpx

RECORDING = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "embedded_calls.jsonl"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Server:
    """A running server: its process, base URL and database."""

    proc: subprocess.Popen[bytes]
    url: str
    db: Path
    token: str | None = None

    def client(self, **kw: object) -> httpx.Client:
        headers = {"Authorization": f"Bearer {self.token}"} if self.token else {}
        return httpx.Client(base_url=self.url, headers=headers, timeout=120, **kw)

    def kill(self) -> None:
        """``kill -9`` the server (its workers die with it)."""
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(timeout=10)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                self.kill()


def start_server(db: Path, *args: str, token: str | None = None) -> Server:
    """Start ``llm-grop serve`` on ``db`` and wait until it answers."""
    port = free_port()
    env = os.environ | {"MUJOCO_GL": "osmesa"}
    if token:
        env["LLM_GROP_TOKEN"] = token
    # The server's output goes to a file beside its database: a pipe nobody reads would
    # fill up and stall it.
    log = db.with_name(db.name + ".log").open("ab")
    proc = subprocess.Popen(
        [sys.executable, "-m", "llm_grop", "serve", "--llm", "replay", "--replay",
         str(RECORDING), "--db", str(db), "--port", str(port), *args],
        env=env, stdout=log, stderr=log)
    log.close()
    server = Server(proc, f"http://127.0.0.1:{port}", db, token)
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    for _ in range(300):
        if proc.poll() is not None:
            raise RuntimeError(f"serve exited: {db.with_name(db.name + '.log').read_text()}")
        try:
            if httpx.get(f"{server.url}/v1/info", headers=headers, timeout=1).status_code == 200:
                return server
        except httpx.HTTPError:
            pass
        time.sleep(0.1)
    server.stop()
    raise RuntimeError("serve did not answer within 30 s")


def wait_done(client: httpx.Client, job_id: str, timeout_s: float = 120) -> dict:
    """Poll a run until it ends; its last answer."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        job = client.get(f"/v1/runs/{job_id}").json()
        if job["state"] in ("done", "failed", "cancelled"):
            return job
        time.sleep(0.1)
    raise AssertionError(f"run {job_id} still {job['state']} after {timeout_s} s")
