"""Episode success rate: Task 8 with 1 chair and with 4 chairs near the table.

Every method runs the same 50 seeds (the same scenes and chairs); LLM methods replay the
embedded model's recorded answers. Success = every object reached the table.
Run: .venv/bin/python benchmarks/episode_success.py [--seeds 50] [--methods llm-grop,...]
     [--quick]
"""

from __future__ import annotations

import argparse
import statistics

from common import mean_se, parse_args, replay_llm

from llm_grop.api import run
from llm_grop.errors import Infeasible


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--methods", default="llm-grop")
    ap.add_argument("--chairs", default="1,4")
    args = parse_args(ap, {"seeds": 1, "chairs": "1"})
    llm = replay_llm()
    for chairs in (int(c) for c in args.chairs.split(",")):
        for method in args.methods.split(","):
            ok, times, failures, infeasible = 0, [], [], 0
            for seed in range(args.seeds):
                try:
                    r = run(task=8, method=method, seed=seed, chairs=chairs, llm=llm)
                except Infeasible:
                    infeasible += 1
                    continue
                ok += r.success
                times.append(r.execution.execution_time_s)
                failures.append(r.execution.failures)
            t, se = mean_se(times)
            print(f"{chairs} chair(s), {method}: success {ok}/{args.seeds} = "
                  f"{ok / args.seeds:.2f}; execution time {t:.1f} ± {se:.1f} s; "
                  f"failed actions per episode {statistics.fmean(failures):.2f}; "
                  f"no plan {infeasible}")


if __name__ == "__main__":
    main()
