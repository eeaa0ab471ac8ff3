"""Reading a distance out of free text (an LLM's answer to Template 2, a preference):
:func:`parse_distance_cm`. How it reads:

* A number with a unit wins over numbers without one (list numbering, "Step 2").
  The first such distance in the text is taken.
* A range ("5-7 centimeters", "5 to 7 cm", "between 5 and 7 cm", "5 or 6 cm")
  gives its midpoint.
* Units: centimetres, millimetres, metres, inches ("in." or a final "in", never
  the word "in" inside a sentence), feet. Number words ("five", "twenty-two",
  "one and a half", "half an inch"; the table of ``request_words.yaml``) are understood.
* Without any unit, the first number is read as centimetres.
* A negative distance, one above :data:`MAX_GAP_CM`, or none at all gives ``None``
  (:func:`llm_grop.arrangement.distances.parse_distance_m` then falls back to a default).
* Numbers: "1,000" (comma thousands groups), "1e3" (exponents), "2½"/"¼"/"¾".
  The text is NFKC-normalised first, so fullwidth ("１０ ｃｍ") and mathematical
  digits read as ASCII ones and thin or no-break spaces as spaces; only ASCII
  digits are then read (Arabic-Indic and other scripts' digits are not). The
  Unicode minus "−", "‐", "‑", "‒" and the en and em dashes are hyphens (:data:`DASHES`,
  the one table of them), so "−5 cm" is negative and "5–7 cm" a range. Superscripts,
  subscripts, circled digits and other fractions ("²", "₂", "①", "⅓"), which NFKC would
  turn into digits, are read as spaces: "5 cm²" is 5 cm, and "① Place it" holds no
  number.
"""

from __future__ import annotations

import functools
import re
import unicodedata
from collections.abc import Mapping

from llm_grop.language.vocabulary import request_words

#: Answers above this many centimetres are taken as unreadable.
MAX_GAP_CM = 200.0

#: Centimetres per unit, by the unit's first letters (see ``_unit_cm``).
_UNIT_CM = {"cm": 1.0, "centi": 1.0, "mm": 0.1, "milli": 0.1, "m": 100.0, "met": 100.0,
            "in": 2.54, "″": 2.54, "ft": 30.48, "foot": 30.48, "feet": 30.48}

# ASCII digits only ([0-9], not \d): other scripts' digits are not read (module docstring).
_NUM = r"(?:(?:[0-9]{1,3}(?:,[0-9]{3})+|[0-9]+)(?:\.[0-9]+)?|\.[0-9]+)(?:e[+-]?[0-9]+)?"
_UNIT = (r"centimet(?:er|re)s?|cms?|millimet(?:er|re)s?|mm|met(?:er|re)s?|m|"
         r"inch(?:es)?|in\.|in(?=\s*(?:$|[,;:)!?]))|″|ft|foot|feet")
_QUANTITY = re.compile(
    rf"(?<![\w.])({_NUM})(?:\s*({_UNIT})(?![a-z]))?(?:\s*(?:-|to|and|or)\s*({_NUM}))?\s*({_UNIT})"
    r"(?![a-z])")
_BARE = re.compile(rf"(?<![\w.])({_NUM})(?:\s*(?:-|to|or)\s*({_NUM}))?(?![\w])")
_LIST_NUMBER = re.compile(r"^\s*(?:step\s*)?[0-9]+\s*[.):]\s+", re.MULTILINE)
#: The characters read as a hyphen (so as a minus sign or a range's dash) wherever
#: llm-grop reads text: the hyphen, the Unicode hyphen, non-breaking hyphen and figure
#: dash, the en and em dashes, and the minus sign.
DASHES = "-\u2010\u2011\u2012\u2013\u2014\u2212"
_AS_HYPHEN = str.maketrans(dict.fromkeys(DASHES[1:], "-"))
#: Fractions read as decimals (before NFKC, which would make "½" the digits "1⁄2").
_FRACTIONS = {"½": ".5", "¼": ".25", "¾": ".75"}


#: A unit written as a word of its own ("cm", "centimetres", "inches"): never the word
#: "in", which in a request is a relation ("a strawberry in the bowl").
_UNIT_WORD = re.compile(r"centimet(?:er|re)s?|cms?|millimet(?:er|re)s?|mm|met(?:er|re)s?|m|"
                        r"inch(?:es)?|ft|foot|feet")


def unit_cm(word: str) -> float | None:
    """Centimetres per unit of a unit word ("cm", "metres", "inch"), else ``None``."""
    return _unit_cm(word) if _UNIT_WORD.fullmatch(word) else None


