"""Natural-language requests: which catalog objects a user asks for, how many, and the
relations the request itself states.

A request such as "set the table with a plate, two forks and a knife" becomes the
items ``dinner plate``, ``dinner fork``, ``dinner fork 2``, ``dinner knife``.

How a request is read (the catalog matcher; the vocabulary is
:mod:`llm_grop.world.request_words`):

* Words are matched against the catalog's names, synonyms and plurals, longest
  match first ("dinner knife" over "knife", "mug lid" over "mug").
* A count may precede an object: ASCII digits, ``one`` to ``twenty``, ``thirty``,
  ``a``/``an``, ``a couple of``, ``a pair of`` (2; "a pair of forks" is two
  dinner forks), ``a dozen``. Without a count an object counts once. A plural
  without a count ("strawberries", "some strawberries") is refused with a request
  for a number, since guessing how many would silently change the task. At most
  :data:`MAX_OBJECTS` objects in all.
* Politeness, verbs, determiners and place phrases ("please", "set the table
  with", "I'd like", "for dinner", "its") are ignored, and so is a possessive
  "'s" ("the mug's lid" is the mug lid); commas, "and", "with", "plus" and "&"
  separate objects. "or" is refused: the request must say exactly what to set.
* What an object holds is not an object: "a glass of water", "a mug of coffee".
* A relation phrase between two objects states their relation: "a mug on a coaster"
  (the mug on top of the mug mat), "the fork to the left of the plate", "a bowl in the
  middle". These become :attr:`Request.relations`, with ``source="request"``.
* Any other words are a chunk the matcher cannot account for (:class:`Unread`).
  :func:`parse_request` refuses them with :class:`UnknownObject` and suggestions;
  :func:`read_request` returns them, so that an LLM can be asked what they mean
  (:mod:`llm_grop.arrangement.understanding`). Adjectives are not special: "a blue mug"
  is the unread chunk 'blue mug' (did you mean 'mug'?), because the pipeline cannot
  honour them.

Items keep the order in which their kind is first mentioned; repeated mentions add
instances ("a fork ... and another fork" gives two dinner forks).

A request may set the table for several diners: "for two", "for 4 people", "four place
settings with ...". The objects it names are then one diner's setting, and every diner
gets one (:func:`for_diners`): the second diner's plate is "dinner plate 2".
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog, ObjectSpec
from llm_grop.world.llmlog import CallRecord
from llm_grop.world.relation import CENTER, Relation
from llm_grop.world.request_reader import (
    MAX_OBJECTS,
    MatchReader,
    Mention,
    Unread,
    is_number,
    normalized,
    tokens,
)
from llm_grop.world.request_words import NUMBERS

#: Most diners one request may set the table for.
MAX_DINERS = 12

#: Longest request read, in characters: a request is a sentence or two, and reading
#: (and an LLM prompt built from it) must stay cheap.
MAX_REQUEST_CHARS = 2000

_SURROGATE = re.compile("[\ud800-\udfff]")
_EXAMPLE = "e.g. 'a dinner plate, a dinner fork and a dinner knife'"


@dataclass(frozen=True)
class Request:
    """A user's request: its ``text``, the catalog ``items`` it asks for, in order, and
    how many ``diners`` it sets the table for (the items are then every diner's, each
    with its ``diner`` index).

    ``relations`` are those the request states between its objects (first diner's
    names); ``source`` says how the objects were read: ``"catalog"`` (the matcher alone)
    or ``"llm"`` (an LLM read what the matcher could not); ``calls`` are those LLM calls;
    ``warnings`` what the reading could not honour.
    """

    text: str
    items: tuple[Item, ...]
    diners: int = 1
    relations: tuple[Relation, ...] = ()
    source: str = "catalog"
    calls: tuple[CallRecord, ...] = ()
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class Reading:
    """What the catalog matcher made of a request.

    ``parts`` are the mentions and unread chunks in the order they were written;
    ``links`` the relations the request states, as ``(subject part, relation, reference
    part or None)`` indexes into ``parts``; ``rest`` the text without its diner phrase.
    """

    text: str
    rest: str
    diners: int
    parts: tuple[Mention | Unread, ...]
    links: tuple[tuple[int, str, int | None], ...] = ()

    @property
    def unread(self) -> tuple[Unread, ...]:
        """The chunks the matcher could not account for, in order."""
        return tuple(p for p in self.parts if isinstance(p, Unread))

    def request(self, answers: Sequence[Sequence[Mention]] = (), source: str = "catalog",
                calls: Sequence[CallRecord] = (), warnings: Sequence[str] = ()) -> Request:
        """The request, each unread chunk replaced by the mentions of ``answers`` (one
        sequence per chunk, in order; an LLM's reading). Raises the first unread chunk's
        :class:`UnknownObject` when ``answers`` does not cover every chunk, and
        :class:`BadInput` when nothing is named or the counts are too many."""
        unread = self.unread
        if len(answers) < len(unread):
            raise unread[len(answers)].error()
        mentions: list[Mention] = []
        at: dict[int, int] = {}  # part index -> mention index
        answer = iter(answers)
        for k, part in enumerate(self.parts):
            if isinstance(part, Mention):
                at[k] = len(mentions)
                mentions.append(part)
            else:
                mentions += next(answer)
        if not mentions:
            raise BadInput(f"request: no object named in {self.text!r}; "
                           f"name the objects to set, {_EXAMPLE}")
        items, names = _items(mentions)
        notes = list(warnings)
        relations = _relations(self.links, at, names, notes)
        return Request(self.text, for_diners(items, self.diners), self.diners, relations,
                       source, tuple(calls), tuple(notes))


def _diner_count(text: str) -> tuple[int, str]:
    """How many diners ``text`` sets the table for, and the text without that phrase."""
    low = text.lower()
    for pattern in _DINERS:
        m = pattern.search(low)
        if m:
            word = m.group(1)
            n = int(word) if is_number(word) else NUMBERS.get(word, 0)
            if not 1 <= n <= MAX_DINERS:
                raise BadInput(f"request: {m.group(0)!r}: between 1 and {MAX_DINERS} diners")
            return n, text[:m.start()] + " " + text[m.end():]
    return 1, text


_DINER_NUMBER = r"([0-9]+|" + "|".join(NUMBERS) + ")"
_DINERS = (
    re.compile(r"\bfor\s+" + _DINER_NUMBER + r"(?:\s+(?:people|persons|diners|guests|of\s+us))?"
               r"(?![\w'])"),
    re.compile(r"\b" + _DINER_NUMBER + r"\s+(?:place\s+settings|settings|places|covers)\b"),
)


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
            out.append(Item(it.kind if k == 1 else f"{it.kind} {k}", it.spec, d))
    return tuple(out)


def _items(mentions: Sequence[Mention]) -> tuple[tuple[Item, ...], list[list[str]]]:
    """Numbered items, grouped by kind in order of first mention, and the item names
    each mention stands for."""
    counts: dict[str, int] = {}
    specs: dict[str, ObjectSpec] = {}
    names: list[list[str]] = []
    for m in mentions:
        first = counts.get(m.spec.name, 0)
        names.append([m.spec.name if k == 1 else f"{m.spec.name} {k}"
                      for k in range(first + 1, first + m.count + 1)])
        counts[m.spec.name] = first + m.count
        specs[m.spec.name] = m.spec
    total = sum(counts.values())
    if total > MAX_OBJECTS:
        raise BadInput(f"request: {total} objects is too many; at most {MAX_OBJECTS}")
    items: list[Item] = []
    for kind, count in counts.items():
        items += [Item(kind if k == 1 else f"{kind} {k}", specs[kind])
                  for k in range(1, count + 1)]
    return tuple(items), names


def _relations(links: Sequence[tuple[int, str, int | None]], at: dict[int, int],
               names: Sequence[Sequence[str]], warnings: list[str]) -> tuple[Relation, ...]:
    """The stated relations between items: instance by instance when both sides count
    the same ("two mugs on two coasters"), every subject to a single reference ("two
    forks to the left of the plate"); other counts are ambiguous and refused."""
    out: list[Relation] = []
    for s, relation, r in links:
        subjects = names[at[s]]
        if r is None:
            if len(subjects) > 1:
                raise BadInput(f"request: which of the {len(subjects)} {subjects[0]}s goes "
                               "in the center? say it of one object")
            out.append(Relation(subjects[0], CENTER, None, source="request"))
            continue
        references = names[at[r]]
        if subjects[0] == references[0]:
            warnings.append(f"ignored the request's relation of the {subjects[0]} to itself")
            continue
        if len(references) == 1:
            out += [Relation(name, relation, references[0], source="request")
                    for name in subjects]
        elif len(references) == len(subjects):
            out += [Relation(a, relation, b, source="request")
                    for a, b in zip(subjects, references, strict=True)]
        else:
            raise BadInput(f"request: {len(subjects)} {subjects[0]} {relation} "
                           f"{len(references)} {references[0]}: say which goes with which")
    return tuple(out)


def read_request(text: str, catalog: Catalog) -> Reading:
    """What the catalog matcher makes of ``text``: its mentions, stated relations and
    the chunks it cannot account for (see :class:`Reading`).

    Raises :class:`BadInput` for an empty or overlong request, "or", a dangling or
    out-of-range count, or a plural without a count.
    """
    if not text.strip():
        raise BadInput(f"request: empty; name the objects to set, {_EXAMPLE}")
    if len(text) > MAX_REQUEST_CHARS:
        raise BadInput(f"request: {len(text)} characters; at most {MAX_REQUEST_CHARS}")
    bad = _SURROGATE.search(text)
    if bad:
        # What a command line holds when its bytes are not UTF-8 (surrogateescape).
        byte = ord(bad.group(0)) - 0xDC00 if ord(bad.group(0)) >= 0xDC80 else None
        what = f"the byte 0x{byte:02x}" if byte is not None else "a lone surrogate"
        raise BadInput(f"request: not UTF-8 text (character {bad.start() + 1} is {what}); "
                       "write the request in UTF-8")
    diners, rest = _diner_count(normalized(text))
    reader = MatchReader(tokens(rest), catalog)
    reader.read()
    return Reading(" ".join(text.split()), rest, diners, tuple(reader.parts),
                   tuple(reader.links))


def parse_request(text: str, catalog: Catalog) -> Request:
    """The objects ``text`` asks for, resolved against ``catalog`` by the matcher alone.

    Raises :class:`BadInput` as :func:`read_request` does, when nothing is named or there
    are more than :data:`MAX_OBJECTS` objects, and :class:`UnknownObject` (with
    suggestions) for the first chunk the catalog does not account for.
    """
    return read_request(text, catalog).request()


def items_from_names(names: Sequence[str], catalog: Catalog, where: str = "objects"
                     ) -> tuple[Item, ...]:
    """Items for a list of object names (e.g. a task's); repeating a name adds an instance.

    Each name must be a single catalog name, synonym or plural; an unknown one raises
    :class:`UnknownObject` naming ``where``.
    """
    mentions = [Mention(catalog.resolve(name, where), 1) for name in names]
    if not mentions:
        raise BadInput(f"{where}: no objects given")
    return _items(mentions)[0]


__all__ = ["MAX_DINERS", "MAX_OBJECTS", "Mention", "Reading", "Request", "Unread",
           "for_diners", "items_from_names", "parse_request", "read_request"]
