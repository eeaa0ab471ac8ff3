"""The paper's four methods on Task 8 in 3D physics against the 2D kinematic simulator.

Runs `llm-grop bench --tasks 8` once per simulator (the embedded model's recorded
answers, 2 workers, no pictures) into DIR/kinematic2d and DIR/mujoco, resuming what is
already there, and prints success, execution time and rating side by side.
Run: .venv/bin/python benchmarks/mujoco_vs_2d.py [--trials 20] [--out DIR]
     [--feasibility default] [--tasks 8] [--methods tpra,latp,grop,llm-grop] [--quick]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from common import bench, parse_args, scratch

METHODS = ("tpra", "latp", "grop", "llm-grop")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=20)
    ap.add_argument("--out", type=Path, default=Path("bench-3d-vs-2d"))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--feasibility", default="default")
    ap.add_argument("--tasks", default="8")
    ap.add_argument("--methods", default=",".join(METHODS))
    args = parse_args(ap, {"trials": 1, "tasks": "1", "methods": "llm-grop", "workers": 1,
                           "out": lambda: scratch("mujoco-vs-2d")})
    summaries = {}
    for sim in ("kinematic2d", "mujoco"):
        out = args.out / (sim if args.feasibility == "default" else f"{sim}-{args.feasibility}")
        t0 = time.perf_counter()
        bench(out, "--simulator", sim, "--feasibility", args.feasibility, tasks=args.tasks,
              trials=args.trials, methods=args.methods, workers=args.workers)
        print(f"{sim}: {time.perf_counter() - t0:.0f} s wall")
        summaries[sim] = json.loads((out / "summary.json").read_text())
    print(f"\nTask {args.tasks} x {args.trials} trials, feasibility {args.feasibility}")
    print(f"{'method':<10} {'success 2D':>10} {'success 3D':>10} {'time 2D (s)':>12} "
          f"{'time 3D (s)':>12} {'rating 2D':>10} {'rating 3D':>10}")
    for m in args.methods.split(","):
        a, b = (_method(summaries[s], m) for s in ("kinematic2d", "mujoco"))
        print(f"{m:<10} {a['success_rate']['mean']:>10.2f} {b['success_rate']['mean']:>10.2f} "
              f"{a['execution_time_s']['mean']:>12.1f} {b['execution_time_s']['mean']:>12.1f} "
              f"{a['rating']['mean']:>10.2f} {b['rating']['mean']:>10.2f}")


def _method(summary: dict, name: str) -> dict:
    for m in summary["methods"]:
        if m["method"] == name:
            return m
    raise SystemExit(f"no method {name} in the summary")


if __name__ == "__main__":
    main()
