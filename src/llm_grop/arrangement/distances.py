"""Template 2 and the distance parser (paper §III-B).

The LLM is asked how many centimetres separate two related objects; the answer
is read as the **gap between the objects' edges** (see ``geometry``). A range
("5-7 centimeters") gives its midpoint; inches, millimetres, metres, feet and
number words are understood; a bare number is centimetres. When nothing can be
read, the gap is :data:`DEFAULT_GAP_CM`, as in the authors' code.
"""

from __future__ import annotations

import functools
import re
from importlib import resources

from llm_grop.world.relation import CENTER, STACKING, Relation

#: The gap used when an answer holds no readable distance, in centimetres.
DEFAULT_GAP_CM = 5.0
#: Answers above this many centimetres are taken as unreadable.
MAX_GAP_CM = 200.0

#: Centimetres per unit.
_UNITS = {
    "cm": 1.0, "centimeter": 1.0, "centimeters": 1.0, "centimetre": 1.0, "centimetres": 1.0,
    "mm": 0.1, "millimeter": 0.1, "millimeters": 0.1, "millimetre": 0.1, "millimetres": 0.1,
    "m": 100.0, "meter": 100.0, "meters": 100.0, "metre": 100.0, "metres": 100.0,
    "in": 2.54, "inch": 2.54, "inches": 2.54, '"': 2.54,
    "ft": 30.48, "foot": 30.48, "feet": 30.48,
}
_WORDS = {
    "zero": 0, "one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7,
    "eight": 8, "nine": 9, "ten": 10, "eleven": 11, "twelve": 12, "thirteen": 13,
    "fourteen": 14, "fifteen": 15, "sixteen": 16, "seventeen": 17, "eighteen": 18,
    "nineteen": 19, "twenty": 20, "thirty": 30, "forty": 40, "fifty": 50, "half": 0.5,
    "a": 1, "an": 1,
}
_TENS = {"twenty", "thirty", "forty", "fifty"}

_NUM = r"\d+(?:\.\d+)?|\.\d+"
_UNIT = (r"centimet(?:er|re)s?|cm|millimet(?:er|re)s?|mm|met(?:er|re)s?|m|inch(?:es)?|in\.|"
         r"in(?=\s*$)|ft|foot|feet")
_RANGE = re.compile(
    rf"(?:between\s+)?({_NUM})\s*(?:-|–|to|and)\s*({_NUM})\s*({_UNIT})\b\.?", re.IGNORECASE)
_SINGLE = re.compile(rf"(?<![\w.])({_NUM})\s*({_UNIT})(?![a-z])", re.IGNORECASE)
_BARE = re.compile(rf"(?<![\w.])({_NUM})(?!\w|\.\d)", re.IGNORECASE)


@functools.lru_cache(maxsize=4)
def _asset(name: str) -> str:
    return resources.files("llm_grop.arrangement").joinpath(f"prompts/{name}").read_text("utf-8")


def template2_prompt(relation: Relation) -> str:
    """Template 2 for one relation: how many centimetres apart the two objects should be."""
    if relation.relation == CENTER or relation.relation in STACKING:
        raise ValueError(f"no distance is asked for {relation.relation!r}")
    return _asset("template2.txt").format(subject=relation.subject, relation=relation.relation,
                                          reference=relation.reference).strip()


def template2_grammar() -> str:
    """GBNF that makes a model answer "About N centimeters." or "N-M centimeters."."""
    return _asset("template2.gbnf")


def _unit_cm(unit: str) -> float:
    return _UNITS[unit.lower().rstrip(".")]


def _words_to_digits(text: str) -> str:
    """"twenty-two centimeters" -> "22 centimeters" (number words followed by a unit)."""
    def repl(m: re.Match[str]) -> str:
        words = re.split(r"[\s-]+", m.group(1).lower())
        if words[0] in _TENS and len(words) == 2:
            return f"{_WORDS[words[0]] + _WORDS[words[1]]:g} {m.group(2)}"
        if len(words) == 3 and words[1] == "and" and words[2] == "half":
            return f"{_WORDS[words[0]] + 0.5:g} {m.group(2)}"
        return f"{_WORDS[words[-1]]:g} {m.group(2)}"

    names = "|".join(sorted(_WORDS, key=len, reverse=True))
    pattern = (rf"\b((?:(?:{names})(?:[\s-]+and[\s-]+a[\s-]+half|[\s-]+(?:{names}))?))\s+"
               rf"({_UNIT})(?![a-z])")
    return re.sub(pattern, repl, text, flags=re.IGNORECASE)


def parse_distance_cm(text: str) -> float | None:
    """The distance an answer gives, in centimetres, or ``None`` when none can be read."""
    text = _words_to_digits(text.replace("½", ".5"))
    value: float | None = None
    best = len(text) + 1
    m = _RANGE.search(text)
    if m:
        value, best = (float(m.group(1)) + float(m.group(2))) / 2 * _unit_cm(m.group(3)), m.start()
    m = _SINGLE.search(text)
    if m and m.start() < best:
        sign = -1.0 if text[:m.start()].rstrip().endswith("-") else 1.0
        value, best = sign * float(m.group(1)) * _unit_cm(m.group(2)), m.start()
    if value is None:
        stripped = re.sub(r"^\s*\d+[.)]\s+", "", text)
        m = _BARE.search(stripped)
        if m:
            value = float(m.group(1))
    if value is None or not 0 <= value <= MAX_GAP_CM:
        return None
    return value


def parse_distance_m(text: str) -> tuple[float, bool]:
    """``(gap in metres, whether the default was used)`` for an answer to Template 2."""
    cm = parse_distance_cm(text)
    return ((DEFAULT_GAP_CM if cm is None else cm) / 100.0, cm is None)
