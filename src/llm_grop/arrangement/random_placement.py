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

**When the authors' box cannot hold the objects.** The authors' box (centres within
±0.225 m) holds the paper's settings but not, say, 20 objects. The rule: a configuration
is drawn in the authors' box; when :data:`MAX_TRIES` tries find none there, that
configuration and every later one of the call are drawn in the **grown box** instead:
each diner's box grows, along each of its place's axes, to the place's own half-extent
(the diner's share of the table; the whole top for one diner) where that is larger than
0.225 m, and its Gaussian grows with it (std dev still :data:`SIGMA_M` /
:data:`TRUNCATION_M` of the half-extent), the authors' shape stretched. Only a call the
authors' box could not serve changes, so every arrangement the authors' box holds is drawn
exactly as before (the same numbers from the same seed); the grown draws come from the
same random stream, so they too are the same for the same seed. When the grown box holds
no configuration either in :data:`MAX_TRIES` tries, the call raises :class:`Infeasible`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

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

#: Tries per configuration before giving up (in the authors' box, then in the grown one).
MAX_TRIES = 50


@dataclass(frozen=True)
class DrawBox:
    """Where an object's centre is drawn, in its diner's place frame: a Gaussian of std dev
    ``sigma_m`` along each axis ``(u, v)``, truncated to ``half_m`` either side; metres."""

    sigma_m: tuple[float, float]
    half_m: tuple[float, float]


#: The authors' box: ``N(0, 0.03 I)`` truncated to ±0.225 m along both axes.
AUTHORS_BOX = DrawBox((SIGMA_M, SIGMA_M), (TRUNCATION_M, TRUNCATION_M))


#: Where the baselines draw: ``authors``, the authors' box (grown when it cannot hold the
#: objects); ``place``, each diner's whole place from the start.
DrawBoxChoice = Literal["authors", "place"]


def grown_box(place: Place) -> DrawBox:
    """The box a diner's draws grow to when the authors' box cannot hold the objects: along
    each axis, ``place``'s half-extent where that is larger than :data:`TRUNCATION_M`, with
    the Gaussian's std dev scaled by the same factor (see the module doc)."""
    half = (max(TRUNCATION_M, place.box.width / 2), max(TRUNCATION_M, place.box.depth / 2))
    return DrawBox((SIGMA_M * half[0] / TRUNCATION_M, SIGMA_M * half[1] / TRUNCATION_M), half)


def random_configurations(items: Sequence[Item], table: Table, rng: np.random.Generator,
                          m: int = DEFAULTS.m, *, box: DrawBoxChoice = "authors"
                          ) -> tuple[Configuration, ...]:
    """``m`` configurations with every item drawn at random around its diner's place
    centre, on the table and without overlaps, in the authors' box or, when that cannot
    hold the items, in the grown box (see the module doc); ``box="place"`` draws in the
    grown box from the start. An item's ``diner`` is its
    seat's index in ``table.seats`` (``None``: the first). Raises :class:`Infeasible` when
    an item cannot lie on the table or a configuration is not found in either box."""
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
    authors = [AUTHORS_BOX] * len(items)
    grown = [grown_box(p) for p in place]
    boxes = authors if box == "authors" else grown
    out = []
    for _ in range(m):
        found = _one(items, feet, place, boxes, order, table, rng)
        if found is None and boxes is authors and grown != authors:
            boxes = grown  # this configuration and every later one of the call
            found = _one(items, feet, place, boxes, order, table, rng)
        if found is None:
            also = ", nor in each diner's whole place" if boxes is grown else ""
            raise Infeasible(f"could not place {len(items)} objects at random without "
                             f"overlaps on the {table.label} in {MAX_TRIES} tries{also}")
        out.append(found)
    return tuple(out)


def _one(items: Sequence[Item], feet: Sequence[Footprint], place: Sequence[Place],
         boxes: Sequence[DrawBox], order: Sequence[int], table: Table,
         rng: np.random.Generator) -> Configuration | None:
    """One configuration drawn in ``boxes`` (one per item), or ``None`` after
    :data:`MAX_TRIES` tries."""
    for _ in range(MAX_TRIES):
        xy: dict[int, tuple[float, float]] = {}
        for i in order:
            f, box = feet[i], boxes[i]
            u = rng.normal(0.0, box.sigma_m[0], BATCH)
            v = rng.normal(0.0, box.sigma_m[1], BATCH)
            # Rejecting the draws beyond the truncation leaves the truncated Gaussian.
            ok = (np.abs(u) <= box.half_m[0]) & (np.abs(v) <= box.half_m[1])
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
    return None
