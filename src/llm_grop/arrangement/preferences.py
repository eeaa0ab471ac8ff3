"""Symbolic relations a user states as preferences (paper §III-A: relations come from the
LLM or from the user).

Preferences are sentences in the paper's own phrasing ("the dinner fork to the left of
the dinner plate", "mug lid on top of mug"), read by the same reader as the LLM's answers.
They win over the LLM: an LLM relation about a pair the user spoke of is dropped, and so
is one that clingo finds inconsistent with the preferences. When the preferences relate
every requested object to the others (:func:`covers`), Template 1 is not asked at all. A
preference that states a distance ("the dinner fork 2 cm to the left of the dinner
plate") sets that gap, and Template 2 is asked only for the others.

A preference may also say how far an object goes from the diner's edge of the table
("the dinner plate 3 cm from the diner's edge"): that object becomes the origin of the
layout (:mod:`llm_grop.arrangement.geometry`) and the LLM is not asked for the distance.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Annotated

from pydantic import BaseModel, StringConstraints

from llm_grop.arrangement import consistency
from llm_grop.arrangement.distances import parse_distance_cm
from llm_grop.datafile import load_yaml_model
from llm_grop.errors import BadInput
from llm_grop.language.answer_reader import parse_relations
from llm_grop.language.distance import DASHES
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import DIRECTION, Choice, Relation
from llm_grop.world.request import items_from_names
from llm_grop.world.table import Table

#: "... from the diner's edge", "... from the near edge of the table", "... from the edge".
_EDGE = re.compile(r"\bfrom\s+the\s+(?:diner['’]?s\s+|near(?:est)?\s+)?edge\b", re.IGNORECASE)
#: A minus sign (any of the dashes) before a number, not inside a word or a range.
_NEGATIVE = re.compile(rf"(?<![\w.])[{DASHES}]\s*\d")


def is_edge_sentence(sentence: str) -> bool:
    """Whether ``sentence`` states a distance from the diner's edge of the table."""
    return _EDGE.search(sentence) is not None


def _edge_object(head: str, items: Sequence[Item], catalog: Catalog) -> tuple[Item, str] | None:
    """The requested item ``head`` names first, with the text after its name."""
    text = " " + re.sub(r"\s+", " ", head.lower()) + " "
    best: tuple[int, Item, str] | None = None
    phrases = [(it.name, it) for it in items]
    phrases += [(alias, it) for alias, kind in catalog.aliases().items() for it in items
                if it.kind == kind]
    for phrase, item in phrases:
        at = text.find(f" {phrase} ")
        if at < 0:
            at = text.find(f" {phrase}s ")
        if at < 0:
            continue
        rank = (at, -len(phrase))
        if best is None or rank < (best[0], -len(best[2])):
            best = (at, item, phrase)
    if best is None:
        return None
    at, item, phrase = best
    rest = text[at + len(phrase) + 1:]
    return item, rest


def read_edge_preferences(required: Sequence[str], pool: Sequence[str],
                          items: Sequence[Item], catalog: Catalog, table: Table
                          ) -> dict[str, float]:
    """The distance, metres, from the diner's edge of the table to the near edge of each
    object an edge sentence names (see :func:`is_edge_sentence`), by item name.

    ``required`` sentences must name a requested object (else :class:`BadInput`);
    ``pool`` sentences apply when their object is requested. Raises :class:`BadInput`
    for a sentence without a distance, a negative one, or one deeper than the table.
    """
    out: dict[str, float] = {}
    for required_one, sentence in [(True, s) for s in required] + [(False, s) for s in pool]:
        m = _EDGE.search(sentence)
        if m is None:
            continue
        param = PREFER if required_one else None
        found = _edge_object(sentence[:m.start()], items, catalog)
        if found is None:
            if required_one:
                raise _refused(param, sentence, "names no requested object "
                               f"({', '.join(i.name for i in items)})")
            continue
        item, rest = found
        if _NEGATIVE.search(rest):
            raise _refused(param, sentence, "a distance must not be negative")
        cm = parse_distance_cm(rest)
        if cm is None:
            raise _refused(param, sentence, "no distance from the edge, such as "
                           "'3 cm from the diner's edge'")
        if cm / 100 > table.depth:
            raise _refused(param, sentence, f"{cm:g} cm does not fit on the {table.label}")
        out.setdefault(item.name, cm / 100)
    return out


