"""Several diners at one table: planning time, success and each setting's rating.

Runs LLM-GROP in 2D with the user's preferences file (so no LLM call is made), for each
table and diner count, over several seeds: four diners in the packaged dining room, and
up to 24 objects in ``data/banquet_room.yaml`` (the same room with longer supply tables,
where that much tableware has room to wait). Prints, per case, the
planning time (median and max, LLM calls excluded), how many episodes placed every
object, and the automatic rater's score of each diner's setting (mean per diner, the
mean of each table's lowest setting).
Run: .venv/bin/python benchmarks/diners.py [--seeds 10] [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from common import parse_args

from llm_grop import BackendOptions, run
from llm_grop.arrangement.pipeline import ArrangeOptions
from llm_grop.arrangement.preferences import load_preference_file
from llm_grop.contract.serialize import arrangement_to_dict
from llm_grop.errors import LLMGropError
from llm_grop.evaluation import rate
from llm_grop.world.table import Table

DATA = Path(__file__).parent / "data"
SETTING = "a dinner plate, a dinner fork and a dinner knife"
BANQUET = str(DATA / "banquet_room.yaml")
CASES = (
    ("4 diners, round table of 1.2 m", None, "round:1.2",
     f"set the table for four with {SETTING}"),
    ("4 diners, 1.8 x 0.9 m table", None, "1.8x0.9", f"set the table for four with {SETTING}"),
    ("4 diners, round table of 1.2 m, banquet room", BANQUET, "round:1.2",
     f"set the table for four with {SETTING}"),
    ("4 diners, 1.8 x 0.9 m table, banquet room", BANQUET, "1.8x0.9",
     f"set the table for four with {SETTING}"),
    ("6 diners x 4 objects (24), 1.8 x 0.9 m table, banquet room", BANQUET, "1.8x0.9",
     f"set the table for six with {SETTING} and a water cup"),
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    args = parse_args(ap, {"seeds": 1})
    options = ArrangeOptions(preference_pool=load_preference_file(DATA / "preferences.yaml"))
    no_calls = BackendOptions(replay_path=str(DATA / "embedded_calls.jsonl"))
    for label, scene, table, request in CASES:
        planning, ratings, lowest, placed, errors = [], [], [], 0, []
        t0 = time.perf_counter()
        for seed in range(args.seeds):
            try:
                result = run(request, scene=scene, table=Table.parse(table), seed=seed,
                             llm="replay",
                             llm_options=no_calls, options=options)
            except LLMGropError as exc:
                errors.append(f"seed {seed}: {exc}")
                continue
            planning.append(1000 * result.planning_time_s)
            placed += result.success
            rating = rate(arrangement_to_dict(result.final))
            ratings.append([r.score for r in rating.diners])
            lowest.append(rating.score)
        wall = time.perf_counter() - t0
        print(f"{label} ({request!r}, {args.seeds} seeds, {wall:.0f} s):")
        if planning:
            print(f"  planning time: median {statistics.median(planning):.0f} ms, "
                  f"max {max(planning):.0f} ms")
            per_diner = [statistics.fmean(r[k] for r in ratings) for k in range(len(ratings[0]))]
            print(f"  every object placed: {placed}/{args.seeds}")
            print(f"  rating per diner's setting (mean): "
                  f"{', '.join(f'{v:.2f}' for v in per_diner)}; lowest setting, mean "
                  f"{statistics.fmean(lowest):.2f}, min {min(lowest)}")
        for e in errors:
            print(f"  {e}")


if __name__ == "__main__":
    main()
