"""The supervisor ends what runs too long and what a client cancels, and the pool goes on
with a fresh worker (MuJoCo runs: long enough to catch running)."""

from __future__ import annotations

import time
from pathlib import Path

from service_support import start_server, wait_done

FREE = {"request": "a dinner plate, a dinner fork and a dinner knife", "simulator": "mujoco",
        "video": False}


def wait_running(client, job_id: str) -> None:
    deadline = time.monotonic() + 60
    while client.get(f"/v1/runs/{job_id}").json()["state"] != "running":
        assert time.monotonic() < deadline
        time.sleep(0.1)


def test_a_run_over_time_fails_and_a_cancelled_one_ends_cancelled(tmp_path: Path) -> None:
    s = start_server(tmp_path / "jobs.sqlite", "--workers", "1", "--max-run-time", "4")
    try:
        with s.client() as c:
            slow = c.post("/v1/runs", json=FREE).json()["id"]
            job = wait_done(c, slow)
            assert job["state"] == "failed" and job["status"] == 504
            assert job["error"] == "ran longer than this server's 4 s"
            quick = c.post("/v1/runs", json={"task": 1, "seed": 0}).json()["id"]
            assert wait_done(c, quick)["state"] == "done"  # a fresh worker took over
    finally:
        s.stop()
    s = start_server(tmp_path / "jobs.sqlite", "--workers", "1")
    try:
        with s.client() as c:
            slow = c.post("/v1/runs", json=FREE).json()["id"]
            waiting = c.post("/v1/runs", json={"task": 1, "seed": 1}).json()["id"]
            wait_running(c, slow)
            assert c.delete(f"/v1/runs/{slow}").status_code == 200
            job = wait_done(c, slow)
            assert job["state"] == "cancelled" and job["error"] == "cancelled by the client"
            assert job["status"] is None
            assert wait_done(c, waiting)["state"] == "done"
    finally:
        s.stop()
