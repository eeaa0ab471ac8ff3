"""The fast path of reading a request: the catalog matcher alone.

How the matcher reads (its vocabulary: :mod:`llm_grop.language.vocabulary`):

* Words are matched against the catalog's names, synonyms and plurals, longest match
  first ("dinner knife" over "knife", "mug lid" over "mug").
* A count may precede an object: digits, ``one`` to ``twenty``, ``a pair of``, ``a dozen``.
  Without a count an object counts once; at most 12 of one object, 30 in all.
* Politeness, verbs and place phrases ("please", "set the table with", "if you can",
  "nothing else", "in front of me") are fillers; commas, semicolons, "and", "with" and
  "plus" separate objects. "or" is refused: the request must say what to set.
* What an object holds is not an object ("a glass of water"), unless the catalog has the
  name ("a glass of wine" is a wine glass).
* Relation phrases between objects are stated relations ("a mug on a coaster", "the fork
  to the left of the plate", "the knife beside it", "the fork and knife either side of the
  plate"), with a distance before them ("the fork 2 cm left of the plate"). "On its left"
  is "to the left of it", and "it" must stand for one object: the only one named before
  in its sentence, or the one a "with" introduced the subject by ("a bread plate with
  bread on it"; :mod:`llm_grop.language.references`). A phrase without a reference ("on
  the left") relates to the reference stated nearby, else to that one object.
* Whatever could be read two ways is left to the LLM: a relation after a list ("a fork
  and a spoon to the left of the plate": both?), a plural without a number, "it" that
  could stand for two objects, a name repeated without "the" or "another", counts for
  several diners ("two plates for two people"), a negation ("without a fork").
* Diners: "for two", "for 4 people", "three place settings": the objects named are then
  one diner's setting.

The matcher's reading stands alone only when it accounts for every word and resolves
every reference (:attr:`FastReading.reading`); otherwise the request goes to the LLM
(:mod:`llm_grop.language.understanding`), or, without one, is refused with the first
chunk it could not read (:meth:`FastReading.error`).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

from llm_grop.errors import BadInput, UnknownObject
from llm_grop.language.matcher import read_words
from llm_grop.language.parts import Link, Mention, Unread
from llm_grop.language.reading import Reading, ReadObject, ReadRelation, to_request, unrelated
from llm_grop.language.vocabulary import EITHER_SIDE, request_words
from llm_grop.language.words import is_number, normalized
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import CENTER
from llm_grop.world.request import (
    MAX_DINERS,
    MAX_REQUEST_CHARS,
    Request,
    Wanted,
    number_items,
)

_SURROGATE = re.compile("[\ud800-\udfff]")
#: Phrases that give one diner something, which a request for several leaves open.
_ONE_DINER = re.compile(r"\bfor\s+(?:one|me|myself|him|her|one person|the host)\b")
EXAMPLE = "e.g. 'a dinner plate, a dinner fork and a dinner knife'"


@dataclass(frozen=True)
class FastReading:
    """What the catalog matcher made of a request.

    ``reading`` is its reading when it accounts for every word, else ``None``; then
    ``unread`` holds the chunks it could not read and ``doubts`` what it could not
    resolve. ``named`` maps each catalog kind the request names to the counts it gives
    (0: no number, "some strawberries").
    """

    text: str
    diners: int
    reading: Reading | None
    unread: tuple[Unread, ...] = ()
    doubts: tuple[str, ...] = ()
    named: Mapping[str, tuple[int, ...]] = field(default_factory=dict)

    def error(self) -> BadInput:
        """The one-line error that refuses the request without an LLM: the first unread
        chunk (with suggestions), else the first doubt, else "no object named"."""
        if self.unread:
            return UnknownObject(self.unread[0].text, list(self.unread[0].suggestions))
        if self.doubts:
            return BadInput(f"request: {self.doubts[0]}")
        return BadInput(f"request: no object named in {self.text!r}; name the objects to "
                        f"set, {EXAMPLE}")


def check_text(text: str) -> None:
    """Raises :class:`BadInput` for an empty or overlong request, or one whose bytes were
    not UTF-8."""
    if not text.strip():
        raise BadInput(f"request: empty; name the objects to set, {EXAMPLE}")
    if len(text) > MAX_REQUEST_CHARS:
        raise BadInput(f"request: {len(text)} characters; at most {MAX_REQUEST_CHARS}")
    bad = _SURROGATE.search(text)
    if bad:
        # What a command line holds when its bytes are not UTF-8 (surrogateescape).
        byte = ord(bad.group(0)) - 0xDC00 if ord(bad.group(0)) >= 0xDC80 else None
        what = f"the byte 0x{byte:02x}" if byte is not None else "a lone surrogate"
        raise BadInput(f"request: not UTF-8 text (character {bad.start() + 1} is {what}); "
                       "write the request in UTF-8")


@functools.cache
def _diner_patterns() -> tuple[re.Pattern[str], ...]:
    number = r"([0-9]+|" + "|".join(request_words().numbers) + ")"
    people = r"(?:\s+(?:people|persons|diners|guests|adults|of\s+us|others))?"
    return (
        re.compile(r"\bfor\s+(?:the\s+|all\s+)?" + number + people + r"(?![\w'])"),
        re.compile(r"\bfor\s+a\s+(?:family|party|group)\s+of\s+" + number + r"(?![\w'])"),
        re.compile(r"\b" + number + r"\s+(?:place\s+settings|settings|places|covers|"
                   r"people|persons|diners|guests)\b"),
    )


def diner_count(text: str) -> tuple[int, str]:
    """How many diners ``text`` sets the table for, and the text without that phrase
    (spaces keep the other words' places). Raises :class:`BadInput` outside 1 to 12."""
    low = text.lower()
    for pattern in _diner_patterns():
        m = pattern.search(low)
        if m:
            word = m.group(1)
            n = int(word) if is_number(word) else request_words().numbers.get(word, 0)
            if not 1 <= n <= MAX_DINERS:
                raise BadInput(f"request: {m.group(0)!r}: between 1 and {MAX_DINERS} diners")
            return n, text[:m.start()] + " " * (m.end() - m.start()) + text[m.end():]
    return 1, text


def read_request(text: str, catalog: Catalog) -> FastReading:
    """What the catalog matcher makes of ``text`` (see the module docstring).

    Raises :class:`BadInput` for an empty or overlong request, "or", a count of 0 or over
    12, a negative distance, or more than 12 diners: no reader could take those.
    """
    check_text(text)
    diners, rest = diner_count(normalized(text))
    reader = read_words(rest, catalog, diners)
    doubts = list(reader.doubts)
    if diners > 1 and _ONE_DINER.search(rest.lower()):
        doubts.append(f"{diners} diners, and something for one of them")
    mentions = [(k, p) for k, p in enumerate(reader.parts) if isinstance(p, Mention)]
    named: dict[str, list[int]] = {}
    for _, m in mentions:
        named.setdefault(m.spec.name, []).append(m.count or 0)
    unread = tuple(p for p in reader.parts if isinstance(p, Unread))
    base = FastReading(" ".join(text.split()), diners, None, unread, (),
                       {k: tuple(v) for k, v in named.items()})
    if not mentions and not unread and not doubts:
        doubts.append(f"no object named in {base.text!r}; name the objects to set, "
                      f"{EXAMPLE}")
    if unread or doubts:
        return replace(base, doubts=tuple(doubts))

    def words(start: int, end: int) -> str:
        a, b = reader.span(start, end)
        return " ".join(rest[a:b].split())

    objects = tuple(ReadObject(m.spec.name, m.count or 1, "request", words(m.start, m.end))
                    for _, m in mentions)
    _, names = number_items([Wanted(m.spec, m.count or 1) for _, m in mentions])
    at = {k: names[n] for n, (k, _) in enumerate(mentions)}
    relations: list[ReadRelation] = []
    for link in reader.links:
        relations += _relations(link, at, words(link.start, link.end), doubts)
    reading = Reading(base.text, objects, tuple(relations), diners)
    doubts += [why for _, why in unrelated(reading, catalog)]
    if doubts:
        return replace(base, doubts=tuple(doubts))
    return replace(base, reading=reading)


def _relations(link: Link, at: Mapping[int, Sequence[str]], words: str, doubts: list[str]
               ) -> list[ReadRelation]:
    """The relations one link states between items: each subject to a single reference
    ("two forks to the left of the plate"), instance by instance when both sides count the
    same ("two mugs on two coasters"); other counts are doubts."""
    subjects = at[link.subject]
    if link.relation == CENTER:
        if len(subjects) > 1:
            doubts.append(f"which of the {len(subjects)} {subjects[0]}s goes in the center?")
            return []
        return [ReadRelation(subjects[0], CENTER, None, link.distance_cm, None, words)]
    if link.reference is None:
        return []  # its doubt is recorded already
    references = at[link.reference]
    if link.relation == EITHER_SIDE:
        # The two objects either side in the order they were named.
        first, second = sorted((link.subject, link.partner if link.partner is not None
                                else link.subject))
        subjects, partners = at[first], at[second] if link.partner is not None else []
        if len(subjects) != 1 or len(partners) != 1 or len(references) != 1:
            doubts.append("'either side of' needs two single objects and one reference")
            return []
        return [ReadRelation(subjects[0], EITHER_SIDE, references[0], link.distance_cm,
                             partners[0], words)]
    if len(references) == 1:
        pairs = [(s, references[0]) for s in subjects]
    elif len(references) == len(subjects):
        pairs = list(zip(subjects, references, strict=True))
    else:
        doubts.append(f"{len(subjects)} {subjects[0]} {link.relation} {len(references)} "
                      f"{references[0]}: say which goes with which")
        return []
    return [ReadRelation(s, link.relation, r, link.distance_cm, None, words) for s, r in pairs]


def parse_request(text: str, catalog: Catalog) -> Request:
    """The request ``text`` makes, read by the catalog matcher alone.

    Raises :class:`BadInput` as :func:`read_request` does, :class:`UnknownObject` (with
    suggestions) for the first chunk the catalog does not account for, and
    :class:`BadInput` for what else the matcher cannot resolve without an LLM.
    """
    fast = read_request(text, catalog)
    if fast.reading is None:
        raise fast.error()
    return to_request(fast.reading, catalog)


__all__ = ["EXAMPLE", "FastReading", "check_text", "diner_count", "parse_request",
           "read_request"]
