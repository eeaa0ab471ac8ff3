"""Example table settings, read for learning a person's style (:mod:`.learning`).

An example is a table setting as the contract writes it: an arrangement JSON, or a run
JSON whose ``final`` holds where the objects really ended up. Only its geometry is read
(each object's place, footprint and ``on``); its ``relations``, if any, are not, since a
setting a person made has none and the geometry is what they did.

Each diner's setting is one :class:`Observation`, read in that diner's place frame
(:func:`~llm_grop.arrangement.diners.in_place_frames`), so that "to the left of" is the
diner's left wherever they sit, and with its objects in the names a one-diner request
would give them (the second diner's "dinner plate 2" is their "dinner plate"). Objects
shared by several diners (``diner`` null at a table that seats several) belong to no one's
setting and are left out, with a warning; so are objects a run left tipped over.

An example that is not a table setting (not JSON, no objects, an unknown kind, an object
off the table or resting on an object the example does not hold) is refused with one
:class:`~llm_grop.errors.BadInput` line naming it. Lengths in metres.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from llm_grop.arrangement.diners import in_place_frames
from llm_grop.arrangement.fidelity import axis_gaps_m
from llm_grop.arrangement.predicates import Footprint, inside_table, pair_relation_holds
from llm_grop.contract.serialize import arrangement_from_dict, read_arrangement_file
from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Item, Placement
from llm_grop.world.catalog import Catalog, ObjectSpec, instance_kind
from llm_grop.world.relation import MEANINGS, ON_TOP_OF, UNDER
from llm_grop.world.request import items_from_names
from llm_grop.world.table import Table

#: How far, metres, an object's footprint may reach beyond the table top and still be on
#: it: the contract's JSON rounds positions to 0.1 mm, and a run's ``final`` is where the
#: simulator left an object, which may overhang the edge by a hair.
OFF_TABLE_SLACK_M = 0.002


@dataclass(frozen=True)
class Observation:
    """One diner's setting in one example.

    ``source`` names the example (its file, or ``example N`` for a document given in
    Python) and, at a table that seats several, the diner (``a.json (diner 2)``).
    ``items`` are the setting's objects named as a one-diner request names them;
    ``placements`` are where they are, in the same order and names, in the diner's
    place frame (metres, +x to the diner's right, +y away from them; ``on`` renamed
    too). ``place`` is the diner's place as a table centred on that frame: its -y edge
    is the diner's edge of the table.
    """

    source: str
    items: tuple[Item, ...]
    placements: tuple[Placement, ...]
    place: Table


@dataclass(frozen=True)
class Example:
    """What one example gives: a setting per diner who has objects, and the warnings
    about what was left out of them."""

    observations: tuple[Observation, ...]
    warnings: tuple[str, ...] = ()


def read_example_file(path: str | Path, catalog: Catalog) -> Example:
    """The example in the arrangement or run JSON file ``path`` (see the module doc)."""
    data, _, where = read_arrangement_file(Path(path))
    return read_example(data, catalog, where=where, source=str(path))


def read_example(data: Mapping[str, Any], catalog: Catalog, *, where: str = "example",
                 source: str | None = None) -> Example:
    """The example in ``data``, an arrangement JSON as parsed (a run JSON's ``final``).

    ``where`` names it in error messages, ``source`` in the observations (default:
    ``where``). Raises :class:`BadInput` for a document that is not a table setting.
    """
    source = where if source is None else source
    objects = data.get("objects")
    if isinstance(objects, list) and not objects:
        raise BadInput(f"{where}: no objects; an example is a table setting")
    arrangement = arrangement_from_dict(_with_catalog_sizes(data, catalog), where)
    table = arrangement.table
    placements = arrangement.placements
    names = [p.name for p in placements]
    specs: dict[str, ObjectSpec] = {}
    for i, p in enumerate(placements):
        at = f"{where}: objects[{i}] ({p.name!r})"
        if names.count(p.name) > 1:
            raise BadInput(f"{at}: the name is used twice")
        specs[p.name] = catalog.resolve(instance_kind(p.kind or p.name), at)
        if p.on is not None and p.on not in names:
            raise BadInput(f"{at}.on: {p.on!r} is not an object of the example")
        if not bool(inside_table(p.x, p.y, Footprint.of_placement(p), table,
                                 -OFF_TABLE_SLACK_M)):
            raise BadInput(f"{at}: lies off the {table.label} (centre at "
                           f"({p.x:+.3f}, {p.y:+.3f}) m)")
    warnings: list[str] = []
    several = len(table.seats) > 1
    shared = [p.name for p in placements if several and p.diner is None]
    tipped = [p.name for p in placements if not p.upright]
    if shared:
        warnings.append(f"{where}: left out {', '.join(shared)}: shared by the diners, in "
                        "no one's setting")
    if tipped:
        warnings.append(f"{where}: left out {', '.join(tipped)}: tipped over")
    kept = [p for p in placements if p.name not in shared and p.name not in tipped]
    out = []
    for k, (place, local) in enumerate(in_place_frames(kept, table)):
        if not local:
            continue
        label = f"{source} (diner {k + 1})" if several else source
        out.append(_observation(label, local, specs, place.box, catalog))
    if not out:
        raise BadInput(f"{where}: no object is left to learn from")
    return Example(tuple(out), tuple(warnings))


def _observation(source: str, local: Sequence[Placement], specs: Mapping[str, ObjectSpec],
                 place: Table, catalog: Catalog) -> Observation:
    """One diner's placements (place frame) as an observation in one-diner names."""
    items = items_from_names([specs[p.name].name for p in local], catalog)
    # items_from_names numbers instances of a kind in the order given, so the k-th
    # object of a kind here is the k-th item of that kind.
    rename: dict[str, str] = {}
    for kind in dict.fromkeys(specs[p.name].name for p in local):
        mine = [p.name for p in local if specs[p.name].name == kind]
        theirs = [it.name for it in items if it.kind == kind]
        rename |= dict(zip(mine, theirs, strict=True))
    placements = tuple(replace(p, name=rename[p.name], kind=specs[p.name].name,
                               on=rename.get(p.on) if p.on is not None else None,
                               diner=None)
                       for p in local)
    return Observation(source, items, placements, place)


def _with_catalog_sizes(data: Mapping[str, Any], catalog: Catalog) -> Mapping[str, Any]:
    """``data`` with each object's ``shape`` and ``size`` filled in from the catalog where
    another system left them out (as the rater reads such a file); the rest unchanged."""
    objects = data.get("objects")
    if not isinstance(objects, list):
        return data
    filled: list[Any] = []
    for o in objects:
        if isinstance(o, dict) and ("size" not in o or "shape" not in o):
            name = o.get("kind") or o.get("name")
            spec = catalog.lookup(instance_kind(name)) if isinstance(name, str) else None
            if spec is not None:
                o = {"shape": spec.shape, "size": list(spec.size)} | o
        filled.append(o)
    return {**data, "objects": filled}


#: The relations read from where two objects lie (all but stacking, read from ``on``, and
#: ``center``, which is about the table, not a pair).
_LYING = tuple(m.name for m in MEANINGS.values() if m.reference and m.rests is None)


def relation_between(s: Placement, r: Placement) -> str | None:
    """The relation ``s`` (subject) keeps to ``r`` (reference) where they lie: ``on top of``
    or ``under`` when one rests on the other (``on``), else the one relation of
    ``relations.yaml`` whose axis states hold; ``None`` when they overlap on both axes
    without resting on each other."""
    if s.on == r.name:
        return ON_TOP_OF
    if r.on == s.name:
        return UNDER
    fs, fr = Footprint.of_placement(s), Footprint.of_placement(r)
    for name in _LYING:
        if bool(pair_relation_holds(name, s.x, s.y, fs, r.x, r.y, fr)):
            return name
    return None


def observed_gap_m(relation: str, s: Placement, r: Placement) -> float:
    """The gap, metres, between ``s`` and ``r`` for ``relation`` (not stacking), edge to
    edge as the layout sets it. A diagonal's two axes may differ; of one gap for both (as
    the layout sets it), their mean is the one whose worst error on either axis (the
    fidelity's measure) is smallest."""
    fs, fr = Footprint.of_placement(s), Footprint.of_placement(r)
    gaps = axis_gaps_m(relation, s.x, s.y, fs, r.x, r.y, fr)
    return float(np.mean([float(g) for g in gaps]))


def box_distance_m(a: Placement, b: Placement) -> float:
    """The distance, metres, between two footprints' bounding boxes (0 where they meet)."""
    fa, fb = Footprint.of_placement(a), Footprint.of_placement(b)
    gx = max(abs(a.x - b.x) - fa.hx - fb.hx, 0.0)
    gy = max(abs(a.y - b.y) - fa.hy - fb.hy, 0.0)
    return math.hypot(gx, gy)
