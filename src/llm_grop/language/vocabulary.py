"""The one vocabulary of words requests, preferences and the LLM's answers are read with.

Two data files beside this module hold it: ``vocabulary.yaml``, the relation phrases ("to
the left of", "on its right", "beside", "either side of"), and ``request_words.yaml``, the
words of a request that are neither objects nor relations (counts, vague quantities,
fillers, separators). The request reader (:mod:`llm_grop.language.matcher`), the reader of
the LLM's answers (:mod:`llm_grop.language.answer_tokens`) and preferences all match
relation phrases through :meth:`PhraseTable.match`, so a phrase means one thing wherever
it is written.
"""

from __future__ import annotations

import functools
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from typing import Any

import yaml

from llm_grop.world.relation import RELATION_NAMES, Choice, Relation

#: Ambiguous relation words: "beside" is to the left of or to the right of its reference,
#: as the LLM or clingo with the other relations decides.
BESIDE = "beside"
#: "A and B either side of R": one of A and B to the left of R, the other to its right.
EITHER_SIDE = "either side of"
#: The relations a reading may state: the contract's, and the ambiguous words.
READING_RELATIONS: tuple[str, ...] = (*RELATION_NAMES, BESIDE, EITHER_SIDE)

ARTICLES = frozenset({"a", "an", "the"})

#: Directions said of "its" ("to its upper left"), as words.
_ITS_DIRECTIONS = frozenset({("left",), ("right",), ("upper", "left"), ("upper", "right"),
                             ("lower", "left"), ("lower", "right"), ("top", "left"),
                             ("top", "right"), ("bottom", "left"), ("bottom", "right")})


def its_at(words: Sequence[str], i: int) -> tuple[int, tuple[str, ...]] | None:
    """"on its left (hand side)" at ``words[i]`` as ``(end, words to read instead)``: "to the
    left of it", so that the pronoun is read as a reference like any other; else ``None``."""
    if words[i] not in ("to", "on", "at", "towards"):
        return None
    j = i + 1 + (i + 1 < len(words) and words[i + 1] == "the")
    if j >= len(words) or words[j] != "its":
        return None
    for n in (2, 1):
        direction = tuple(words[j + 1:j + 1 + n])
        if len(direction) == n and direction in _ITS_DIRECTIONS:
            end = j + 1 + n
            while end < len(words) and words[end] in ("hand", "side"):
                end += 1
            return end, ("to", "the", *direction, "of", "it")
    return None


def its_segments(words: Sequence[str]) -> list[tuple[int, int, tuple[str, ...]]]:
    """``words`` cut into ``(start, end, words to read)``: each word as itself, and each
    :func:`its_at` phrase as "to the left of it"."""
    out: list[tuple[int, int, tuple[str, ...]]] = []
    i = 0
    while i < len(words):
        found = its_at(words, i)
        end, instead = found if found is not None else (i + 1, (words[i],))
        out.append((i, end, instead))
        i = end
    return out


def expand_its(words: Sequence[str]) -> list[str]:
    """``words`` with every :func:`its_at` phrase read as "to the left of it"."""
    return [w for _, _, instead in its_segments(words) for w in instead]


@dataclass(frozen=True)
class PhraseMatch:
    """A relation phrase found in a list of words: the relation it names (a contract name or
    an ambiguous word), whether it is bare (names no reference), and the index after it."""

    relation: str
    bare: bool
    end: int


@dataclass(frozen=True)
class PhraseTable:
    """Relation phrases (as word tuples, articles and skipped words left out) -> (relation,
    bare); ``ambiguous`` maps each ambiguous word to the relations it may stand for."""

    phrases: Mapping[tuple[str, ...], tuple[str, bool]]
    skip: frozenset[str]
    ambiguous: Mapping[str, tuple[str, ...]]
    longest: int
    #: Every non-empty prefix of a phrase, so a match can stop as soon as none continues.
    prefixes: frozenset[tuple[str, ...]]

    def starts(self, word: str) -> bool:
        """Whether a phrase may start at ``word`` (a cheap test before :meth:`match`)."""
        return word not in self.skip and word not in ARTICLES and (word,) in self.prefixes

    def match(self, words: Sequence[str], i: int) -> PhraseMatch | None:
        """The longest phrase starting at ``words[i]``; articles and skipped words are
        passed over inside a phrase, never at its start."""
        if not self.starts(words[i]):
            return None
        kept: tuple[str, ...] = ()
        best: PhraseMatch | None = None
        j = i
        while j < len(words) and len(kept) < self.longest:
            word = words[j]
            if word not in self.skip and word not in ARTICLES:
                kept += (word,)
                if kept not in self.prefixes:
                    break
                hit = self.phrases.get(kept)
                if hit is not None:
                    best = PhraseMatch(hit[0], hit[1], j + 1)
            j += 1
        return best


def beside(subject: str, reference: str, words: str = "", source: str = "llm",
           gap_m: float | None = None) -> Choice:
    """"``subject`` beside ``reference``": one of the sides ``vocabulary.yaml`` gives it."""
    return Choice(tuple((Relation(subject, side, reference, words, source, gap_m),)
                        for side in phrase_table().ambiguous[BESIDE]), words)


