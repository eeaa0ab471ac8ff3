"""The catalog matcher: reads a request's words into the objects it names, the relations
it states between them, and the chunks it cannot account for (see
:mod:`llm_grop.world.request` for the rules, :mod:`llm_grop.world.request_words` for the
vocabulary)."""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from llm_grop.errors import BadInput, UnknownObject
from llm_grop.world.catalog import Catalog, ObjectSpec, singular_forms
from llm_grop.world.relation import CENTER
from llm_grop.world.request_words import (
    ARTICLES,
    CENTER_PHRASES,
    COUNT_PHRASES,
    FILLERS,
    RELATION_PHRASES,
    SEPARATOR_CHARS,
    SEPARATOR_WORDS,
    VAGUE,
)

#: Most objects one request may ask for (all kinds together).
MAX_OBJECTS = 30

#: Phrases after an object that are no contents: "a plate for dinner" is only a plate.
_PURPOSE_FILLERS = tuple(p for p in FILLERS if len(p) > 1 and p[0] == "for")

_TOKEN = re.compile(r"[^\W_]+(?:'[^\W_]+)*")


@dataclass(frozen=True)
class Unread:
    """A chunk of the request the catalog matcher cannot account for, with the catalog
    names closest to it."""

    text: str
    suggestions: tuple[str, ...] = ()

    def error(self, where: str = "request") -> UnknownObject:
        """The one-line error for this chunk."""
        return UnknownObject(self.text, list(self.suggestions), where)


@dataclass(frozen=True)
class Mention:
    """One object named in the request, before instances are numbered."""

    spec: ObjectSpec
    count: int


def normalized(text: str) -> str:
    """``text`` in the form the matcher reads: NFKC (fullwidth letters and digits become
    ASCII, ligatures split) except for other numerals such as '²' and '①', which stay
    as they are rather than become counts; typographic apostrophes made plain."""
    if text.isascii():
        return text
    out = [c if unicodedata.category(c) == "No" else unicodedata.normalize("NFKC", c)
           for c in text]
    return "".join(out).replace("\u2019", "'").replace("\u2018", "'")


def is_number(word: str) -> bool:
    """Whether ``word`` is a count in ASCII digits (``str.isdigit`` also accepts '²')."""
    return word.isascii() and word.isdigit() and len(word) <= 6


def tokens(text: str) -> list[str]:
    """Words of ``text`` (lower case) with ``","`` standing for every separator;
    possessives keep their "'s"."""
    text = normalized(text).lower().replace("-", " ")
    out: list[str] = []
    pos = 0
    for m in _TOKEN.finditer(text):
        if SEPARATOR_CHARS.intersection(text[pos:m.start()]):
            out.append(",")
        out.append(m.group(0))
        pos = m.end()
    return out


def _longest(words: Sequence[str], i: int, phrases: Iterable[tuple[str, ...]]) -> int:
    """Length of the longest phrase of ``phrases`` starting at ``words[i]``, else 0."""
    return max((len(p) for p in phrases if tuple(words[i:i + len(p)]) == p), default=0)