@dataclass(frozen=True)
class Preferences:
    """The relations stated preferences give (``source="preference"``, ``gap_m`` any
    distance they state), and their ambiguous ones ("the knife beside the plate")."""

    relations: tuple[Relation, ...] = ()
    choices: tuple[Choice, ...] = ()


#: The API parameter that holds the preferences a user states for one request.
PREFER = "preferences"


def _refused(param: str | None, sentence: str, why: str) -> BadInput:
    """The error for ``sentence``: naming ``param`` (:data:`PREFER`) for a stated
    preference, or as a preference of the pool (``param`` ``None``)."""
    if param is None:
        return BadInput(f"preference {sentence!r}: {why}")
    return BadInput(f"{sentence!r}: {why}", param=param)


def _with_gap(relation: Relation, sentence: str, param: str | None,
              learned_from: Sequence[str] = ()) -> Relation:
    """``relation`` as a preference, with the distance ``sentence`` states, if any; as a
    learned one when it was read off the example settings ``learned_from``."""
    # A numbered object's number ("the dinner fork 2") is part of its name, not a distance.
    said = sentence
    for name in sorted({relation.subject, relation.reference} - {None}, key=len, reverse=True):
        said = re.sub(rf"(?<![\w.]){re.escape(name)}(?![\w.])", " ", said, flags=re.I)
    if _NEGATIVE.search(said):
        raise _refused(param, sentence, "a distance must not be negative")
    cm = parse_distance_cm(said)
    return replace(relation, source="learned" if learned_from else "preference",
                   gap_m=None if cm is None else cm / 100, learned_from=tuple(learned_from))


def read_preferences(required: Sequence[str], pool: Sequence[str], items: Sequence[Item],
                     catalog: Catalog, learned: Mapping[str, Sequence[str]] | None = None
                     ) -> Preferences:
    """The relations of the ``required`` sentences (each must name requested objects, else
    :class:`BadInput`) and of those ``pool`` sentences whose objects are all requested. A
    pool sentence ``learned`` maps to the example settings it was read off gives learned
    relations (``source="learned"``).

    Raises :class:`BadInput` when the preferences contradict each other, or state a
    negative distance.
    """
    required = [s for s in required if not is_edge_sentence(s)]
    pool = [s for s in pool if not is_edge_sentence(s)]
    out: list[Relation] = []
    choices: list[Choice] = []
    for sentence in required:
        parsed = parse_relations(sentence, items, catalog)
        if not (parsed.relations or parsed.choices) or parsed.ignored:
            raise _refused(PREFER, sentence, "cannot read it as a relation between "
                           f"requested objects ({', '.join(i.name for i in items)})")
        out += [_with_gap(r, sentence, PREFER) for r in parsed.relations]
        choices += [_choice(c, sentence, PREFER) for c in parsed.choices]
    everything: tuple[Item, ...] | None = None
    for sentence in pool:
        parsed = parse_relations(sentence, items, catalog)
        if (parsed.relations or parsed.choices) and not parsed.ignored:
            seen = (learned or {}).get(sentence, ())
            out += [_with_gap(r, sentence, None, seen) for r in parsed.relations]
            choices += [_choice(c, sentence, None) for c in parsed.choices]
            continue
        # Not about the requested objects; it must still read as a relation at all.
        everything = everything or items_from_names(catalog.names(), catalog)
        read = parse_relations(sentence, everything, catalog)
        if not (read.relations or read.choices):
            raise BadInput(f"preferences: cannot read {sentence!r} as a relation between "
                           "catalog objects")
    return Preferences(combine((), out), tuple(choices))


def _choice(choice: Choice, sentence: str, param: str | None) -> Choice:
    return Choice(tuple(tuple(_with_gap(r, sentence, param) for r in option)
                        for option in choice.options), choice.words)


def combine(stated: Sequence[Relation], preferences: Sequence[Relation]
            ) -> tuple[Relation, ...]:
    """The relations the request ``stated`` and the ``preferences``, repeats dropped (the
    request's first). They have the same precedence; raises :class:`BadInput` naming
    where each came from when they contradict each other."""
    seen: set[tuple[str, str, str | None]] = set()
    unique = []
    for r in [*stated, *preferences]:
        if r.key() not in seen:
            seen.add(r.key())
            unique.append(r)
    conflict = consistency.check(unique).conflict
    if conflict:
        raise BadInput(contradiction(conflict))
    return tuple(unique)


