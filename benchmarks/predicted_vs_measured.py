"""The planner's predictions against what a simulator measured, from bench results.

For each results directory (`llm-grop bench --out DIR`) and method: the mean predicted
probability that every action succeeds at its first attempt (the plan's `feasibility`)
against the fraction of trials that had no failed attempt, and the plan's expected
duration against the measured execution time (seconds).
Run: .venv/bin/python benchmarks/predicted_vs_measured.py DIR [DIR ...]
     .venv/bin/python benchmarks/predicted_vs_measured.py --quick   (a tiny bench of its own)
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections import defaultdict
from pathlib import Path

from common import parse_args, results_dirs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="*", type=Path)
    args = parse_args(ap)
    with results_dirs(ap, args) as dirs:
        report(dirs)


def report(dirs: list[Path]) -> None:
    """The table, one row per results directory and method."""
    print(f"{'results':<28} {'method':<9} {'trials':>6} {'P(no failure)':>14} "
          f"{'measured':>9} {'expected s':>11} {'measured s':>11}")
    for d in dirs:
        rows = [json.loads(line) for line in (d / "trials.jsonl").read_text().splitlines()
                if line.strip()]
        by_method: dict[str, list[dict]] = defaultdict(list)
        for r in rows:
            if r.get("status") == "ok":
                by_method[r["method"]].append(r)
        for method, rs in sorted(by_method.items()):
            predicted = statistics.fmean(r["plan"]["feasibility"] for r in rs)
            clean = statistics.fmean(r["failures"] == 0 for r in rs)
            expected = statistics.fmean(r["plan"]["expected_duration_s"] for r in rs)
            measured = statistics.fmean(r["execution_time_s"] for r in rs)
            label = f"{d.name} ({rs[0].get('feasibility', 'default')})"
            print(f"{label:<28} {method:<9} {len(rs):>6} {predicted:>14.2f} {clean:>9.2f} "
                  f"{expected:>11.1f} {measured:>11.1f}")


if __name__ == "__main__":
    main()