def _unit_cm(unit: str) -> float:
    unit = unit.rstrip(".")
    for prefix in ("centi", "milli", "met", "cm", "mm", "in", "ft", "foot", "feet", "″", "m"):
        if unit.startswith(prefix):
            return _UNIT_CM[prefix]
    raise ValueError(f"unknown unit {unit!r}")


@functools.cache
def _number_words() -> tuple[Mapping[str, int], Mapping[str, int], Mapping[str, int]]:
    """The number words of ``request_words.yaml`` (the one table of them) as this module
    reads them: those below twenty, the same without "one" (a pronoun as often as a
    number, so read only before a unit), and the tens, which one below twenty may follow
    ("twenty-two")."""
    numbers = request_words().numbers
    below_twenty = {w: n for w, n in numbers.items() if n < 20}
    ones = {w: n for w, n in below_twenty.items() if w != "one"}
    tens = {w: n for w, n in numbers.items() if 20 <= n < 100 and n % 10 == 0}
    return below_twenty, ones, tens


def _words_to_digits(text: str) -> str:
    """Number words as digits: "twenty-two cm" -> "22 cm", "half an inch" -> "0.5 inch"."""
    below_twenty, ones, tens = _number_words()
    unit = rf"(?=\s*(?:{_UNIT})(?![a-z]))"
    text = re.sub(rf"\b({'|'.join(tens)})(?:[\s-]+({'|'.join(below_twenty)}))?\b",
                  lambda m: str(tens[m.group(1)] + (below_twenty[m.group(2)] if m.group(2)
                                                    else 0)),
                  text)
    text = re.sub(rf"\b({'|'.join(ones)})\b", lambda m: str(ones[m.group(1)]), text)
    text = re.sub(r"\b(\d+|one|an?)\s+and\s+(?:a|one)\s+half\b",
                  lambda m: f"{below_twenty.get(m.group(1), 1) + 0.5:g}"
                  if not m.group(1)[0].isdigit() else f"{int(m.group(1)) + 0.5:g}", text)
    text = re.sub(rf"\bhalf\s+(?:a|an)\b{unit}", "0.5", text)
    text = re.sub(rf"\b(?:a|an)\s+half\b{unit}", "0.5", text)
    return re.sub(rf"\b(?:a|an|one)\b{unit}", "1", text)


def plain_dashes(text: str) -> str:
    """``text`` with each of :data:`DASHES` an ASCII hyphen."""
    return text.translate(_AS_HYPHEN)


def _in_range(cm: float) -> float | None:
    return cm if 0.0 <= cm <= MAX_GAP_CM else None


def _number(text: str) -> float:
    """A matched ``_NUM`` as a float ("1,000" -> 1000.0; "1e999" -> inf)."""
    return float(text.replace(",", ""))


def _normalized(text: str) -> str:
    """``text`` lower case and NFKC-normalised, with the module docstring's dashes,
    fractions and non-decimal digits replaced."""
    for fraction, decimal in _FRACTIONS.items():
        text = text.replace(fraction, decimal)
    if not text.isascii():
        # NFKC turns "²", "①" and "⅓" into digits; they are no numbers of a distance.
        text = "".join(" " if ch.isnumeric() and not ch.isdecimal() else ch for ch in text)
        # NFKC makes the double prime (inches) two primes.
        text = unicodedata.normalize("NFKC", text).replace("′′", "″")
    return plain_dashes(text.lower())


def parse_distance_cm(text: str) -> float | None:
    """The distance an answer gives, in centimetres, or ``None`` when none can be read."""
    text = _words_to_digits(re.sub(r"[*_`]", "", _normalized(text)))
    m = _QUANTITY.search(text)
    if m:
        if re.search(r"(?:-|minus\s*)$", text[:m.start()]):
            return None
        low = _number(m.group(1))
        high = _number(m.group(3)) if m.group(3) else low
        cm = (low + high) / 2 * _unit_cm(m.group(4))
        return _in_range(cm)
    m = _BARE.search(_LIST_NUMBER.sub("", text))
    if m is None:
        return None
    if re.search(r"(?:-|minus\s*)$", _LIST_NUMBER.sub("", text)[:m.start()]):
        return None
    low = _number(m.group(1))
    high = _number(m.group(2)) if m.group(2) else low
    return _in_range((low + high) / 2)




__all__ = ["DASHES", "MAX_GAP_CM", "parse_distance_cm", "plain_dashes", "unit_cm"]
