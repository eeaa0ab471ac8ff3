"""Symbolic relations a user states as preferences (paper §III-A: relations come from the
LLM or from the user).

Preferences are sentences in the paper's own phrasing ("the dinner fork to the left of
the dinner plate", "mug lid on top of mug"), read by the same reader as the LLM's answers.
They win over the LLM: an LLM relation about a pair the user spoke of is dropped, and so
is one that clingo finds inconsistent with the preferences. When the preferences mention
every requested object, Template 1 is not asked at all. A preference that states a
distance ("the dinner fork 2 cm to the left of the dinner plate") sets that gap, and
Template 2 is asked only for the others.

A preference may also say how far an object goes from the diner's edge of the table
("the dinner plate 3 cm from the diner's edge"): that object becomes the origin of the
layout (:mod:`llm_grop.arrangement.geometry`) and the LLM is not asked for the distance.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Annotated

from pydantic import BaseModel, StringConstraints

from llm_grop.arrangement import consistency
from llm_grop.arrangement.distances import parse_distance_cm, parse_distance_m
from llm_grop.arrangement.relations import parse_relations
from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.datafile import load_yaml_model
from llm_grop.world.relation import Relation
from llm_grop.world.request import items_from_names
from llm_grop.world.table import Table

#: "... from the diner's edge", "... from the near edge of the table", "... from the edge".
_EDGE = re.compile(r"\bfrom\s+the\s+(?:diner['’]?s\s+|near(?:est)?\s+)?edge\b", re.IGNORECASE)


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
        where = "--prefer" if required_one else "preferences"
        found = _edge_object(sentence[:m.start()], items, catalog)
        if found is None:
            if required_one:
                raise BadInput(f"--prefer: {sentence!r} names no requested object "
                               f"({', '.join(i.name for i in items)})")
            continue
        item, rest = found
        if re.search(r"(?<![\w.])[-−]\s*\d", rest):
            raise BadInput(f"{where} {sentence!r}: a distance must not be negative")
        cm = parse_distance_cm(rest)
        if cm is None:
            raise BadInput(f"{where} {sentence!r}: no distance from the edge, such as "
                           "'3 cm from the diner's edge'")
        if cm / 100 > table.depth:
            raise BadInput(f"{where} {sentence!r}: {cm:g} cm does not fit on the "
                           f"{table.label}")
        out.setdefault(item.name, cm / 100)
    return out


def read_preferences(required: Sequence[str], pool: Sequence[str], items: Sequence[Item],
                     catalog: Catalog) -> tuple[Relation, ...]:
    """The relations of the ``required`` sentences (each must name requested objects, else
    :class:`BadInput`) and of those ``pool`` sentences whose objects are all requested.

    Raises :class:`BadInput` when the preferences contradict each other.
    """
    required = [s for s in required if not is_edge_sentence(s)]
    pool = [s for s in pool if not is_edge_sentence(s)]
    out: list[Relation] = []
    for sentence in required:
        parsed = parse_relations(sentence, items, catalog)
        if not parsed.relations or parsed.ignored:
            raise BadInput(f"--prefer: cannot read {sentence!r} as a relation between "
                           f"requested objects ({', '.join(i.name for i in items)})")
        out += parsed.relations
    everything: tuple[Item, ...] | None = None
    for sentence in pool:
        parsed = parse_relations(sentence, items, catalog)
        if parsed.relations and not parsed.ignored:
            out += parsed.relations
            continue
        # Not about the requested objects; it must still read as a relation at all.
        everything = everything or items_from_names(catalog.names(), catalog)
        if not parse_relations(sentence, everything, catalog).relations:
            raise BadInput(f"preferences: cannot read {sentence!r} as a relation between "
                           "catalog objects")
    return combine((), [replace(r, source="preference") for r in out])


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
        sources = {r.source for r in conflict}
        whose = "preferences" if sources == {"preference"} else \
            "the request's relations" if sources == {"request"} else \
            "the request's relations and the preferences"
        lines = "; ".join(f"{r.line or r.sentence()} ({_FROM[r.source]})" for r in conflict)
        raise BadInput(f"{whose} contradict each other: {lines}")
    return tuple(unique)


_FROM = {"request": "from the request", "preference": "a preference", "llm": "the LLM"}


def covers(preferences: Sequence[Relation], items: Sequence[Item]) -> bool:
    """Whether every requested object is mentioned by some preference."""
    named = {r.subject for r in preferences} | {r.reference for r in preferences}
    return bool(preferences) and all(i.name in named for i in items)


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


def stated_gaps(preferences: Sequence[Relation], table: Table
                ) -> dict[tuple[str, str, str | None], float]:
    """The gaps, metres, that preferences state in their sentences, by relation key.

    Raises :class:`BadInput` for a negative gap or one wider than the table.
    """
    out = {}
    for r in preferences:
        line = r.line or ""
        if re.search(r"(?<![\w.])-\s*\d", line):
            raise BadInput(f"preference {line!r}: a distance must not be negative")
        gap_m, defaulted = parse_distance_m(line)
        if defaulted:
            continue
        if gap_m > max(table.width, table.depth):
            raise BadInput(f"preference {line!r}: {100 * gap_m:g} cm does not fit on the "
                           f"{table.label}")
        out[r.key()] = gap_m
    return out


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
