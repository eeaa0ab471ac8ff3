"""Trips against one object per trip: a six-diner table set with the tray and without.

Six diners, each with a dinner plate, a dinner fork, a dinner knife and a water cup (24
objects), GROP in the 2D simulator on a 2.4 x 1.0 m table, for seeds 0..N-1: the plan's
expected duration (seconds, under the planner's belief: driving, picks and places with
their expected retries, and with capacity above 1 each object's load onto the tray and
unload from it on a trip of several) and the executed time (seconds), with capacity 1 and
with ``--capacity`` (default 4), and how many trips carried the objects.

    PYTHONPATH=src python benchmarks/family_trips.py --seeds 10
"""

from __future__ import annotations

import argparse
import statistics

from common import replay_llm

from llm_grop.api import run

REQUEST = ("set the table for six people, each with a dinner plate, a dinner fork, a "
           "dinner knife and a water cup")


def one(seed: int, capacity: int, table: str) -> tuple[float, float, int, bool]:
    """Expected and executed seconds, trips and success of one run."""
    r = run(REQUEST, method="grop", seed=seed, capacity=capacity, table=table,
            llm=replay_llm())
    trips = len(r.execution.trips) if r.execution.trips else len(r.plan.order)
    return r.plan.expected_duration_s, r.execution.execution_time_s, trips, r.success


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--capacity", type=int, default=4)
    ap.add_argument("--table", default="2.4x1.0")
    args = ap.parse_args()
    rows = []
    print(f"seed  cap1 expected  cap1 executed  cap{args.capacity} expected  "
          f"cap{args.capacity} executed  trips  success(1/{args.capacity})", flush=True)
    for seed in range(args.seeds):
        e1, x1, _, ok1 = one(seed, 1, args.table)
        e4, x4, trips, ok4 = one(seed, args.capacity, args.table)
        rows.append((e1, x1, e4, x4))
        print(f"{seed:4d}  {e1:13.1f}  {x1:13.1f}  {e4:13.1f}  {x4:13.1f}  {trips:5d}  "
              f"{ok1}/{ok4}", flush=True)
    faster_e = sum(r[2] < r[0] - 1e-6 for r in rows)
    faster_x = sum(r[3] < r[1] - 1e-6 for r in rows)
    slower_x = sum(r[3] > r[1] + 1e-6 for r in rows)
    print(f"mean: capacity 1 expected {statistics.fmean(r[0] for r in rows):.1f} s, executed "
          f"{statistics.fmean(r[1] for r in rows):.1f} s; capacity {args.capacity} expected "
          f"{statistics.fmean(r[2] for r in rows):.1f} s, executed "
          f"{statistics.fmean(r[3] for r in rows):.1f} s")
    print(f"capacity {args.capacity} faster in expectation on {faster_e} of {len(rows)} "
          f"seeds, in execution on {faster_x} (slower on {slower_x})")


if __name__ == "__main__":
    main()