def either_side(first: str, second: str, reference: str, words: str = "",
                source: str = "llm", gap_m: float | None = None) -> Choice:
    """"``first`` and ``second`` either side of ``reference``": one on each of the two
    sides ``vocabulary.yaml`` gives it."""
    a, b = phrase_table().ambiguous[EITHER_SIDE][:2]

    def rel(subject: str, side: str) -> Relation:
        return Relation(subject, side, reference, words, source, gap_m)

    return Choice(((rel(first, a), rel(second, b)), (rel(first, b), rel(second, a))), words)


def _asset(name: str) -> Any:
    text = resources.files("llm_grop.language").joinpath(name).read_text("utf-8")
    return yaml.safe_load(text)


def _words(text: object) -> tuple[str, ...]:
    return tuple(str(text).lower().replace("-", " ").split())


@functools.cache
def phrase_table() -> PhraseTable:
    """The relation phrases of ``vocabulary.yaml``; raises ``ValueError`` naming the entry
    when the file names an unknown relation or gives one phrase two meanings."""
    data = _asset("vocabulary.yaml")
    skip = frozenset(str(w) for w in data["skip"])
    ambiguous = {str(k): tuple(str(r) for r in v) for k, v in data["ambiguous"].items()}
    phrases: dict[tuple[str, ...], tuple[str, bool]] = {}
    for section, bare in (("relations", False), ("bare", True)):
        for relation, texts in data[section].items():
            if relation not in READING_RELATIONS:
                raise ValueError(f"vocabulary.yaml: {section}: unknown relation {relation!r}")
            for text in texts:
                key = tuple(w for w in _words(text) if w not in skip and w not in ARTICLES)
                if not key:
                    raise ValueError(f"vocabulary.yaml: {section}.{relation}: {text!r} is "
                                     "only skipped words")
                if phrases.get(key, (relation, bare)) != (relation, bare):
                    raise ValueError(f"vocabulary.yaml: {text!r} means both "
                                     f"{phrases[key][0]!r} and {relation!r}")
                phrases[key] = (relation, bare)
    prefixes = frozenset(p[:k] for p in phrases for k in range(1, len(p) + 1))
    return PhraseTable(phrases, skip, ambiguous, max(len(p) for p in phrases), prefixes)


@dataclass(frozen=True)
class RequestWords:
    """The words of ``request_words.yaml``, phrases as word tuples.

    ``counts`` holds every phrase that counts the next object (number words included);
    ``articles`` those that count 1 but may dangle harmlessly; ``per_diner`` those that
    say "for every diner", fillers when a request sets the table for several.
    """

    numbers: Mapping[str, int]
    counts: Mapping[tuple[str, ...], int]
    articles: frozenset[tuple[str, ...]]
    vague: frozenset[tuple[str, ...]]
    fillers: frozenset[tuple[str, ...]]
    per_diner: frozenset[tuple[str, ...]]
    separator_words: frozenset[tuple[str, ...]]
    separator_chars: frozenset[str]
    longest: int


@functools.cache
def request_words() -> RequestWords:
    """The request words of ``request_words.yaml``."""
    data = _asset("request_words.yaml")
    numbers = {str(k): int(v) for k, v in data["numbers"].items()}
    counts = {(w,): n for w, n in numbers.items()}
    counts.update({_words(k): int(v) for k, v in data["counts"].items()})
    fillers = {_words(p) for p in data["fillers"]} | {_words(w) for w in data["words"]}
    separators = frozenset(_words(w) for w in data["separator_words"])
    per_diner = frozenset(_words(p) for p in data["per_diner"])
    every: Iterable[tuple[str, ...]] = [*counts, *fillers, *separators, *per_diner]
    return RequestWords(numbers, counts, frozenset(_words(a) for a in data["articles"]),
                        frozenset(_words(v) for v in data["vague"]), frozenset(fillers),
                        per_diner, separators, frozenset(str(data["separator_chars"])),
                        max(len(p) for p in every))


@dataclass(frozen=True)
class DiningWords:
    """The words of ``dining_words.yaml``: ``every`` one may stand for tableware;
    ``contents`` are what a container may hold."""

    every: frozenset[str]
    contents: frozenset[str]


@functools.cache
def dining_words() -> DiningWords:
    """The words of ``dining_words.yaml``."""
    data = _asset("dining_words.yaml")
    every = frozenset(str(w).lower() for words in data.values() for w in words)
    return DiningWords(every, frozenset(str(w).lower() for w in data["contents"]))


def longest_at(words: Sequence[str], i: int, phrases: Collection[tuple[str, ...]],
               limit: int) -> int:
    """Length of the longest phrase of ``phrases`` (each at most ``limit`` words) that starts
    at ``words[i]``, else 0."""
    for n in range(min(limit, len(words) - i), 0, -1):
        if tuple(words[i:i + n]) in phrases:
            return n
    return 0


__all__ = ["ARTICLES", "BESIDE", "EITHER_SIDE", "READING_RELATIONS", "DiningWords",
           "its_at", "its_segments",
           "PhraseMatch",
           "PhraseTable", "RequestWords", "beside", "dining_words", "either_side",
           "expand_its", "longest_at", "phrase_table", "request_words"]
