"""Natural-language requests: which catalog objects a user asks for, and how many.

A request such as "set the table with a plate, two forks and a knife" becomes the
items ``dinner plate``, ``dinner fork``, ``dinner fork 2``, ``dinner knife``.

How a request is read:

* Words are matched against the catalog's names, synonyms and plurals, longest
  match first ("dinner knife" over "knife", "mug lid" over "mug").
* A count may precede an object: digits, ``one`` to ``twenty``, ``thirty``,
  ``a``/``an``, ``a couple of``, ``a pair of`` (2; "a pair of forks" is two
  dinner forks), ``a dozen``. Without a count an object counts once. A plural
  without a count ("strawberries", "some strawberries") is refused with a request
  for a number, since guessing how many would silently change the task. At most
  :data:`MAX_OBJECTS` objects in all.
* Politeness, verbs, determiners and place phrases ("please", "set the table
  with", "I'd like", "for dinner", "its") are ignored, and so is a possessive
  "'s" ("the mug's lid" is the mug lid); commas, "and", "with", "plus" and "&"
  separate objects. "or" is refused: the request must say exactly what to set.
* Any other word is taken as (part of) an object name the catalog does not know,
  and the request is refused with :class:`UnknownObject` and suggestions.
  Adjectives are not special: "a blue mug" is refused as the unknown object
  'blue mug' (did you mean 'mug'?), because the pipeline cannot honour them.

Items keep the order in which their kind is first mentioned; repeated mentions add
instances ("a fork ... and another fork" gives two dinner forks).

A request may set the table for several diners: "for two", "for 4 people", "four place
settings with ...". The objects it names are then one diner's setting, and every diner
gets one (:func:`for_diners`): the second diner's plate is "dinner plate 2".
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from llm_grop.errors import BadInput, UnknownObject
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog, ObjectSpec, singular_forms

#: Most objects one request may ask for (all kinds together).
MAX_OBJECTS = 30

_EXAMPLE = "e.g. 'a dinner plate, a dinner fork and a dinner knife'"

_NUMBERS: dict[str, int] = {
    "one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7,
    "eight": 8, "nine": 9, "ten": 10, "eleven": 11, "twelve": 12, "thirteen": 13,
    "fourteen": 14, "fifteen": 15, "sixteen": 16, "seventeen": 17, "eighteen": 18,
    "nineteen": 19, "twenty": 20, "thirty": 30,
}


def _phrases(*texts: str) -> tuple[tuple[str, ...], ...]:
    return tuple(tuple(t.split()) for t in texts)


# Phrases that count the next object. Articles also count 1, but may dangle harmlessly.
_COUNT_PHRASES: dict[tuple[str, ...], int] = {
    **{(w,): n for w, n in _NUMBERS.items()},
    ("a",): 1, ("an",): 1, ("another",): 1, ("single",): 1, ("a", "single"): 1,
    ("a", "couple", "of"): 2, ("couple", "of"): 2, ("a", "pair", "of"): 2, ("pair", "of"): 2,
    ("a", "dozen"): 12, ("dozen",): 12,
}
_ARTICLES = _phrases("a", "an", "one", "another")
# Quantities that name no number: a plural after them still needs one.
_VAGUE = _phrases("some", "a few", "few", "several", "many", "a lot of", "lots of",
                  "a bunch of", "more", "any", "extra", "a number of")
_FILLERS = _phrases(
    "for dinner", "for breakfast", "for lunch", "for supper", "for brunch", "for one",
    "for one person", "on the table", "at the table", "place setting", "thank you", "if you can",
    "if possible", "set up",
) + tuple((w,) for w in (
    "please", "kindly", "thanks", "thank", "you", "i", "i'd", "i'll", "i'm", "id", "we", "we'd",
    "let's", "would", "like", "love", "want", "wants", "need", "needs", "could", "can", "will",
    "may", "might", "must", "should", "shall", "me", "us", "set", "lay", "put", "place", "arrange",
    "get", "bring", "give", "serve", "prepare", "make", "setup", "up", "out", "down", "the",
    "table", "setting", "on", "onto", "at", "in", "into", "to", "for", "of", "its", "it", "it's",
    "their", "his", "her", "my", "our", "your", "this", "that", "these", "those", "there", "here",
    "is", "are", "be", "just", "only", "too", "as", "well", "now", "nicely", "neatly", "properly",
    "meal", "dinner", "breakfast", "lunch", "supper", "brunch",
))
_SEPARATOR_WORDS = frozenset({"and", "with", "plus", "also", "then"})
_SEPARATOR_CHARS = frozenset(",;:.!?&+/|()[]{}\n")
_TOKEN = re.compile(r"[^\W_]+(?:'[^\W_]+)*")


@dataclass(frozen=True)
class Request:
    """A user's request: its ``text``, the catalog ``items`` it asks for, in order, and
    how many ``diners`` it sets the table for (the items are then every diner's, each
    with its ``diner`` index)."""

    text: str
    items: tuple[Item, ...]
    diners: int = 1


#: Most diners one request may set the table for.
MAX_DINERS = 12

_DINER_NUMBER = r"(\d+|" + "|".join(_NUMBERS) + ")"
_DINERS = (
    re.compile(r"\bfor\s+" + _DINER_NUMBER + r"(?:\s+(?:people|persons|diners|guests|of\s+us))?"
               r"(?![\w'])"),
    re.compile(r"\b" + _DINER_NUMBER + r"\s+(?:place\s+settings|settings|places|covers)\b"),
)


def _diner_count(text: str) -> tuple[int, str]:
    """How many diners ``text`` sets the table for, and the text without that phrase."""
    low = text.lower()
    for pattern in _DINERS:
        m = pattern.search(low)
        if m:
            word = m.group(1)
            n = int(word) if word.isascii() and word.isdigit() else _NUMBERS.get(word, 0)
            if not 1 <= n <= MAX_DINERS:
                raise BadInput(f"request: {m.group(0)!r}: between 1 and {MAX_DINERS} diners")
            return n, text[:m.start()] + " " + text[m.end():]
    return 1, text


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


@dataclass
class _Mention:
    """One object named in the request, before instances are numbered."""

    spec: ObjectSpec
    count: int


def _tokens(text: str) -> list[str]:
    """Words of ``text`` (lower case) with ``","`` standing for every separator."""
    text = text.lower().replace("\u2019", "'").replace("-", " ")
    out: list[str] = []
    pos = 0
    for m in _TOKEN.finditer(text):
        if _SEPARATOR_CHARS.intersection(text[pos:m.start()]):
            out.append(",")
        word = m.group(0)
        if word.endswith("'s") and (word,) not in _FILLERS:
            word = word[:-2]  # a possessive: "the mug's lid" names the mug lid
        out.append(word)
        pos = m.end()
    return out


def _longest(words: Sequence[str], i: int, phrases: Iterable[tuple[str, ...]]) -> int:
    """Length of the longest phrase of ``phrases`` starting at ``words[i]``, else 0."""
    return max((len(p) for p in phrases if tuple(words[i:i + len(p)]) == p), default=0)


class _Reader:
    """Reads a request's words left to right into mentions; see the module docstring."""

    def __init__(self, text: str, catalog: Catalog) -> None:
        self.catalog = catalog
        self.aliases = catalog.aliases()
        self.longest = max((len(a.split()) for a in self.aliases), default=1)
        self.words = _tokens(text)
        self.mentions: list[_Mention] = []
        self.count: int | None = None   # the pending count of the next object
        self.count_words: tuple[str, ...] = ()
        self.unknown: list[str] = []    # words of an unrecognised chunk

    def read(self) -> list[_Mention]:
        """Every mention; raises on an unknown chunk or a count that counts nothing."""
        words = self.words
        i = 0
        while i < len(words):
            obj = self._object_at(i)
            if obj is not None:
                n, spec, plural = obj
                self._take(spec, plural, " ".join(words[i:i + n]))
                i += n
                continue
            if words[i] == "or":
                raise BadInput("request: 'or' leaves the choice open; "
                               "name exactly the objects to set")
            if words[i] == "," or words[i] in _SEPARATOR_WORDS:
                self._end_chunk()
                i += 1
                continue
            n_count = _longest(words, i, _COUNT_PHRASES)
            n_vague = _longest(words, i, _VAGUE)
            n_filler = _longest(words, i, _FILLERS)
            n = max(n_count, n_vague, n_filler)
            if n == 0 and words[i].isdigit():
                self._flush_unknown()
                self._set_count(int(words[i]), (words[i],))
                n = 1
            elif n == 0:
                self.unknown.append(words[i])
                n = 1
            elif n == n_count:
                self._flush_unknown()
                phrase = tuple(words[i:i + n])
                self._set_count(_COUNT_PHRASES[phrase], phrase)
            elif n == n_vague:
                self._flush_unknown()
                self._set_count(None, ())
            else:
                self._flush_unknown()
            i += n
        self._end_chunk()
        return self.mentions

    def _object_at(self, i: int) -> tuple[int, ObjectSpec, bool] | None:
        """``(words used, spec, plural?)`` of the longest catalog name at ``words[i]``."""
        for n in range(min(self.longest, len(self.words) - i), 0, -1):
            part = self.words[i:i + n]
            if "," in part:
                continue
            phrase = " ".join(part)
            for form in singular_forms(phrase):
                if form in self.aliases:
                    return n, self.catalog.specs[self.aliases[form]], form != phrase
        return None

    def _check_no_dangling_count(self) -> None:
        if self.count is not None and self.count_words not in _ARTICLES:
            raise BadInput(f"request: {' '.join(self.count_words)!r} is not followed by "
                           "an object name")

    def _set_count(self, value: int | None, words: tuple[str, ...]) -> None:
        self._check_no_dangling_count()
        self.count = value
        self.count_words = words

    def _take(self, spec: ObjectSpec, plural: bool, written: str) -> None:
        if self.unknown:
            # Unknown words right before a known name ("blue mug") are part of its name.
            name = " ".join([*self.unknown, written])
            hints = [spec.name] + [s for s in self.catalog.suggest(name) if s != spec.name]
            raise UnknownObject(name, hints[:3])
        count = self.count
        if count is None:
            if plural:
                raise BadInput(f"request: how many {written!r}? give a number, "
                               f"e.g. 'three {written}'")
            count = 1
        if count < 1:
            raise BadInput(f"request: '{' '.join(self.count_words)} {written}': "
                           "a count must be at least 1")
        if count > MAX_OBJECTS:
            raise BadInput(f"request: '{count} {written}' is too many; "
                           f"at most {MAX_OBJECTS} objects in all")
        self.mentions.append(_Mention(spec, count))
        self.count, self.count_words = None, ()

    def _flush_unknown(self) -> None:
        if self.unknown:
            name = " ".join(self.unknown)
            raise UnknownObject(name, self.catalog.suggest(name))

    def _end_chunk(self) -> None:
        self._flush_unknown()
        self._check_no_dangling_count()
        self.count, self.count_words = None, ()


