"""A request as the pipeline takes it: the catalog items it asks for, in order, for how
many diners, the relations it states, and how it was read.

Reading a request's words is :mod:`llm_grop.language`; this module holds the record it
produces and the numbering of items ("dinner fork", "dinner fork 2"), which tasks and tests
use too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog, ObjectSpec
from llm_grop.world.llmlog import CallRecord
from llm_grop.world.relation import Choice, Relation

#: Most diners one request may set the table for.
MAX_DINERS = 12
#: Most instances of one object a request may ask for (per diner).
MAX_COUNT = 12
#: Most objects one request may ask for (all kinds and diners together).
MAX_OBJECTS = 30
#: Longest request read, in characters: a request is a sentence or two, and reading
#: (and an LLM prompt built from it) must stay cheap.
MAX_REQUEST_CHARS = 2000


@dataclass(frozen=True)
class Request:
    """A user's request: its ``text``, the catalog ``items`` it asks for, in order, and
    how many ``diners`` it sets the table for (the items are then every diner's, each
    with its ``diner`` index). Each item says where it came from (``Item.source``,
    ``Item.words``).

    ``relations`` are those the request states between its objects (first diner's names;
    ``source="request"``, ``line`` the request's words, ``gap_m`` a stated distance);
    ``choices`` the ambiguous ones ("the knife beside the plate"), which the arrangement
    decides. ``source`` says how it was read: ``"catalog"`` (the matcher alone, or the
    paper's Table I) or ``"llm"`` (an LLM read the whole request); ``calls`` are the
    LLM calls that read it; ``warnings`` what the reading could not honour or guessed;
    ``guessed`` the kinds the LLM chose that the request does not name (or not how many).
    """

    text: str
    items: tuple[Item, ...]
    diners: int = 1
    relations: tuple[Relation, ...] = ()
    source: str = "catalog"
    calls: tuple[CallRecord, ...] = ()
    warnings: tuple[str, ...] = ()
    choices: tuple[Choice, ...] = ()
    guessed: tuple[str, ...] = ()


@dataclass(frozen=True)
class Wanted:
    """``count`` instances of catalog kind ``spec``, with where they came from (see
    :class:`~llm_grop.world.arrangement.Item`)."""

    spec: ObjectSpec
    count: int
    source: str = "request"
    words: str = ""


def for_diners(items: Sequence[Item], diners: int) -> tuple[Item, ...]:
    """One setting of ``items`` for each of ``diners`` diners, numbered across them
    (the second diner's "dinner plate" is "dinner plate 2"); one diner: ``items`` as
    they are."""
    if diners == 1:
        return tuple(items)
    per_kind: dict[str, int] = {}
    for it in items:
        per_kind[it.kind] = per_kind.get(it.kind, 0) + 1
    total = len(items) * diners
    if total > MAX_OBJECTS:
        raise BadInput(f"request: {diners} diners x {len(items)} objects is {total}; "
                       f"at most {MAX_OBJECTS} objects in all")
    out = []
    for d in range(diners):
        seen: dict[str, int] = {}
        for it in items:
            seen[it.kind] = seen.get(it.kind, 0) + 1
            k = d * per_kind[it.kind] + seen[it.kind]
            out.append(Item(it.kind if k == 1 else f"{it.kind} {k}", it.spec, d, it.source,
                            it.words))
    return tuple(out)


def number_items(wanted: Sequence[Wanted]) -> tuple[tuple[Item, ...], list[list[str]]]:
    """Numbered items, grouped by kind in order of first mention, and the item names each
    entry of ``wanted`` stands for ("a fork, a plate and another fork": dinner fork, dinner
    fork 2, dinner plate; the third entry stands for "dinner fork 2").

    Raises :class:`BadInput` for more than :data:`MAX_OBJECTS` objects in all.
    """
    counts: dict[str, int] = {}
    names: list[list[str]] = []
    for w in wanted:
        done = counts.get(w.spec.name, 0)
        names.append([w.spec.name if k == 1 else f"{w.spec.name} {k}"
                      for k in range(done + 1, done + w.count + 1)])
        counts[w.spec.name] = done + w.count
    total = sum(counts.values())
    if total > MAX_OBJECTS:
        raise BadInput(f"request: {total} objects is too many; at most {MAX_OBJECTS}")
    by_name = {n: w for w, ns in zip(wanted, names, strict=True) for n in ns}
    items: list[Item] = []
    for kind, count in counts.items():
        for k in range(1, count + 1):
            name = kind if k == 1 else f"{kind} {k}"
            w = by_name[name]
            items.append(Item(name, w.spec, None, w.source, w.words))
    return tuple(items), names


def items_from_names(names: Sequence[str], catalog: Catalog, where: str = "objects"
                     ) -> tuple[Item, ...]:
    """Items for a list of object names (e.g. a task's); repeating a name adds an instance.

    Each name must be a single catalog name, synonym or plural; an unknown one raises
    :class:`UnknownObject` naming ``where``.
    """
    wanted = [Wanted(catalog.resolve(name, where), 1, "task") for name in names]
    if not wanted:
        raise BadInput(f"{where}: no objects given")
    return number_items(wanted)[0]


__all__ = ["MAX_COUNT", "MAX_DINERS", "MAX_OBJECTS", "MAX_REQUEST_CHARS", "Request",
           "Wanted", "for_diners", "items_from_names", "number_items"]