@dataclass
class MatchReader:
    """Reads a request's words left to right into parts; see the module docstring."""

    words: list[str]
    catalog: Catalog
    parts: list[Mention | Unread] = field(default_factory=list)
    links: list[tuple[int, str, int | None]] = field(default_factory=list)
    count: int | None = None          # the pending count of the next object
    count_words: tuple[str, ...] = ()
    unknown: list[str] = field(default_factory=list)  # words of an unrecognised chunk
    tail: int = 0                     # fillers at the end of ``unknown``
    subject: int | None = None        # the part a relation phrase would start from
    relation: str | None = None       # a relation phrase waiting for its reference
    contents: bool = False            # reading what the last object holds ("of water")
    written: str = ""                 # the last object's name as written
    definite: bool = False            # the word before was "the"

    def __post_init__(self) -> None:
        # A possessive names its owner: "the mug's lid" is the mug lid, and "my wife's
        # mug" is a mug (an owner that is no object is a filler).
        self.possessive = {k for k, w in enumerate(self.words)
                           if w.endswith("'s") and (w,) not in FILLERS}
        self.words = [w[:-2] if k in self.possessive else w for k, w in enumerate(self.words)]
        self.aliases = self.catalog.aliases()
        self.longest = max((len(a.split()) for a in self.aliases), default=1)

    def read(self) -> None:
        """Reads every word; raises :class:`BadInput` on a count that counts nothing."""
        words, i = self.words, 0
        while i < len(words):
            i += self._step(i)
        self._end_chunk()

    def _step(self, i: int) -> int:
        """Reads the phrase at ``words[i]``; returns how many words it used."""
        words = self.words
        definite, self.definite = self.definite, False
        obj = self._object_at(i)
        if obj is not None:
            n, spec, plural = obj
            self._take(spec, plural, " ".join(words[i:i + n]), definite)
            return n
        if words[i] == "or":
            raise BadInput("request: 'or' leaves the choice open; "
                           "name exactly the objects to set")
        if words[i] == "," or words[i] in SEPARATOR_WORDS:
            self._end_chunk()
            return 1
        if i in self.possessive:
            return 1
        if self.subject is not None and not self.unknown:
            n = max(_longest(words, i, RELATION_PHRASES), _longest(words, i, CENTER_PHRASES))
            if n and n >= _longest(words, i, FILLERS):
                phrase = tuple(words[i:i + n])
                if phrase in CENTER_PHRASES:
                    self.links.append((self.subject, CENTER, None))
                else:
                    self.relation = RELATION_PHRASES[phrase]
                self.contents = False
                return n
            if words[i] in ("of", "for") and self.relation is None and self.count is None \
                    and not _longest(words, i, _PURPOSE_FILLERS):
                self.contents = True
                return 1
        n_count = _longest(words, i, COUNT_PHRASES)
        if self.contents and not n_count:
            self._refine(words[i])
            return 1  # what the last object holds: "a mug of coffee"
        n_vague = _longest(words, i, VAGUE)
        n_filler = _longest(words, i, FILLERS)
        n = max(n_count, n_vague, n_filler)
        if n == 0 and is_number(words[i]):
            self._flush_unknown()
            self._set_count(int(words[i]), (words[i],))
            return 1
        if n == 0:
            self.unknown.append(words[i])
            self.tail = 0
            return 1
        if self.unknown and n == n_filler and n > max(n_count, n_vague):
            # Fillers inside an unread chunk belong to it: "something to eat soup".
            self.unknown += words[i:i + n]
            self.tail += n
            return n
        self._flush_unknown()
        if n == n_count:
            phrase = tuple(words[i:i + n])
            self._set_count(COUNT_PHRASES[phrase], phrase)
        elif n == n_vague:
            self._set_count(None, ())
        else:
            self.definite = words[i:i + n] == ["the"]
        return n

    def _refine(self, word: str) -> None:
        """A container named by what it holds: "a glass of wine" is a wine glass and "a
        bowl of soup" a soup bowl, when the catalog has that name."""
        if self.subject is None or self.subject != len(self.parts) - 1:
            return
        last = self.parts[self.subject]
        for form in singular_forms(f"{word} {self.written}"):
            if form in self.aliases and isinstance(last, Mention):
                self.parts[self.subject] = Mention(self.catalog.specs[self.aliases[form]],
                                                   last.count)
                return

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
        if self.count is not None and self.count_words not in ARTICLES:
            raise BadInput(f"request: {' '.join(self.count_words)!r} is not followed by "
                           "an object name")

    def _set_count(self, value: int | None, words: tuple[str, ...]) -> None:
        self._check_no_dangling_count()
        self.count = value
        self.count_words = words
        self.contents = False

    def _take(self, spec: ObjectSpec, plural: bool, written: str, definite: bool = False
              ) -> None:
        self.contents = False
        self.written = written
        if self.tail:
            self._flush_unknown()
        if self.unknown:
            # Unknown words right before a known name ("blue mug") are part of its name.
            name = " ".join([*self.unknown, written])
            hints = [spec.name] + [s for s in self.catalog.suggest(name) if s != spec.name]
            self.parts.append(Unread(name, tuple(hints[:3])))
            self.unknown.clear()
            self.subject = self.relation = None
            self.count, self.count_words = None, ()
            return
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
        earlier = [k for k, p in enumerate(self.parts) if isinstance(p, Mention)
                   and p.spec == spec and p.count == 1]
        if definite and self.count is None and not plural and earlier:
            at = earlier[0]  # "the knife" of a request that named a knife already
        else:
            self.parts.append(Mention(spec, count))
            at = len(self.parts) - 1
        if self.relation is not None and self.subject is not None:
            self.links.append((self.subject, self.relation, at))
        self.subject, self.relation = at, None
        self.count, self.count_words = None, ()

    def _flush_unknown(self) -> None:
        if self.unknown:
            name = " ".join(self.unknown[:len(self.unknown) - self.tail])
            self.parts.append(Unread(name, tuple(self.catalog.suggest(name))))
            self.unknown.clear()
            self.tail = 0
            self.subject = self.relation = None

    def _end_chunk(self) -> None:
        self._flush_unknown()
        self._check_no_dangling_count()
        self.count, self.count_words = None, ()
        self.subject = self.relation = None
        self.contents = False
