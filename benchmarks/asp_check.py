"""Wall time of the clingo consistency check (paper §III-A), in milliseconds.

Prints the median and p95 over 200 runs of `check` on a realistic consistent
10-relation answer, and of `minimal_conflict` and `largest_consistent_subset` on
the paper's inconsistent example (6 lines, minimal conflict {2, 3, 5}).
Run: .venv/bin/python benchmarks/asp_check.py [--runs N] [--quick]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable

from common import parse_args

from llm_grop.arrangement.consistency import check, largest_consistent_subset, minimal_conflict
from llm_grop.world.relation import Relation

R = Relation

TEN = [
    R("dinner plate", "center", None),
    R("dinner fork", "to the left of", "dinner plate"),
    R("salad fork", "to the left of", "dinner fork"),
    R("dinner knife", "to the right of", "dinner plate"),
    R("soup spoon", "to the right of", "dinner knife"),
    R("water cup", "above and to the right of", "dinner plate"),
    R("bread plate", "above and to the left of", "dinner plate"),
    R("butter knife", "on top of", "bread plate"),
    R("mug mat", "to the right of", "soup spoon"),
    R("mug", "on top of", "mug mat"),
]
PAPER = [
    R("fruit bowl", "center", None, "1"),
    R("butter knife", "above and to the right of", "fruit bowl", "2"),
    R("dinner fork", "to the left of", "butter knife", "3"),
    R("dinner knife", "to the right of", "butter knife", "4"),
    R("fruit bowl", "to the right of", "dinner fork", "5"),
    R("water cup", "below and to the left of", "dinner knife", "6"),
]


def _time(fn: Callable[[], object], runs: int) -> tuple[float, float]:
    """Median and p95 wall time of ``fn()`` in milliseconds, after one warm-up call."""
    fn()
    samples = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        samples.append((time.perf_counter() - t0) * 1000)
    samples.sort()
    return statistics.median(samples), samples[math.ceil(0.95 * runs) - 1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200)
    runs = parse_args(parser, {"runs": 5}).runs
    # Guard against timing a wrong answer.
    if not check(TEN).consistent:
        raise SystemExit("the 10-relation answer should be consistent")
    if [r.line for r in minimal_conflict(PAPER)] != ["2", "3", "5"]:
        raise SystemExit("the paper's example should conflict on lines 2, 3, 5")
    if len(largest_consistent_subset(PAPER)) != 5:
        raise SystemExit("the paper's example should keep 5 of 6 lines")
    for label, fn in (
        ("check, consistent 10-relation answer", lambda: check(TEN)),
        ("minimal_conflict, paper's example", lambda: minimal_conflict(PAPER)),
        ("largest_consistent_subset, paper's example", lambda: largest_consistent_subset(PAPER)),
    ):
        median, p95 = _time(fn, runs)
        print(f"{label:45s} median {median:5.2f} ms  p95 {p95:5.2f} ms  ({runs} runs)")


if __name__ == "__main__":
    main()
