"""Cutting a request into tokens: words (lower case), numbers, separators and sentence
ends, with their offsets in the text, and "on its left" written "to the left of it" so
that the pronoun is read as a reference (the first step of :mod:`llm_grop.language.matcher`).
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from llm_grop.language.distance import plain_dashes, unit_cm
from llm_grop.language.vocabulary import its_segments, request_words

#: A word, or a number with its decimals: "2.5 cm" is one number and a unit.
_TOKEN = re.compile(r"[0-9]+(?:\.[0-9]+)?|[^\W\d_]+(?:'[^\W\d_]+)*")
#: Characters that end a sentence (other separators only separate objects).
_SENTENCE_END = frozenset(".!?\n")


@dataclass(frozen=True)
class Token:
    """A word of the request (lower case), ``","`` for a separator or ``"."`` for a sentence
    end, with its character offsets in the text read."""

    word: str
    start: int
    end: int


def normalized(text: str) -> str:
    """``text`` in the form the matcher reads: NFKC (fullwidth letters and digits become
    ASCII, ligatures split) except for other numerals such as '²' and '①', which stay
    as they are rather than become counts; typographic apostrophes and dashes made plain."""
    if text.isascii():
        return text
    out = [c if unicodedata.category(c) == "No" else unicodedata.normalize("NFKC", c)
           for c in text]
    return plain_dashes("".join(out).replace("\u2019", "'").replace("\u2018", "'"))


def is_number(word: str) -> bool:
    """Whether ``word`` is a count in ASCII digits (``str.isdigit`` also accepts '²')."""
    return word.isascii() and word.isdigit() and len(word) <= 6


def tokens(text: str) -> list[Token]:
    """The words of ``text`` (lower case; hyphens inside words read as spaces), with a
    ``","`` token for each run of separators, a ``"."`` for a sentence end, and a ``"-"``
    for a minus sign before a number; offsets are into ``normalized(text)``."""
    text = normalized(text)
    separators = request_words().separator_chars
    out: list[Token] = []
    pos = 0
    for m in _TOKEN.finditer(text):
        gap = text[pos:m.start()]
        if _SENTENCE_END.intersection(gap.replace("...", " ")) and out:
            out.append(Token(".", pos, m.start()))
        elif separators.intersection(gap):
            out.append(Token(",", pos, m.start()))
        if m.group(0)[0].isdigit() and re.search(r"(?:^|[\s(])-\s*$", gap):
            out.append(Token("-", m.start() - 1, m.start()))
        out.append(Token(m.group(0).lower(), m.start(), m.end()))
        pos = m.end()
    return _expand_its(out)


def _expand_its(toks: list[Token]) -> list[Token]:
    """Tokens with "on its left (hand side)" read as "to the left of it"
    (:func:`~llm_grop.language.vocabulary.its_segments`), spanning the words they replace."""
    out: list[Token] = []
    for start, end, instead in its_segments([t.word for t in toks]):
        if end == start + 1 and instead == (toks[start].word,):
            out.append(toks[start])
        else:
            out += [Token(w, toks[start].start, toks[end - 1].end) for w in instead]
    return out


def distance_at(words: Sequence[str], i: int, numbers: Mapping[str, int]
                ) -> tuple[float, int] | None:
    """The distance, centimetres, stated at ``words[i]`` ("2 cm", "2.5 centimetres", "an
    inch", "one and a half inches"; negative after "-" or "minus"), and the index after
    its unit; ``None`` when no number and unit start there. ``numbers``: number words."""
    j, sign = i, 1.0
    if words[j] in ("-", "minus"):
        j, sign = j + 1, -1.0
    value: float | None = None
    if j < len(words) and re.fullmatch(r"[0-9]+(?:\.[0-9]+)?", words[j]):
        value, j = float(words[j]), j + 1
    elif j < len(words) and words[j] in numbers:
        value, j = float(numbers[words[j]]), j + 1
    elif j + 1 < len(words) and words[j] == "half" and words[j + 1] in ("a", "an"):
        value, j = 0.5, j + 2
    elif j < len(words) and words[j] in ("a", "an", "one"):
        value, j = 1.0, j + 1
    if value is not None and words[j:j + 3] == ["and", "a", "half"]:
        value, j = value + 0.5, j + 3
    per_unit = unit_cm(words[j]) if value is not None and j < len(words) else None
    if per_unit is None:
        return None
    return sign * (value or 0.0) * per_unit, j + 1
