"""Random collision-free placement on the table: the arrangement of the TPRA and GROP
baselines (paper §IV), which know no semantics.

As in the authors' code, each object's centre is drawn from a Gaussian of variance
:data:`VARIANCE_M2` per axis (std dev :data:`SIGMA_M`), truncated to :data:`TRUNCATION_M`
either side along each axis, around the centre of its diner's place
(:mod:`llm_grop.geometry.places`, in that place's frame): the part of the table in which
LLM-GROP arranges that diner's setting. One diner's place is the whole table, so the draw
is around the table's centre, where the authors root both the baselines and LLM-GROP. A
draw is redrawn while the object is not wholly on the table (a round one's too) or
overlaps one already placed (the sampler's footprint test, sizes inflated 5%). Nothing is
stacked: without relations nothing says what rests on what.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from llm_grop.arrangement.predicates import Footprint, clear_of, inside_table
from llm_grop.errors import BadInput, Infeasible
from llm_grop.geometry.places import Place, places
from llm_grop.settings import DEFAULTS
from llm_grop.world.arrangement import Configuration, Item, Placement
from llm_grop.world.table import Table

#: Variance, square metres, of each axis of the Gaussian an object's centre is drawn from
#: around its diner's place centre (the authors' ``N(0, 0.03 I)``).
VARIANCE_M2 = 0.03

#: That Gaussian's std dev per axis, metres (about 0.173 m).
SIGMA_M = math.sqrt(VARIANCE_M2)

#: The farthest, metres, an object's centre is drawn from its diner's place centre along
#: each of the place's axes (the authors' truncation): a draw beyond it is redrawn.
TRUNCATION_M = 0.225

#: Candidates drawn per object per try, all tested at once.
BATCH = 64

#: Tries per configuration before giving up.
MAX_TRIES = 50


def random_configurations(items: Sequence[Item], table: Table, rng: np.random.Generator,
                          m: int = DEFAULTS.m) -> tuple[Configuration, ...]:
    """``m`` configurations with every item drawn at random around its diner's place
    centre, on the table and without overlaps (see the module doc). An item's ``diner``
    is its seat's index in ``table.seats`` (``None``: the first). Raises
    :class:`Infeasible` when an item cannot lie on the table or a configuration is not
    found in :data:`MAX_TRIES` tries."""
    order = sorted(range(len(items)), key=lambda i: -Footprint.of_spec(items[i].spec).area)
    feet = [Footprint.of_spec(it.spec) for it in items]
    for i in order:
        # The centre is a convex top's roomiest spot: what does not fit there fits nowhere.
        if not inside_table(0.0, 0.0, feet[i], table):
            raise Infeasible(f"{items[i].name!r} does not fit on the {table.label}")
    seated = places(table, table.seats)
    for it in items:
        if (it.diner or 0) >= len(seated):
            raise BadInput(f"{it.name!r} belongs to diner {it.diner}, but the {table.label} "
                           f"seats {len(seated)}")
    place = [seated[it.diner or 0] for it in items]
    return tuple(_one(items, feet, place, order, table, rng) for _ in range(m))


def _one(items: Sequence[Item], feet: Sequence[Footprint], place: Sequence[Place],
         order: Sequence[int], table: Table, rng: np.random.Generator) -> Configuration:
    for _ in range(MAX_TRIES):
        xy: dict[int, tuple[float, float]] = {}
        for i in order:
            f = feet[i]
            u = rng.normal(0.0, SIGMA_M, BATCH)
            v = rng.normal(0.0, SIGMA_M, BATCH)
            # Rejecting the draws beyond the truncation leaves the truncated Gaussian.
            ok = (np.abs(u) <= TRUNCATION_M) & (np.abs(v) <= TRUNCATION_M)
            cx, cy = place[i].to_table(u, v)
            ok &= inside_table(cx, cy, f, table)
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
