"""Wall time of the geometric stage: LLM-guided layout plus M = 25 sampled configurations.

Two cases: the paper's Task 8 on a 0.9 x 0.6 m table (target: median <= 20 ms) and
15 objects on a 1.2 x 0.8 m table. Relations are fixed here (no LLM); every gap is 3 cm.
Run: .venv/bin/python benchmarks/sampler.py [--runs 20] [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from common import parse_args

from llm_grop.arrangement.geometry import guided_layout
from llm_grop.arrangement.sampling import sample_configurations, violations
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import Relation
from llm_grop.world.table import Table

GAP_M = 0.03

TASK8 = [
    ("dinner plate", "center", None),
    ("dinner fork", "to the left of", "dinner plate"),
    ("dinner knife", "to the right of", "dinner plate"),
    ("mug", "above and to the right of", "dinner plate"),
    ("mug lid", "on top of", "mug"),
]

FIFTEEN = [
    ("dinner plate", "center", None),
    ("dinner fork", "to the left of", "dinner plate"),
    ("salad fork", "to the left of", "dinner fork"),
    ("napkin", "to the left of", "salad fork"),
    ("dinner knife", "to the right of", "dinner plate"),
    ("soup spoon", "to the right of", "dinner knife"),
    ("teaspoon", "to the right of", "soup spoon"),
    ("butter knife", "above", "dinner plate"),
    ("bread plate", "above and to the left of", "dinner plate"),
    ("bread", "on top of", "bread plate"),
    ("water cup", "above and to the right of", "dinner plate"),
    ("wine glass", "to the right of", "water cup"),
    ("mug mat", "to the right of", "wine glass"),
    ("mug", "on top of", "mug mat"),
    ("mug lid", "on top of", "mug"),
]


def run(name: str, facts: list[tuple[str, str, str | None]], table: Table, runs: int) -> None:
    catalog = Catalog.load(use_env=False)
    names = list(dict.fromkeys(n for f in facts for n in (f[0], f[2]) if n is not None))
    items = []
    for n in names:
        spec = catalog.lookup(n)
        assert spec is not None, n
        items.append(Item(n, spec))
    relations = [Relation(*f) for f in facts]
    gaps = {r.key(): GAP_M for r in relations}
    times = []
    for seed in range(runs):
        start = time.perf_counter()
        layout = guided_layout(items, relations, gaps, table)
        configs = sample_configurations(items, layout, relations, table,
                                        np.random.default_rng(seed), m=25)
        times.append(time.perf_counter() - start)
        assert len(configs) == 25
        assert all(not violations(c, relations, table) for c in configs)
    print(f"{name}: {len(items)} objects on a {table.width} x {table.depth} m table, M=25: "
          f"median {1000 * statistics.median(times):.1f} ms, "
          f"min {1000 * min(times):.1f} ms, max {1000 * max(times):.1f} ms over {runs} runs")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    args = parse_args(ap, {"runs": 2})
    run("task 8", TASK8, Table(0.9, 0.6), args.runs)
    run("15 objects", FIFTEEN, Table(1.2, 0.8), args.runs)


if __name__ == "__main__":
    main()
