"""What the catalog matcher reads a request into: objects mentioned, chunks it cannot
read, and the relations stated between parts (:mod:`llm_grop.language.matcher`)."""

from __future__ import annotations

from dataclasses import dataclass

from llm_grop.world.catalog import ObjectSpec


@dataclass(frozen=True)
class Unread:
    """A chunk of the request the matcher cannot account for, with the catalog names
    closest to it."""

    text: str
    suggestions: tuple[str, ...] = ()


@dataclass(frozen=True)
class Mention:
    """One object named in the request: its kind, how many (``None``: a plural without a
    number, "some strawberries"), and the token span ``[start, end)`` it was read from."""

    spec: ObjectSpec
    count: int | None
    start: int = 0
    end: int = 0


@dataclass
class Link:
    """A relation the request states: ``subject`` and ``reference`` are part indexes.

    ``kind`` says how the reference was given: ``"named"`` (an object follows the phrase),
    ``"pronoun"`` ("beside it"), ``"bare"`` ("on the left": none), ``"center"``. ``partner``
    is the other subject of "either side of"; ``distance_cm`` a stated gap; ``start`` and
    ``end`` the token span of the words that state it.
    """

    subject: int
    relation: str
    reference: int | None
    kind: str
    start: int
    end: int
    distance_cm: float | None = None
    partner: int | None = None
