"""The catalog matcher: reads a request's words, left to right, into the objects it names,
the relations it states between them, and what it cannot account for.

It is the fast path of :mod:`llm_grop.language.request`: its reading stands alone only when
it accounts for every word. The words it knows are the catalog's names, synonyms and
plurals, and the vocabulary of :mod:`llm_grop.language.vocabulary` (counts, fillers,
separators, relation phrases). Anything else is an :class:`Unread` chunk, and anything it
cannot resolve (a pronoun with nothing before it, a plural without a number) is a
*doubt*: either leaves the request to the LLM.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from llm_grop.errors import BadInput
from llm_grop.language.parts import Link, Mention, Unread
from llm_grop.language.references import antecedent, resolve_references
from llm_grop.language.vocabulary import (
    ARTICLES,
    EITHER_SIDE,
    PhraseMatch,
    PhraseTable,
    dining_words,
    longest_at,
    phrase_table,
    request_words,
)
from llm_grop.language.words import Token, distance_at, is_number, normalized, tokens
from llm_grop.world.catalog import Catalog, ObjectSpec, singular_forms
from llm_grop.world.relation import CENTER
from llm_grop.world.request import MAX_COUNT

#: Words after a stated distance that close it ("2 cm away").
_AWAY = frozenset({"away", "apart", "off", "gap", "between"})
_PRONOUNS = frozenset({"it", "them"})
#: Separators that list objects, so that what follows may share a relation.
_COORDINATING = frozenset({("and",), (",",), ("plus",), ("and", "also")})


@dataclass
class MatchReader:
    """Reads a request's tokens left to right into parts and links; see the module
    docstring. Hard errors (a count of 0 or over :data:`MAX_COUNT`, a negative distance,
    "or") raise :class:`BadInput`; what only an LLM may resolve is kept in ``doubts``."""

    toks: list[Token]
    catalog: Catalog
    text: str = ""                    # what the tokens' offsets point into
    diners: int = 1                   # several: a plural without a number is one each
    parts: list[Mention | Unread] = field(default_factory=list)
    links: list[Link] = field(default_factory=list)
    doubts: list[str] = field(default_factory=list)
    count: int | None = None          # the pending count of the next object
    count_words: tuple[str, ...] = ()
    count_start: int | None = None    # token index of the pending count
    unknown: list[int] = field(default_factory=list)  # token indexes of an unread chunk
    tail: int = 0                     # fillers at the end of ``unknown``
    subject: int | None = None        # the part a relation phrase would start from
    subject_start: int = 0            # the token where the subject was last written
    before: int | None = None         # the subject before the last "and" (either side of)
    pending: Link | None = None       # a relation phrase waiting for its reference
    distance: tuple[float, int] | None = None  # a stated distance (cm) and where it began
    contents: bool = False            # reading what the last object holds ("of water")
    written: str = ""                 # the last object's name as written
    definite: bool = False            # the word before was "the"

    def __post_init__(self) -> None:
        self.words = [t.word for t in self.toks]
        self.vocab = request_words()
        self.dining = dining_words()
        self.table: PhraseTable = phrase_table()
        # A possessive names its owner: "the mug's lid" is the mug lid, and "my wife's
        # mug" is a mug (an owner that is no object is a filler).
        filler_words = {w for phrase in self.vocab.fillers for w in phrase}
        self.possessive = {k for k, w in enumerate(self.words)
                           if w.endswith("'s") and w not in filler_words}
        self.words = [w[:-2] if k in self.possessive else w for k, w in enumerate(self.words)]
        self.aliases = self.catalog.aliases()
        self.longest = max((len(a.split()) for a in self.aliases), default=1)
        self._sentences = []
        ends = 0
        for t in self.toks:
            self._sentences.append(ends)
            ends += t.word == "."
        self.after_comma: int | None = None  # the subject a "," closed
        self.after_pronoun = False  # "a lid on it on a coaster": of which object?
        self.separator: tuple[str, ...] = ()  # the separator words just read
        #: part -> (the separator before it, the subject before that separator)
        self.joined: dict[int, tuple[tuple[str, ...], int | None]] = {}

    def read(self) -> None:
        """Reads every token."""
        i = 0
        while i < len(self.words):
            i += self._step(i)
        self._end_chunk()
        if self.pending is not None:
            self.doubts.append("a relation phrase names no object after it")

    def sentence_at(self, token: int) -> int:
        """The number of the sentence token ``token`` is in (sentences end with ".")."""
        return self._sentences[min(token, len(self._sentences) - 1)] if self._sentences else 0

    def span(self, start: int, end: int) -> tuple[int, int]:
        """Character offsets of tokens ``[start, end)``."""
        return self.toks[start].start, self.toks[max(start, end - 1)].end

    # -- one phrase -----------------------------------------------------------------
    def _step(self, i: int) -> int:
        """Reads the phrase at ``words[i]``; returns how many tokens it used."""
        words = self.words
        definite, self.definite = self.definite, False
        obj = self._object_at(i)
        if obj is not None:
            n, spec, plural = obj
            if self.contents:
                self.doubts.append(f"{self.written!r} of or for {' '.join(words[i:i + n])!r}")
            self._take(spec, plural, i, n, definite)
            return n
        word = words[i]
        if word == "or":
            raise BadInput("request: 'or' leaves the choice open; "
                           "name exactly the objects to set")
        if word in (",", "."):
            self._end_chunk(sentence=word == ".")
            self.separator = (word,) if word == "," else ()
            return 1
        n_sep = longest_at(words, i, self.vocab.separator_words, self.vocab.longest)
        if n_sep:
            self._end_chunk(soft=True)
            self.separator = tuple(words[i:i + n_sep])
            return n_sep
        if i in self.possessive:
            return 1
        if self.pending is not None and word in _PRONOUNS and not self.unknown:
            self._link_pronoun(i)
            return 1
        if word == "it" and self.pending is None and not self.unknown and \
                self.subject is None and i + 1 < len(words) and self._subject_it(i):
            return 1
        distance = self._distance_at(i)
        if distance is not None:
            return distance
        if self.subject is None and self.after_comma is not None and not self.unknown:
            m = self._phrase(i)
            if m is not None and not m.bare:
                # "a water glass, to the left of the wine glass": the phrase is the glass's
                self.subject, self.after_comma = self.after_comma, None
        if self.subject is not None and not self.unknown:
            n = self._relation_at(i)
            if n:
                return n
            if word in ("of", "for") and self.pending is None and self.count is None \
                    and not self._purpose_at(i):
                self.contents = True
                return 1
        n_count = longest_at(words, i, self.vocab.counts, self.vocab.longest)
        if self.contents and (n_count and (words[i],) not in self.vocab.articles
                              or is_number(word)):
            self.doubts.append(f"{self.written!r} of {' '.join(words[i:i + n_count])!r}")
        if self.contents and (word in ARTICLES or any(
                f in self.dining.contents for f in singular_forms(word))):
            self._refine(word)
            return 1  # what the last object holds: "a mug of coffee"
        self.contents = False  # anything else is read as itself: "without", "each"
        n_vague = longest_at(words, i, self.vocab.vague, self.vocab.longest)
        n_filler = longest_at(words, i, self.vocab.fillers, self.vocab.longest)
        if self.diners > 1:
            n_filler = max(n_filler, longest_at(words, i, self.vocab.per_diner,
                                                self.vocab.longest))
        n = max(n_count, n_vague, n_filler)
        if n == 0 and is_number(word):
            self._flush_unknown()
            self._set_count(int(word), (word,), i)
            return 1
        if n == 0 or word == "-":
            self.after_comma = None
            self.separator = ()
            self.unknown.append(i)
            self.tail = 0
            return 1
        if self.unknown and n == n_filler and n > max(n_count, n_vague):
            # Fillers inside an unread chunk belong to it: "something to eat soup".
            self.unknown += range(i, i + n)
            self.tail += n
            return n
        self._flush_unknown()
        if n == n_count:
            phrase = tuple(words[i:i + n])
            self._set_count(self.vocab.counts[phrase], phrase, i)
        elif n == n_vague:
            self._set_count(None, (), i)
        else:
            self.definite = words[i:i + n] == ["the"]
        return n

    def _subject_it(self, i: int) -> bool:
        """Reads "it" as the subject of the relation phrase after it ("put it on a
        coaster"); ``False`` when no phrase follows or "it" has no one antecedent."""
        m = self.table.match(self.words, i + 1)
        if m is None:
            return False
        placed = {k.subject for k in self.links if k.kind in ("pronoun", "bare")}
        at = antecedent(self, i, placed)
        if at is None:
            self.doubts.append("what 'it' refers to")
            return False
        self.subject, self.subject_start = at, i
        return True

    def _purpose_at(self, i: int) -> bool:
        """Whether "for ..." at ``i`` is a filler ("for dinner"), not contents."""
        n = longest_at(self.words, i, self.vocab.fillers, self.vocab.longest)
        return n > 1 and self.words[i] == "for"

    def _phrase(self, i: int) -> PhraseMatch | None:
        """The relation phrase at ``words[i]``, after any skipped words ("slightly to the
        left of", "directly behind")."""
        j = i
        while j < len(self.words) and self.words[j] in self.table.skip:
            j += 1
        return self.table.match(self.words, j) if j < len(self.words) else None

    def _relation_at(self, i: int) -> int:
        """Reads a relation phrase of the subject at ``i``; returns the tokens used (0: none).

        A filler phrase at least as long wins ("on the table" is no stacking)."""
        m = self._phrase(i)
        if m is None or m.end - i < longest_at(self.words, i, self.vocab.fillers,
                                               self.vocab.longest):
            return 0
        assert self.subject is not None
        if self.after_pronoun:
            self.doubts.append("a second relation phrase after 'it': of which object?")
        start = self.subject_start
        distance = self.distance[0] if self.distance else None
        self.distance = None
        partner = None
        if m.relation == EITHER_SIDE:
            partner = self.before
            if partner is None:
                self.doubts.append("'either side of' needs two objects")
            else:
                start = min(start, self._start_of(partner))
        link = Link(self.subject, m.relation, None, "bare", start, m.end, distance, partner)
        self.contents = False
        if m.relation == CENTER:
            link.kind = "center"
            self.links.append(link)
        elif m.bare:
            self.links.append(link)
        else:
            link.kind = "named"
            self.pending = link
        return m.end - i

    def _start_of(self, part: int) -> int:
        p = self.parts[part]
        return p.start if isinstance(p, Mention) else 0

    def _distance_at(self, i: int) -> int | None:
        """Reads "2 cm", "an inch", "-2 cm" at ``i`` (see :func:`distance_at`); returns
        the tokens used, or ``None`` when no distance starts here."""
        found = distance_at(self.words, i, self.vocab.numbers)
        if found is None:
            return None
        cm, j = found
        if cm < 0:
            a, b = self.span(i, j)
            raise BadInput(f"request: {self.text[a:b]!r}: a distance must not be negative")
        last = self.links[-1] if self.links else None
        if j < len(self.words) and self.words[j] in _AWAY and last is not None and \
                last.distance_cm is None and last.kind in ("named", "pronoun"):
            last.distance_cm, last.end = cm, j + 1  # "the fork left of the plate, 2 cm away"
            return j + 1 - i
        self._flush_unknown()
        self.distance = (cm, i)
        return j - i

    # -- objects ----------------------------------------------------------------------
    def _refine(self, word: str) -> None:
        """A container named by what it holds: "a glass of wine" is a wine glass and "a
        bowl of soup" a soup bowl, when the catalog has that name."""
        if self.subject is None or self.subject != len(self.parts) - 1:
            return
        last = self.parts[self.subject]
        for form in singular_forms(f"{word} {self.written}"):
            if form in self.aliases and isinstance(last, Mention):
                self.parts[self.subject] = Mention(self.catalog.specs[self.aliases[form]],
                                                   last.count, last.start, last.end)
                return

    def _object_at(self, i: int) -> tuple[int, ObjectSpec, bool] | None:
        """``(words used, spec, plural?)`` of the longest catalog name at ``words[i]``."""
        for n in range(min(self.longest, len(self.words) - i), 0, -1):
            part = self.words[i:i + n]
            if "," in part or "." in part:
                continue
            phrase = " ".join(part)
            for form in singular_forms(phrase):
                if form in self.aliases:
                    return n, self.catalog.specs[self.aliases[form]], form != phrase
        return None

    def _check_no_dangling_count(self) -> None:
        if self.count is not None and self.count_words not in self.vocab.articles:
            self.doubts.append(f"{' '.join(self.count_words)!r} is not followed by an "
                               "object name")

    def _set_count(self, value: int | None, words: tuple[str, ...], at: int) -> None:
        self._check_no_dangling_count()
        self.count, self.count_words, self.count_start = value, words, at
        self.contents = False

    def _take(self, spec: ObjectSpec, plural: bool, i: int, n: int, definite: bool) -> None:
        self.contents = False
        self.after_comma = None
        self.written = " ".join(self.words[i:i + n])
        if self.tail:
            self._flush_unknown()
        if self.unknown:
            # Unknown words right before a known name ("blue mug") are part of its name.
            name = " ".join([*(self.words[k] for k in self.unknown), self.written])
            hints = [spec.name] + [s for s in self.catalog.suggest(name) if s != spec.name]
            self.parts.append(Unread(name, tuple(hints[:3])))
            self.unknown.clear()
            self.subject = self.pending = None
            self.count, self.count_words, self.count_start = None, (), None
            return
        count = self.count
        if count is None and plural and self.diners > 1:
            count = 1  # "plates and forks for four": one each
        elif count is None and plural:
            self.doubts.append(f"how many {self.written!r}? give a number, e.g. "
                               f"'three {self.written}'")
        elif count is None:
            count = 1  # "a plate", "some bread"
        if count is not None and count < 1:
            raise BadInput(f"request: '{' '.join(self.count_words)} {self.written}': "
                           "a count must be at least 1")
        if count is not None and count > MAX_COUNT:
            raise BadInput(f"request: '{count} {self.written}': at most {MAX_COUNT} of "
                           "one object")
        start = self.count_start if self.count_start is not None else \
            i - (definite and i > 0 and self.words[i - 1] == "the")
        earlier = [k for k, p in enumerate(self.parts) if isinstance(p, Mention)
                   and p.spec == spec and p.count == 1]
        again = self.count_start is None and not definite and not plural and any(
            isinstance(p, Mention) and p.spec == spec for p in self.parts)
        if again:
            self.doubts.append(f"{self.written!r} again: another one, or the one named "
                               "before?")
        if self.diners > 1 and self.count is not None and self.count > 1:
            self.doubts.append(f"{' '.join(self.count_words)} {self.written} for "
                               f"{self.diners} diners: each, or in all?")
        if definite and self.count is None and not plural and earlier:
            at = earlier[0]  # "the knife" of a request that named a knife already
        else:
            self.parts.append(Mention(spec, count, start, i + n))
            at = len(self.parts) - 1
            if self.separator:
                self.joined[at] = (self.separator, self.before)
                if self.count_start is None and not definite and self.links and \
                        self.links[-1].reference == self.before and \
                        self.separator in _COORDINATING:
                    # "beneath the fork and knife": of the fork alone, or of both?
                    self.doubts.append(f"{self.written!r} joined to the object of a relation")
        self.separator = ()
        self.after_pronoun = False
        if self.pending is not None:
            self.pending.reference, self.pending.end = at, i + n
            self._check_shared(self.pending)
            self.links.append(self.pending)
            self.pending = None
        self.subject, self.subject_start = at, start
        self.count, self.count_words, self.count_start = None, (), None

    def _check_shared(self, link: Link) -> None:
        """A doubt when the subject of ``link`` was listed right after another object with
        no relation of its own ("a fork and a spoon to the left of the plate": both?)."""
        separator, previous = self.joined.get(link.subject, ((), None))
        related = {k.subject for k in self.links} | {k.reference for k in self.links}
        if separator in _COORDINATING and previous is not None and previous not in related \
                and link.relation != EITHER_SIDE:
            said = self.parts[link.subject]
            name = said.spec.name if isinstance(said, Mention) else "it"
            self.doubts.append(f"does {link.relation!r} hold for what is listed before the "
                               f"{name} too?")

    def _link_pronoun(self, i: int) -> None:
        assert self.pending is not None
        link, self.pending = self.pending, None
        link.kind, link.end = "pronoun", i + 1
        self.after_pronoun = True
        if self.words[i] == "them":
            self.doubts.append("'them' may stand for several objects")
        self.links.append(link)

    def _flush_unknown(self) -> None:
        if self.unknown:
            kept = self.unknown[:len(self.unknown) - self.tail]
            name = " ".join(self.words[k] for k in kept)
            self.parts.append(Unread(name, tuple(self.catalog.suggest(name))))
            self.unknown.clear()
            self.tail = 0
            self.subject = self.pending = None

    def _end_chunk(self, sentence: bool = False, soft: bool = False) -> None:
        self._flush_unknown()
        self._check_no_dangling_count()
        if self.pending is not None:
            self.doubts.append("a relation phrase names no object after it")
            self.pending = None
        if self.distance is not None:
            self.doubts.append("a distance that relates no two objects")
            self.distance = None
        self.before = None if sentence else self.subject
        self.separator = ()
        self.after_comma = self.subject if not soft and not sentence else None
        self.count, self.count_words, self.count_start = None, (), None
        self.subject = None
        self.contents = False
        self.after_pronoun = False


def read_words(text: str, catalog: Catalog, diners: int = 1) -> MatchReader:
    """A matcher that has read ``text`` (a request for ``diners`` diners), references
    resolved."""
    reader = MatchReader(tokens(text), catalog, normalized(text), diners=diners)
    reader.read()
    resolve_references(reader)
    return reader