_FROM = {"request": "the request", "preference": "a preference", "llm": "the LLM",
         "learned": "the examples"}


#: Who stated the relations that contradict each other, in the order a message names them.
_WHOSE = {"request": "the request's relations", "preference": "the preferences",
          "learned": "the examples"}


def contradiction(conflict: Sequence[Relation | Choice]) -> str:
    """The one-line message for stated relations that contradict each other (clingo's
    minimal conflict), each in the words it was stated in and saying where it came from."""
    sources = {c.options[0][0].source if isinstance(c, Choice) else c.source
               for c in conflict}
    whose = "preferences" if sources == {"preference"} else " and ".join(
        words for source, words in _WHOSE.items() if source in sources) \
        or "the stated relations"
    said = []
    for c in conflict:
        first = c.options[0][0] if isinstance(c, Choice) else c
        words = c.words if isinstance(c, Choice) else first.line
        said.append(f"{words or first.sentence()!r} ({_FROM.get(first.source, first.source)})")
    return f"{whose} contradict each other: {'; '.join(said)}"


def covers(preferences: Sequence[Relation], items: Sequence[Item]) -> bool:
    """Whether the preferences relate every requested object to every other, through one
    another: the ``items`` are one connected group when each relation joins its two
    objects. Mentioning each object is not enough: "the mug lid on top of the mug" beside
    "the dinner fork to the left of the dinner plate" says nothing of where the mug goes
    from the plate, so Template 1 must still be asked for that."""
    names = {i.name for i in items}
    if not preferences or not names:
        return False
    group = {next(iter(names))}
    grew = True
    while grew:
        grew = False
        for r in preferences:
            ends = {r.subject, r.reference}
            if ends & group and not ends <= group:
                group |= ends
                grew = True
    return names <= group


def merge(preferences: Sequence[Relation], llm: Sequence[Relation]
          ) -> tuple[tuple[Relation, ...], tuple[Relation, ...]]:
    """``(kept, overridden)``: the preferences, then every LLM relation that is about
    another pair and consistent with what is kept so far."""
    pairs = {frozenset((r.subject, r.reference)) for r in preferences}
    kept = list(preferences)
    overridden = []
    for r in llm:
        if frozenset((r.subject, r.reference)) in pairs \
                or consistency.check([*kept, r]).conflict:
            overridden.append(r)
        else:
            kept.append(r)
    return tuple(kept), tuple(overridden)


def stated_gaps(stated: Sequence[Relation], table: Table
                ) -> dict[tuple[str, str, str | None], float]:
    """The gaps, metres, that the request or the preferences state, by relation key.

    Raises :class:`BadInput` for a gap longer than the table along the axis the relation
    moves on (its width for "to the left of", its depth for "above", either for a
    diagonal).
    """
    out = {}
    for r in stated:
        if r.gap_m is None:
            continue
        dx, dy = DIRECTION.get(r.relation, (0, 0))
        room = min([table.width] * bool(dx) + [table.depth] * bool(dy) or
                   [max(table.width, table.depth)])
        if r.gap_m > room:
            raise BadInput(f"{_where(r)} {r.line or r.sentence()!r}: {100 * r.gap_m:g} cm "
                           f"does not fit on the {table.label}")
        out[r.key()] = r.gap_m
    return out


def _where(r: Relation) -> str:
    return "request:" if r.source == "request" else "preference"


class _PreferenceFile(BaseModel):
    preferences: list[Annotated[str, StringConstraints(strip_whitespace=True, min_length=1)]]


def load_preference_file(path: str | Path) -> tuple[str, ...]:
    """The sentences of a preferences file: YAML ``preferences: [sentence, ...]``."""
    where = f"preferences {path}"
    try:
        text = Path(path).read_bytes().decode("utf-8")
    except OSError as exc:
        raise BadInput(f"{where}: cannot read ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise BadInput(f"{where}: not UTF-8 (byte {exc.start})") from None
    doc = load_yaml_model(text, where, _PreferenceFile, "preferences", "preferences")
    return tuple(doc.preferences)
