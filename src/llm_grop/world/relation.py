"""Symbolic spatial relations, named with the paper's phrases (the contract's names)."""

from __future__ import annotations

from dataclasses import dataclass

LEFT = "to the left of"
RIGHT = "to the right of"
ABOVE = "above"
BELOW = "below"
ABOVE_LEFT = "above and to the left of"
ABOVE_RIGHT = "above and to the right of"
BELOW_LEFT = "below and to the left of"
BELOW_RIGHT = "below and to the right of"
ON_TOP_OF = "on top of"
UNDER = "under"
CENTER = "center"

#: Every relation name, in the order Template 1 lists them.
RELATION_NAMES: tuple[str, ...] = (
    ABOVE, RIGHT, BELOW, LEFT, ABOVE_RIGHT, BELOW_RIGHT, BELOW_LEFT, ABOVE_LEFT,
    ON_TOP_OF, UNDER, CENTER,
)

#: The relation that holds the other way round: ``X r Y`` iff ``Y CONVERSE[r] X``.
CONVERSE: dict[str, str] = {
    LEFT: RIGHT, RIGHT: LEFT, ABOVE: BELOW, BELOW: ABOVE,
    ABOVE_LEFT: BELOW_RIGHT, BELOW_RIGHT: ABOVE_LEFT,
    ABOVE_RIGHT: BELOW_LEFT, BELOW_LEFT: ABOVE_RIGHT,
    ON_TOP_OF: UNDER, UNDER: ON_TOP_OF,
}

#: Unit direction of the subject from the reference in the table frame (+x right, +y above).
DIRECTION: dict[str, tuple[int, int]] = {
    LEFT: (-1, 0), RIGHT: (1, 0), ABOVE: (0, 1), BELOW: (0, -1),
    ABOVE_LEFT: (-1, 1), ABOVE_RIGHT: (1, 1), BELOW_LEFT: (-1, -1), BELOW_RIGHT: (1, -1),
    ON_TOP_OF: (0, 0), UNDER: (0, 0),
}

#: Relations that stack one object on another.
STACKING = frozenset({ON_TOP_OF, UNDER})

#: Where a relation came from: the LLM's answer, a preference the user stated
#: (``--prefer`` or a preferences file), or the request's own words ("a mug on a coaster").
SOURCES: tuple[str, ...] = ("llm", "preference", "request")


@dataclass(frozen=True)
class Relation:
    """``subject relation reference``, e.g. dinner fork / to the left of / dinner plate.

    ``reference`` is ``None`` for ``center`` (the subject is at the table's centre).
    ``line`` is the LLM's text the relation was read from, or ``""`` when stated by a user.
    ``source`` is one of :data:`SOURCES`.
    """

    subject: str
    relation: str
    reference: str | None
    line: str = ""
    source: str = "llm"

    def __post_init__(self) -> None:
        if self.relation not in RELATION_NAMES:
            raise ValueError(f"unknown relation {self.relation!r}")
        if (self.relation == CENTER) != (self.reference is None):
            raise ValueError("'center' takes no reference; every other relation needs one")
        if self.source not in SOURCES:
            raise ValueError(f"unknown relation source {self.source!r}")

    def sentence(self) -> str:
        """The relation as a Template 1 line: ``Place the X to the left of the Y.``"""
        if self.relation == CENTER:
            return f"Place the {self.subject} in the center of the table."
        return f"Place the {self.subject} {self.relation} the {self.reference}."

    def converse(self) -> Relation:
        """The same fact said from the reference's side (not defined for ``center``)."""
        if self.reference is None:
            raise ValueError("'center' has no converse")
        return Relation(self.reference, CONVERSE[self.relation], self.subject, self.line,
                        self.source)

    def key(self) -> tuple[str, str, str | None]:
        """``(subject, relation, reference)`` without the source line."""
        return (self.subject, self.relation, self.reference)
