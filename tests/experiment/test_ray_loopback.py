"""Ray clusters on loopback: a two-node ``ray.cluster_utils.Cluster`` whose nodes run on
127.0.0.1 is joined by ``bench`` and ``sweep`` at ``--ray-address 127.0.0.1:PORT`` and
loses its worker node in the middle of a bench (the lost trials run again on the node left,
and every row is present exactly once, identical to a local run's but for the wall-clock
fields); a cluster ``--executor ray`` starts runs on 127.0.0.1 and dies with its driver."""

from __future__ import annotations

import contextlib
import ipaddress
import json
import os
import re
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from llm_grop.cli import main
from llm_grop.experiment.ray_loopback import LOOPBACK, RAY_LOOPBACK_SWITCH, node_address
from llm_grop.experiment.trial import RUN_DEPENDENT_FIELDS

RECORDING = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "embedded_calls.jsonl"
BASE = ["bench", "--tasks", "1,2", "--trials", "3", "--llm", "replay", "--replay",
        str(RECORDING), "--no-images", "-q"]
#: Rows of BASE: 2 tasks x 3 trials x 4 methods.
ROWS = 24
#: A node of the loopback cluster: on 127.0.0.1, one CPU (this machine has two).
NODE = {"node_ip_address": LOOPBACK, "num_cpus": 1}
SWEEP = f"""\
tasks: [1]
methods: grop
trials: 1
images: false
llm: {{backend: replay, replay: {RECORDING}}}
grid:
  chairs: [0, 2]
"""


def _rows(out: Path) -> list[dict]:
    path = out / "trials.jsonl"
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def _stable(rows: list[dict]) -> list[dict]:
    return [{k: v for k, v in r.items() if k not in RUN_DEPENDENT_FIELDS} for r in rows]


@pytest.mark.parametrize(("address", "node"), [
    (None, LOOPBACK), ("local", LOOPBACK), ("127.0.0.1:6379", LOOPBACK),
    ("localhost:6379", LOOPBACK), ("127.0.0.5:6379", "127.0.0.5"),
    # Ray's own choice: another host, a cluster found on this machine, a Ray Client.
    ("10.0.0.7:6379", None), ("head:6379", None), ("auto", None),
    ("ray://127.0.0.1:10001", None), ("[::1]:6379", None)])
def test_the_drivers_node_address_is_loopback_for_a_loopback_cluster(
        address: str | None, node: str | None) -> None:
    assert node_address(address) == node


def test_a_port_that_answers_but_is_no_cluster_is_refused_in_time(tmp_path: Path,
                                                                  monkeypatch, capsys) -> None:
    import socket

    from llm_grop.experiment import ray_executor

    pytest.importorskip("ray")
    monkeypatch.setattr(ray_executor, "JOIN_S", 5.0)
    with socket.create_server((LOOPBACK, 0)) as silent:  # accepts, never speaks
        port = silent.getsockname()[1]
        t0 = time.monotonic()
        code = main(BASE + ["--out", str(tmp_path / "x"), "--executor", "ray",
                            "--ray-address", f"{LOOPBACK}:{port}"])
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
                # Another process's arguments need not be UTF-8 (a test of bad bytes).
                cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(
                    errors="replace")
            except OSError:
                continue
            if "ray::" in cmd or "/ray/" in cmd and ("raylet" in cmd or "gcs_server" in cmd
                                                     or "dashboard" in cmd):
                found[int(entry.name)] = cmd.strip()
    return found


#: A node address on a Ray process's command line (``--node-ip-address=`` and the like).
NODE_FLAG = re.compile(r"--node[-_]ip[-_]address[= ](\S+)")


def _listening(pids: set[int]) -> set[ipaddress.IPv4Address | ipaddress.IPv6Address]:
    """The addresses the TCP sockets of ``pids`` listen on (``/proc/net/tcp`` and ``tcp6``)."""
    inodes = set()
    for pid in pids:
        with contextlib.suppress(OSError):  # gone meanwhile
            for fd in Path(f"/proc/{pid}/fd").iterdir():
                with contextlib.suppress(OSError):
                    inodes.add(os.readlink(fd).removeprefix("socket:[").removesuffix("]"))
    found: set[ipaddress.IPv4Address | ipaddress.IPv6Address] = set()
    for table in ("tcp", "tcp6"):
        for line in Path(f"/proc/net/{table}").read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "0A" and fields[9] in inodes:  # 0A: listening
                # The kernel prints each 32-bit word of the address in host (little-endian) order.
                raw = bytes.fromhex(fields[1].split(":")[0])
                words = b"".join(raw[i:i + 4][::-1] for i in range(0, len(raw), 4))
                found.add(ipaddress.ip_address(words))
    return found


def _loopback(ip: ipaddress.IPv4Address | ipaddress.IPv6Address) -> bool:
    mapped = ip.ipv4_mapped if isinstance(ip, ipaddress.IPv6Address) else None
    return (mapped or ip).is_loopback


