"""Ray on loopback (issue 39): a bench joins a two-node Ray cluster whose nodes run on
127.0.0.1 and loses the worker node in the middle of the bench.

Starts a ``ray.cluster_utils.Cluster`` on 127.0.0.1 (a head node and a worker node, one CPU
each), then, for each repeat: times a join of the cluster from a fresh process (the check
``--ray-address`` makes before the bench joins: ``ray_executor.check_joinable``), runs
``llm-grop bench --executor ray --ray-address 127.0.0.1:PORT`` in a process of its own
(the embedded model's recorded answers, 2D, no pictures), removes the worker node once the
first row is written, and counts the rows: expected, present, duplicated, missing, and
whether they are a local run's but for the wall-clock fields. A fresh worker node joins
before the next repeat. Prints the node and driver addresses the cluster's GCS recorded
(loopback only) and a table of the repeats.

``--quick``: Task 1, one trial (4 rows), one repeat.
Run: .venv/bin/python benchmarks/ray_loopback.py [--tasks 1,2,3,4] [--trials 3] [--repeats 3]
     [--quick]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from common import RECORDING, parse_args

from llm_grop.experiment.ray_loopback import LOOPBACK, use_loopback
from llm_grop.experiment.trial import RUN_DEPENDENT_FIELDS

#: A node of the cluster: on 127.0.0.1, one CPU.
NODE = {"node_ip_address": LOOPBACK, "num_cpus": 1}
#: Seconds a bench may take before the script gives up on it (a safety net).
BENCH_S = 1800


def bench_command(out: Path, tasks: str, trials: int, *executor: str) -> list[str]:
    return [sys.executable, "-m", "llm_grop", "bench", "--tasks", tasks, "--trials",
            str(trials), "--llm", "replay", "--replay", str(RECORDING), "--no-images",
            "--out", str(out), "-q", *executor]


def rows(out: Path) -> list[dict[str, Any]]:
    path = out / "trials.jsonl"
    if not path.exists():
        return []
    # A line being written is not a row yet.
    return [json.loads(line) for line in path.read_text().splitlines(keepends=True)
            if line.endswith("\n")]


def key(row: dict[str, Any]) -> tuple[int, int, str]:
    return row["task"], row["trial"], row["method"]


def stable(found: list[dict[str, Any]]) -> dict[tuple[int, int, str], dict[str, Any]]:
    return {key(r): {k: v for k, v in r.items() if k not in RUN_DEPENDENT_FIELDS}
            for r in found}


def lose_a_node(cluster: Any, out: Path, tasks: str, trials: int) -> tuple[float, int, float]:
    """Run the bench on ``cluster`` and remove its worker node once the first row is in:
    ``(the bench's wall time in s, rows written when the node went, seconds into the
    bench it went)``."""
    worker = next(iter(cluster.worker_nodes))
    t0 = time.perf_counter()
    # The bench's output (Ray's note on each batch it runs again) is shown if it fails.
    with out.with_suffix(".log").open("w+") as log:
        proc = subprocess.Popen(bench_command(out, tasks, trials, "--executor", "ray",
                                              "--ray-address", cluster.address),
                                stdout=log, stderr=subprocess.STDOUT)
        try:
            while not rows(out) and proc.poll() is None:
                time.sleep(0.05)
            at_loss, lost_s = len(rows(out)), time.perf_counter() - t0
            cluster.remove_node(worker)
            code = proc.wait(timeout=BENCH_S)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        if code != 0:
            log.seek(0)
            raise SystemExit(f"the bench on the cluster exited {code}:\n{log.read()[-2000:]}")
    return time.perf_counter() - t0, at_loss, lost_s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default="1,2,3,4")
    ap.add_argument("--trials", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=3)
    args = parse_args(ap, {"tasks": "1", "trials": 1, "repeats": 1})
    # Before Ray is imported: it reads its loopback switch then.
    use_loopback()
    import ray.cluster_utils

    from llm_grop.experiment.ray_executor import check_joinable

    with tempfile.TemporaryDirectory(prefix="llm-grop-ray-loopback-") as tmp:
        root = Path(tmp)
        subprocess.run(bench_command(root / "local", args.tasks, args.trials), check=True)
        local = stable(rows(root / "local"))
        t0 = time.perf_counter()
        cluster = ray.cluster_utils.Cluster(initialize_head=True, head_node_args=NODE | {
            "include_dashboard": False})
        try:
            cluster.add_node(**NODE)
            cluster.wait_for_nodes()
            print(f"cluster: 2 nodes at {cluster.address}, started in "
                  f"{time.perf_counter() - t0:.1f} s", flush=True)
            results = []
            for repeat in range(args.repeats):
                if repeat:
                    cluster.add_node(**NODE)
                    cluster.wait_for_nodes()
                t0 = time.perf_counter()
                check_joinable(cluster.address)
                join_s = time.perf_counter() - t0
                out = root / f"ray-{repeat}"
                wall, at_loss, lost_s = lose_a_node(cluster, out, args.tasks, args.trials)
                found = rows(out)
                keys = [key(r) for r in found]
                results.append((join_s, wall, at_loss, lost_s, len(keys), len(set(keys)),
                                len(keys) - len(set(keys)), len(set(local) - set(keys)),
                                stable(found) == local))
            state = cluster.global_state
            nodes = sorted({n["NodeManagerAddress"] for n in state.node_table()})
            drivers = sorted({j["DriverIPAddress"] for j in state.job_table()})
        finally:
            cluster.shutdown()
    print(f"node addresses the GCS recorded: {', '.join(nodes)}; drivers' (the join checks' "
          f"and the benches'): {', '.join(drivers)}")
    print(f"\nbench: tasks {args.tasks} x {args.trials} trials x 4 methods = {len(local)} rows "
          "expected; the worker node removed once the first row was written")
    print("| repeat | join (s) | bench wall (s) | node lost at (s) | rows then | expected | "
          "present | duplicated | missing | rows as local |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
    for i, (join_s, wall, at_loss, lost_s, _, present, dup, missing, same) in enumerate(
            results):
        print(f"| {i + 1} | {join_s:.2f} | {wall:.1f} | {lost_s:.1f} | {at_loss} | "
              f"{len(local)} | {present} | {dup} | {missing} | {'yes' if same else 'NO'} |")
    joins = [r[0] for r in results]
    print(f"\njoin: median {statistics.median(joins):.2f} s over {len(joins)} "
          f"(a fresh process joins the cluster on 127.0.0.1 and leaves)")


if __name__ == "__main__":
    main()
