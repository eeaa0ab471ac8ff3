"""Where the baselines draw their arrangements, measured: mean execution times in 2D.

Task 8 over 20 seeds (0-19) in the 2D simulator, LLM methods replaying the embedded
model's recorded answers. Prints the mean execution time (simulated seconds) of TPRA,
GROP and LLM-GROP, and LLM-GROP's over GROP's; episodes with no plan (``Infeasible``)
are counted and left out of the means. Issue 24: with the baselines' arrangements drawn
over the whole top, GROP keeps the most reachable of 25 and LLM-GROP, set at the diner's
place, looked slow beside it.
Run: .venv/bin/python benchmarks/baseline_draws.py [--seeds 20] [--quick]
"""

from __future__ import annotations

import argparse

from common import mean_se, parse_args, replay_llm

from llm_grop.api import run
from llm_grop.errors import Infeasible

TASK = 8
METHODS = ("tpra", "grop", "llm-grop")


def mean_times(method: str, seeds: int) -> tuple[list[float], int]:
    """Execution times (simulated seconds) of ``method`` on Task 8 for seeds ``0..seeds-1``,
    and how many of those episodes were infeasible."""
    llm = replay_llm()
    times, infeasible = [], 0
    for seed in range(seeds):
        try:
            r = run(task=TASK, seed=seed, method=method, llm=llm)
        except Infeasible:
            infeasible += 1
            continue
        times.append(r.execution.execution_time_s)
    return times, infeasible


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    args = parse_args(ap, {"seeds": 1})
    means: dict[str, float] = {}
    for method in METHODS:
        times, infeasible = mean_times(method, args.seeds)
        mean, se = mean_se(times)
        means[method] = mean
        print(f"task {TASK}, {args.seeds} seeds, {method}: mean execution time {mean:.2f} "
              f"± {se:.2f} s over {len(times)} episodes; infeasible {infeasible}")
    print(f"llm-grop / grop: {means['llm-grop'] / means['grop']:.3f}")


if __name__ == "__main__":
    main()