def test_a_started_cluster_runs_on_loopback_and_dies_with_a_killed_driver(
        tmp_path: Path) -> None:
    # Before the module's cluster starts: ray.init() without an address would join it
    # (Ray finds a cluster_utils or `ray start` cluster through its address file).
    import signal
    import subprocess
    import sys

    pytest.importorskip("ray")
    before = set(_ray_processes())
    out = tmp_path / "killed"
    # Without the tests' own loopback switch: the executor must set it itself.
    env = {k: v for k, v in os.environ.items() if k != RAY_LOOPBACK_SWITCH}
    # Its one-line error is kept: a driver that ends before its first row says why.
    said = tmp_path / "driver.err"
    with said.open("wb") as err:
        driver = subprocess.Popen([sys.executable, "-m", "llm_grop", *BASE, "--out",
                                   str(out), "--executor", "ray", "--workers", "1"], env=env,
                                  stdout=subprocess.DEVNULL, stderr=err)
    deadline = time.monotonic() + 180
    while not _rows(out):
        assert driver.poll() is None and time.monotonic() < deadline, \
            f"the driver ended ({driver.poll()}) with no row: {said.read_text()[-2000:]}"
        time.sleep(0.05)
    started = {pid: cmd for pid, cmd in _ray_processes().items() if pid not in before}
    assert started, "the driver should have started a Ray cluster"
    addresses = {a for cmd in started.values() for a in NODE_FLAG.findall(cmd)}
    assert addresses == {LOOPBACK}, started
    listening = _listening(set(started))
    assert listening and all(_loopback(ip) for ip in listening), listening
    driver.send_signal(signal.SIGKILL)
    driver.wait()
    deadline = time.monotonic() + 20
    while set(_ray_processes()) & set(started) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = {pid: cmd for pid, cmd in _ray_processes().items() if pid in started}
    assert not left, f"Ray processes outlived the driver: {left}"


@pytest.fixture(scope="module")
def local(tmp_path_factory) -> list[dict]:
    """BASE's rows from the local executor."""
    out = tmp_path_factory.mktemp("local") / "bench"
    assert main(BASE + ["--out", str(out)]) == 0
    return _rows(out)


@pytest.fixture(scope="module")
def cluster() -> Any:
    """A two-node Ray cluster whose nodes run on 127.0.0.1, one CPU each. The node-loss
    test removes its worker node and adds another in its place."""
    cluster_utils = pytest.importorskip("ray.cluster_utils")
    made = cluster_utils.Cluster(initialize_head=True,
                                 head_node_args=NODE | {"include_dashboard": False})
    try:
        made.add_node(**NODE)
        made.wait_for_nodes()
        yield made
    finally:
        made.shutdown()


def _addresses(cluster: Any) -> tuple[set[str], set[str]]:
    """The node addresses of the cluster's live nodes, and of every driver that joined it,
    as its GCS records them."""
    state = cluster.global_state
    nodes = {n["NodeManagerAddress"] for n in state.node_table() if n["Alive"]}
    drivers = {job["DriverIPAddress"] for job in state.job_table()}
    return nodes, drivers


def test_a_bench_joins_a_two_node_loopback_cluster(cluster: Any, local: list[dict],
                                                   tmp_path: Path) -> None:
    assert cluster.address.startswith(f"{LOOPBACK}:")
    assert len(cluster.list_all_nodes()) == 2
    out = tmp_path / "joined"
    assert main(BASE + ["--out", str(out), "--executor", "ray",
                        "--ray-address", cluster.address]) == 0
    rows = _rows(out)
    assert len(rows) == ROWS and _stable(rows) == _stable(local)
    assert _addresses(cluster) == ({LOOPBACK}, {LOOPBACK})


def test_a_sweep_joins_a_loopback_cluster(cluster: Any, tmp_path: Path) -> None:
    (tmp_path / "sweep.yaml").write_text(SWEEP)
    out = tmp_path / "out"
    assert main(["sweep", str(tmp_path / "sweep.yaml"), "--out", str(out), "-q",
                 "--executor", "ray", "--ray-address", cluster.address]) == 0
    for cell in ("chairs=0", "chairs=2"):
        assert [r["method"] for r in _rows(out / cell)] == ["grop"]
    assert _addresses(cluster) == ({LOOPBACK}, {LOOPBACK})


def test_a_lost_node_loses_and_duplicates_no_row(cluster: Any, local: list[dict],
                                                 tmp_path: Path) -> None:
    worker = next(iter(cluster.worker_nodes))
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
        if worker in cluster.worker_nodes:
            cluster.remove_node(worker)
        cluster.add_node(**NODE)  # the cluster is two nodes again for what follows
    assert codes == [0]
    rows = _rows(out)
    keys = [(r["task"], r["trial"], r["method"]) for r in rows]
    assert len(keys) == len(set(keys)) == ROWS
    assert _stable(rows) == _stable(local)
