"""How a learned preference is said (issue 42): in the paper's phrasing, checked by reading
it back with the preference reader (:mod:`.preferences`), so that what is learned is
exactly what ``--preferences`` reads. Lengths in centimetres."""

from __future__ import annotations

import math
from collections.abc import Sequence

from llm_grop.arrangement.preferences import read_preferences
from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog


def phrase(subject: str, relation: str, reference: str, gap_cm: float | None,
           items: Sequence[Item], catalog: Catalog) -> str | None:
    """The preference sentence of ``subject relation reference`` with ``gap_cm``
    (centimetres; ``None``: no distance) that the preference reader reads back exactly
    over ``items``; ``None`` when no phrasing does."""
    if gap_cm is None:
        phrasings = [f"the {subject} {relation} the {reference}"]
    else:
        # The paper's phrasing; the other where a number after the subject's name would
        # read as part of a name ("the dinner fork 2 cm ..." beside a "dinner fork 2").
        phrasings = [f"the {subject} {gap_cm:g} cm {relation} the {reference}",
                     f"the {subject} {relation} the {reference}, {gap_cm:g} cm apart"]
    for sentence in phrasings:
        try:
            read = read_preferences([sentence], [], items, catalog).relations
        except BadInput:
            continue
        got = [(r.subject, r.relation, r.reference) for r in read]
        if got == [(subject, relation, reference)] and (gap_cm is None or (
                read[0].gap_m is not None and math.isclose(read[0].gap_m, gap_cm / 100))):
            return sentence
    return None


def round_cm(value_cm: float) -> float:
    """``value_cm`` (centimetres) rounded to a millimetre, as sentences and comments say
    it."""
    return round(value_cm, 1) + 0.0