def _items(mentions: Sequence[_Mention]) -> tuple[Item, ...]:
    """Numbered items, grouped by kind in order of first mention."""
    counts: dict[str, int] = {}
    specs: dict[str, ObjectSpec] = {}
    for m in mentions:
        counts[m.spec.name] = counts.get(m.spec.name, 0) + m.count
        specs[m.spec.name] = m.spec
    total = sum(counts.values())
    if total > MAX_OBJECTS:
        raise BadInput(f"request: {total} objects is too many; at most {MAX_OBJECTS}")
    items: list[Item] = []
    for kind, count in counts.items():
        items += [Item(kind if k == 1 else f"{kind} {k}", specs[kind])
                  for k in range(1, count + 1)]
    return tuple(items)


def parse_request(text: str, catalog: Catalog) -> Request:
    """The objects ``text`` asks for, resolved against ``catalog``.

    Raises :class:`BadInput` for an empty request, a dangling or out-of-range count,
    a plural without a count or more than :data:`MAX_OBJECTS` objects, and
    :class:`UnknownObject` (with suggestions) for a name the catalog does not know.
    """
    if not text.strip():
        raise BadInput(f"request: empty; name the objects to set, {_EXAMPLE}")
    diners, rest = _diner_count(text)
    mentions = _Reader(rest, catalog).read()
    if not mentions:
        raise BadInput(f"request: no object named in {text.strip()!r}; "
                       f"name the objects to set, {_EXAMPLE}")
    return Request(text.strip(), for_diners(_items(mentions), diners), diners)


def items_from_names(names: Sequence[str], catalog: Catalog, where: str = "objects"
                     ) -> tuple[Item, ...]:
    """Items for a list of object names (e.g. a task's); repeating a name adds an instance.

    Each name must be a single catalog name, synonym or plural; an unknown one raises
    :class:`UnknownObject` naming ``where``.
    """
    mentions = [_Mention(catalog.resolve(name, where), 1) for name in names]
    if not mentions:
        raise BadInput(f"{where}: no objects given")
    return _items(mentions)


__all__ = ["MAX_DINERS", "MAX_OBJECTS", "Request", "for_diners", "items_from_names",
           "parse_request"]
