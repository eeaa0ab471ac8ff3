"""Rating a table set for several diners: each diner's setting in that diner's own frame.

A diner's objects (``diner`` in the JSON) are turned into their place's frame
(:mod:`llm_grop.geometry.places`: +y the way the diner faces, the diner at the place's
-y edge) and rated there by the same rules as a single setting, with the whole table's
outline for the on-table checks. The table's score is the lowest setting's.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence

from shapely import affinity

from llm_grop.contract.models import ArrangementDoc, ObjectDoc, TableDoc
from llm_grop.contract.serialize import table_of
from llm_grop.errors import BadInput
from llm_grop.geometry.places import outline, places
from llm_grop.world.angles import wrap_angle


def several_diners(doc: ArrangementDoc) -> bool:
    """Whether ``doc`` lists its diners' seats (each setting is then rated apart, in its
    diner's frame, even a single diner seated elsewhere than the -y edge)."""
    return bool(doc.table.diners)


def per_diner_kinds(kinds: Sequence[str] | None, diners: int,
                    assigned: Sequence[tuple[str, int | None]] | None = None
                    ) -> list[tuple[str, ...] | None]:
    """The kinds each diner should have: from ``assigned`` ``(kind, diner)`` pairs (a
    parsed request), else an equal share of ``kinds``; raises :class:`BadInput` when
    ``kinds`` do not split evenly."""
    if assigned is not None:
        return [tuple(k for k, d in assigned if d == i) for i in range(diners)]
    if kinds is None:
        return [None] * diners
    counts = Counter(kinds)
    uneven = [k for k, n in counts.items() if n % diners]
    if uneven:
        raise BadInput(f"requested: {counts[uneven[0]]} x {uneven[0]} do not split evenly "
                       f"among {diners} diners")
    share: list[str] = []
    for kind in dict.fromkeys(kinds):
        share += [kind] * (counts[kind] // diners)
    return [tuple(share)] * diners


def diner_docs(doc: ArrangementDoc, where: str = "arrangement"
               ) -> list[tuple[ArrangementDoc, object]]:
    """Each diner's setting as an arrangement document in their place's frame, with the
    whole table's outline in that frame."""
    table = table_of(doc, where)
    top = outline(table)
    out = []
    for k, place in enumerate(places(table, table.seats)):
        c, s = math.cos(place.yaw), math.sin(place.yaw)
        objects = []
        for o in doc.objects:
            if o.diner != k:
                continue
            dx, dy = o.x - place.origin[0], o.y - place.origin[1]
            objects.append(ObjectDoc.model_validate({
                **o.model_dump(exclude_unset=True), "x": c * dx + s * dy,
                "y": -s * dx + c * dy, "yaw": wrap_angle(o.yaw - place.yaw)}))
        local = affinity.rotate(affinity.translate(top, -place.origin[0], -place.origin[1]),
                                -place.yaw, origin=(0.0, 0.0), use_radians=True)
        sub = ArrangementDoc(request="", table=TableDoc(size=place.box.size), objects=objects)
        out.append((sub, local))
    return out

