"""A sweep of 10,240 episodes on the local executor and on a local Ray cluster (issue 15).

Writes a sweep file (the paper's 8 tasks x 4 methods x 20 trials, in 16 cells: chairs
0/1/2/4 x utility weight 20/40/80/160 s, the embedded model's recorded answers, 2D, no
pictures unless --images), runs `llm-grop sweep` on it once per executor into fresh
directories with a fresh LLM cache each, and prints each run's wall time, its overhead per
trial against the local run, the LLM cache's hit rate, and whether the two runs' rows are
the same. Then projects, from the measured per-trial costs, the workers and wall time a
million episodes take with a live LLM of a stated latency.

``--quick``: Task 8 in 1 cell (1 chair, weight 40 s), one trial, the local executor, 1
worker, in a scratch directory.
Run: .venv/bin/python benchmarks/sweep_scale.py [--out DIR] [--trials 20] [--workers 2]
     [--executors local,ray] [--images] [--latency-s 2.0] [--target-hours 24] [--quick]
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
import time
from pathlib import Path

from common import RECORDING, parse_args, scratch

from llm_grop.experiment.trial import RUN_DEPENDENT_FIELDS as RUN_DEPENDENT

CHAIRS = (0, 1, 2, 4)
WEIGHTS = (20, 40, 80, 160)
#: ``--quick``'s tasks and grid.
QUICK_TASKS, QUICK_CHAIRS, QUICK_WEIGHTS = "8", (1,), (40,)


def sweep_file(path: Path, trials: int, images: bool, tasks: str = "paper",
               chairs: tuple[int, ...] = CHAIRS, weights: tuple[int, ...] = WEIGHTS) -> None:
    path.write_text(
        f"tasks: {tasks}\nmethods: tpra,latp,grop,llm-grop\n"
        f"trials: {trials}\nimages: {'true' if images else 'false'}\n"
        f"llm: {{backend: replay, replay: {RECORDING.resolve()}}}\n"
        f"grid:\n  chairs: {list(chairs)}\n  weight: {list(weights)}\n", encoding="utf-8")


def rows(out: Path) -> dict[tuple[str, int, int, str], dict]:
    found = {}
    for trials in sorted(out.glob("*/trials.jsonl")):
        for line in trials.read_text(encoding="utf-8").splitlines():
            r = json.loads(line)
            found[(trials.parent.name, r["task"], r["trial"], r["method"])] = r
    return found


def run(executor: str, spec: Path, out: Path, workers: int, reuse: bool) -> float:
    wall_file = out.with_name(out.name + ".wall")
    if reuse and wall_file.exists():
        return float(wall_file.read_text())
    shutil.rmtree(out, ignore_errors=True)
    cache = out.with_name(out.name + "-cache")
    shutil.rmtree(cache, ignore_errors=True)
    # Ray keeps its slots busy by itself; --workers would cap the trials in flight.
    cmd = [sys.executable, "-m", "llm_grop", "sweep", str(spec), "--out", str(out), "-q",
           "--executor", executor, "--cache-dir", str(cache),
           *(["--workers", str(workers)] if executor == "local" else [])]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True)
    wall = time.perf_counter() - t0
    wall_file.write_text(f"{wall:.3f}\n")
    return wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("sweep-scale"))
    ap.add_argument("--trials", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--executors", default="local,ray")
    ap.add_argument("--images", action="store_true")
    ap.add_argument("--latency-s", type=float, default=2.0,
                    help="a live LLM's seconds per call, for the projection")
    ap.add_argument("--target-hours", type=float, default=24.0)
    ap.add_argument("--reuse", action="store_true",
                    help="report on the runs already in --out instead of running them again")
    args = parse_args(ap, {"out": lambda: scratch("sweep-scale"), "trials": 1, "workers": 1,
                           "executors": "local"})
    args.out.mkdir(parents=True, exist_ok=True)
    spec = args.out / "sweep.yaml"
    chairs, weights = (QUICK_CHAIRS, QUICK_WEIGHTS) if args.quick else (CHAIRS, WEIGHTS)
    sweep_file(spec, args.trials, args.images, QUICK_TASKS if args.quick else "paper", chairs,
               weights)
    walls, found = {}, {}
    for executor in args.executors.split(","):
        walls[executor] = run(executor, spec, args.out / executor, args.workers, args.reuse)
        found[executor] = rows(args.out / executor)
        print(f"{executor}: {len(found[executor])} episodes in {walls[executor]:.1f} s",
              flush=True)
    first = next(iter(found))
    n = len(found[first])
    calls = sum(r["llm_calls"] for r in found[first].values())
    print(f"\nsweep: {n} episodes ({len(chairs) * len(weights)} cells), "
          f"{args.workers} workers, pictures {'on' if args.images else 'off'}")
    print("| executor | wall (s) | per episode (ms) | against local | overhead per episode "
          "(ms) | LLM calls | cache hits | hit rate | rows as local |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
    for executor, wall in walls.items():
        got = found[executor]
        hits = sum(r["llm_cache_hits"] for r in got.values())
        total = sum(r["llm_calls"] for r in got.values())
        same = {k: {f: v for f, v in r.items() if f not in RUN_DEPENDENT}
                for k, r in got.items()} == {
            k: {f: v for f, v in r.items() if f not in RUN_DEPENDENT}
            for k, r in found[first].items()}
        base = walls.get("local", wall)
        print(f"| {executor} | {wall:.1f} | {1000 * wall / len(got):.1f} | "
              f"{100 * (wall / base - 1):+.1f} % | {1000 * (wall - base) / len(got):+.2f} | "
              f"{total} | {hits} | {100 * hits / max(total, 1):.1f} % | "
              f"{'yes' if same else 'NO'} |")
    # The projection: CPU seconds per episode from the local run, LLM calls per episode
    # from the rows, and a stated latency per call; with no cache hit (every call new: a
    # sweep over LLMs or seeds) and with this sweep's hit rate (grids over other settings
    # share the LLM's answers).
    cpu_s = walls.get("local", next(iter(walls.values()))) * args.workers / n
    hits = sum(r["llm_cache_hits"] for r in found[first].values())
    episodes, seconds = 1_000_000, args.target_hours * 3600
    print(f"\nmeasured: {cpu_s * 1000:.0f} ms of one CPU per episode; {calls / n:.2f} LLM "
          f"calls per episode; cache hit rate {100 * hits / max(calls, 1):.1f} %")
    print(f"1,000,000 episodes, a live LLM at {args.latency_s:g} s per call, in "
          f"{args.target_hours:g} h:")
    print("| LLM calls asked | per episode: waiting + computing (s) | worker-hours | "
          "trials in flight | CPUs | LLM calls per second | with 100 / 1,000 in flight |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for label, asked in (("every call (no hit)", calls / n),
                         (f"misses only ({100 * hits / max(calls, 1):.1f} % hits)",
                          (calls - hits) / n)):
        busy_s = episodes * (cpu_s + asked * args.latency_s)
        print(f"| {label} | {asked * args.latency_s:.2f} + {cpu_s:.3f} | {busy_s / 3600:,.0f} | "
              f"{math.ceil(busy_s / seconds)} | {math.ceil(episodes * cpu_s / seconds)} | "
              f"{episodes * asked / seconds:.1f} | {busy_s / 100 / 3600:,.1f} h / "
              f"{busy_s / 1000 / 3600:,.2f} h |")

if __name__ == "__main__":
    main()
