"""A two-node Ray cluster (``ray.cluster_utils.Cluster``) loses its worker node in the
middle of a bench: the lost trials run again on the node left, and every row is present
exactly once, identical to a local run's but for the wall-clock fields."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import pytest

from llm_grop.cli import main
from llm_grop.experiment.trial import RUN_DEPENDENT_FIELDS

RECORDING = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "embedded_calls.jsonl"
BASE = ["bench", "--tasks", "1,2", "--trials", "3", "--llm", "replay", "--replay",
        str(RECORDING), "--no-images", "-q"]


def _rows(out: Path) -> list[dict]:
    path = out / "trials.jsonl"
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def _stable(rows: list[dict]) -> list[dict]:
    return [{k: v for k, v in r.items() if k not in RUN_DEPENDENT_FIELDS} for r in rows]


def test_a_lost_node_loses_and_duplicates_no_row(tmp_path: Path) -> None:
    cluster_utils = pytest.importorskip("ray.cluster_utils")
    local = tmp_path / "local"
    assert main(BASE + ["--out", str(local)]) == 0
    cluster = cluster_utils.Cluster(initialize_head=True, head_node_args={
        "num_cpus": 1, "include_dashboard": False})
    worker = cluster.add_node(num_cpus=2)
    cluster.wait_for_nodes()
    out = tmp_path / "ray"
    codes: list[int] = []
    run = threading.Thread(target=lambda: codes.append(main(
        BASE + ["--out", str(out), "--executor", "ray", "--ray-address", cluster.address])))
    try:
        run.start()
        deadline = time.monotonic() + 180
        while not _rows(out) and run.is_alive():
            assert time.monotonic() < deadline
            time.sleep(0.05)
        cluster.remove_node(worker)  # mid-bench: trials are running on it
        run.join(timeout=600)
    finally:
        cluster.shutdown()
    assert codes == [0]
    rows = _rows(out)
    keys = [(r["task"], r["trial"], r["method"]) for r in rows]
    assert len(keys) == len(set(keys)) == 24
    assert _stable(rows) == _stable(_rows(local))


def test_a_port_that_answers_but_is_no_cluster_is_refused_in_time(tmp_path: Path,
                                                                  monkeypatch, capsys) -> None:
    import socket

    from llm_grop.experiment import ray_executor

    pytest.importorskip("ray")
    monkeypatch.setattr(ray_executor, "JOIN_S", 5.0)
    with socket.create_server(("127.0.0.1", 0)) as silent:  # accepts, never speaks
        port = silent.getsockname()[1]
        t0 = time.monotonic()
        code = main(BASE + ["--out", str(tmp_path / "x"), "--executor", "ray",
                            "--ray-address", f"127.0.0.1:{port}"])
        took = time.monotonic() - t0
    assert code == 2 and took < 20
    err = capsys.readouterr().err.strip()
    assert err == (f"llm-grop: error: --executor ray: cannot reach the Ray cluster at "
                   f"127.0.0.1:{port}: could not join it within 5 s (is the cluster's node "
                   "address reachable from here?)")


def _ray_processes() -> dict[int, str]:
    """Ray's processes on this machine: pid -> command line."""
    found = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
            except OSError:
                continue
            if "ray::" in cmd or "/ray/" in cmd and ("raylet" in cmd or "gcs_server" in cmd
                                                     or "dashboard" in cmd):
                found[int(entry.name)] = cmd.strip()
    return found


def test_a_killed_driver_takes_the_cluster_it_started_with_it(tmp_path: Path) -> None:
    import signal
    import subprocess
    import sys

    pytest.importorskip("ray")
    before = set(_ray_processes())
    out = tmp_path / "killed"
    driver = subprocess.Popen([sys.executable, "-m", "llm_grop", *BASE, "--out", str(out),
                               "--executor", "ray", "--workers", "1"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 180
    while not _rows(out):
        assert driver.poll() is None and time.monotonic() < deadline
        time.sleep(0.05)
    started = set(_ray_processes()) - before
    assert started, "the driver should have started a Ray cluster"
    driver.send_signal(signal.SIGKILL)
    driver.wait()
    deadline = time.monotonic() + 20
    while set(_ray_processes()) & started and time.monotonic() < deadline:
        time.sleep(0.2)
    left = {pid: cmd for pid, cmd in _ray_processes().items() if pid in started}
    assert not left, f"Ray processes outlived the driver: {left}"
