"""Wall time of the clingo consistency check (paper §III-A).

Prints the median and p95 over 200 runs of `check` on a consistent 10-relation
answer, and of `check` (with the minimal conflict) and
`largest_consistent_subset` on the paper's inconsistent example.
Run: .venv/bin/python benchmarks/asp_check.py
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

from llm_grop.arrangement.consistency import check, largest_consistent_subset
from llm_grop.world.relation import Relation

TEN = [
    Relation("dinner plate", "center", None),
    Relation("dinner fork", "to the left of", "dinner plate"),
    Relation("salad fork", "to the left of", "dinner fork"),
    Relation("dinner knife", "to the right of", "dinner plate"),
    Relation("soup spoon", "to the right of", "dinner knife"),
    Relation("water cup", "above and to the right of", "dinner plate"),
    Relation("bread plate", "above and to the left of", "dinner plate"),
    Relation("butter knife", "on top of", "bread plate"),
    Relation("mug mat", "to the right of", "soup spoon"),
    Relation("mug", "on top of", "mug mat"),
]
PAPER = [
    Relation("fruit bowl", "center", None),
    Relation("butter knife", "above and to the right of", "fruit bowl"),
    Relation("dinner fork", "to the left of", "butter knife"),
    Relation("dinner knife", "to the right of", "butter knife"),
    Relation("fruit bowl", "to the right of", "dinner fork"),
    Relation("water cup", "below and to the left of", "dinner knife"),
]


def _time(fn: Callable[[], object], runs: int = 200) -> tuple[float, float]:
    fn()
    samples = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        samples.append((time.perf_counter() - t0) * 1000)
    samples.sort()
    return statistics.median(samples), samples[int(0.95 * len(samples)) - 1]


def main() -> None:
    assert check(TEN).consistent and not check(PAPER).consistent
    for label, fn in (
        ("check, consistent 10-relation answer", lambda: check(TEN)),
        ("check + minimal conflict, paper's example (6 lines)", lambda: check(PAPER)),
        ("largest consistent subset, paper's example", lambda: largest_consistent_subset(PAPER)),
    ):
        median, p95 = _time(fn)
        print(f"{label}: median {median:.2f} ms, p95 {p95:.2f} ms (200 runs)")


if __name__ == "__main__":
    main()
