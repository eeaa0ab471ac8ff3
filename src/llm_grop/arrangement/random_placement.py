"""Random collision-free placement on the table: the arrangement of the TPRA and GROP
baselines (paper §IV), which know no semantics.

Each object is drawn uniformly over the positions where it lies wholly on the table (a
round one's too), and redrawn while it overlaps one already placed (the sampler's
footprint test, sizes inflated 5%). Nothing is stacked: without relations nothing says
what rests on what.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from llm_grop.arrangement.predicates import Footprint, clear_of, inside_table
from llm_grop.errors import Infeasible
from llm_grop.world.arrangement import Configuration, Item, Placement
from llm_grop.world.table import Table

#: Candidates drawn per object per try, all tested at once.
BATCH = 64

#: Tries per configuration before giving up.
MAX_TRIES = 50


def random_configurations(items: Sequence[Item], table: Table, rng: np.random.Generator,
                          m: int = 25) -> tuple[Configuration, ...]:
    """``m`` configurations with every item placed uniformly at random without overlaps."""
    order = sorted(range(len(items)), key=lambda i: -Footprint.of_spec(items[i].spec).area)
    feet = [Footprint.of_spec(it.spec) for it in items]
    for i in order:
        if not inside_table(0.0, 0.0, feet[i], table):
            raise Infeasible(f"{items[i].name!r} does not fit on the {table.label}")
    return tuple(_one(items, feet, order, table, rng) for _ in range(m))


def _one(items: Sequence[Item], feet: Sequence[Footprint], order: Sequence[int], table: Table,
         rng: np.random.Generator) -> Configuration:
    for _ in range(MAX_TRIES):
        xy: dict[int, tuple[float, float]] = {}
        for i in order:
            f = feet[i]
            cx = rng.uniform(-(table.width / 2 - f.hx), table.width / 2 - f.hx, BATCH)
            cy = rng.uniform(-(table.depth / 2 - f.hy), table.depth / 2 - f.hy, BATCH)
            # Drawn over the bounding rectangle; on a round top, kept only on the circle.
            ok = inside_table(cx, cy, f, table)
            for j, (x, y) in xy.items():
                ok &= clear_of(cx, cy, f, x, y, feet[j])
            hits = np.flatnonzero(ok)
            if hits.size == 0:
                break
            xy[i] = (float(cx[hits[0]]), float(cy[hits[0]]))
        else:
            return Configuration(tuple(
                Placement(it.name, xy[i][0], xy[i][1], 0.0, it.spec.shape, it.spec.size, None,
                          it.kind, it.spec.height, it.diner) for i, it in enumerate(items)))
    raise Infeasible(f"could not place {len(items)} objects at random without overlaps on the "
                     f"{table.label} in {MAX_TRIES} tries")
