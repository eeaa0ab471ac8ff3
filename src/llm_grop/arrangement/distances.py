"""Template 2, the diner's-edge question, and the distance parser (paper §III-B).

The LLM is asked how many centimetres separate two related objects; the answer
is read as the **gap between the objects' edges** (see ``geometry``), as in the
authors' code. In the same style (:func:`edge_prompt`) it is asked how far the
setting's origin object goes from the table's edge nearest the diner; the answer
is read as the gap between that edge and the object's near edge, and when no
number can be read :data:`DEFAULT_EDGE_GAP_CM` is used. The answers are read by
:func:`llm_grop.language.distance.parse_distance_cm`.
"""

from __future__ import annotations

from llm_grop.arrangement.relations import asset, with_article
from llm_grop.language.distance import MAX_GAP_CM, parse_distance_cm
from llm_grop.world.relation import CENTER, STACKING, Relation

#: The gap used when an answer holds no readable distance, in centimetres
#: (the authors' default).
DEFAULT_GAP_CM = 5.0
#: The gap, centimetres, between the diner's edge of the table and the origin object's
#: near edge when the LLM's answer holds no readable distance (the same default as
#: :data:`DEFAULT_GAP_CM`: no etiquette is assumed for it).
DEFAULT_EDGE_GAP_CM = DEFAULT_GAP_CM


def template2_prompt(relation: Relation) -> str:
    """Template 2 for one relation: how many centimetres apart its two objects should be.

    Raises ``ValueError`` for ``center``, ``on top of`` and ``under``, which have no gap.
    """
    if relation.relation == CENTER or relation.relation in STACKING or relation.reference is None:
        raise ValueError(f"no distance is asked for {relation.relation!r}")
    a_subject = with_article(relation.subject)
    return asset("template2.txt").format(
        A_subject=a_subject[0].upper() + a_subject[1:], subject=relation.subject,
        relation=relation.relation, a_reference=with_article(relation.reference),
        reference=relation.reference).strip()


def edge_prompt(subject: str) -> str:
    """The Template 2-style question of how many centimetres from the diner's edge of the
    table the origin object ``subject`` goes."""
    a_subject = with_article(subject)
    return asset("edge.txt").format(A_subject=a_subject[0].upper() + a_subject[1:],
                                     subject=subject).strip()


def template2_grammar() -> str:
    """GBNF for "About N centimeters." or "N-M centimeters." (N, M of one or two digits)."""
    return asset("template2.gbnf")


def parse_distance_m(text: str, default_cm: float = DEFAULT_GAP_CM) -> tuple[float, bool]:
    """``(gap in metres, whether the default was used)`` for an answer to Template 2
    (or to :func:`edge_prompt`, with ``default_cm`` :data:`DEFAULT_EDGE_GAP_CM`)."""
    cm = parse_distance_cm(text)
    return ((default_cm if cm is None else cm) / 100.0, cm is None)


__all__ = ["DEFAULT_EDGE_GAP_CM", "DEFAULT_GAP_CM", "MAX_GAP_CM", "edge_prompt",
           "parse_distance_cm", "parse_distance_m", "template2_grammar", "template2_prompt"]
