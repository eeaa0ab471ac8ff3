"""Planning time of the task-motion planner (paper §III-C), LLM calls excluded.

* Task 8 (5 objects), LLM-GROP, M = 25, 1 chair: median and p95 over 20 seeds, with the
  embedded model's recorded answers replayed (their time is not counted).
* 10 and 20 objects, GROP (random arrangements, no LLM), M = 25, on a 1.8 x 0.9 m table.
Planning time covers sampling the M configurations, the standing positions, the cost-to-go
fields, utility over all configurations, the object order and the OMPL paths.
Run: .venv/bin/python benchmarks/planning_time.py [--seeds 20] [--quick]
"""

from __future__ import annotations

import argparse
from dataclasses import replace

from common import median_p95, parse_args, replay_llm

from llm_grop.api import run
from llm_grop.files.scene_file import load_scene

TEN = ("set the table with a dinner plate, a bread plate, a dinner fork, a salad fork, "
       "a dinner knife, a soup spoon, a water cup, a mug, a mug mat and a napkin")
TWENTY = ("set the table with a dinner plate, a bread plate, a salad plate, two dinner forks, "
          "a salad fork, two dinner knives, a butter knife, a soup spoon, two teaspoons, "
          "a water cup, a wine glass, a mug, a mug mat, a mug lid, a strawberry, bread "
          "and a napkin")


def _big_table_scene():  # type: ignore[no-untyped-def]
    scene = load_scene()
    target = scene.target_table
    big = replace(target, box=replace(target.box, width=1.8, depth=0.9))
    return replace(scene, tables=tuple(big if t.name == target.name else t
                                       for t in scene.tables))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    args = parse_args(ap, {"seeds": 1})
    llm = replay_llm()
    times = []
    for seed in range(args.seeds):
        r = run(task=8, method="llm-grop", seed=seed, chairs=1, llm=llm)
        times.append(r.planning_time_s * 1000)
    med, p95 = median_p95(times)
    print(f"Task 8, LLM-GROP, M=25: median {med:.1f} ms, p95 {p95:.1f} ms "
          f"({args.seeds} seeds; target <= 50 ms)")
    scene = _big_table_scene()
    for label, request in (("10 objects", TEN), ("20 objects", TWENTY)):
        times = []
        for seed in range(args.seeds):
            r = run(request, method="grop", scene=scene, seed=seed, chairs=1)
            times.append(r.planning_time_s * 1000)
        med, p95 = median_p95(times)
        print(f"{label}, GROP, M=25, 1.8 x 0.9 m table: median {med:.1f} ms, "
              f"p95 {p95:.1f} ms ({args.seeds} seeds)")


if __name__ == "__main__":
    main()
