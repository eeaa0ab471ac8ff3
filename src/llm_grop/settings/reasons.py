"""Pydantic's complaints about a setting, in the project's plain words, as one
:class:`~llm_grop.errors.BadInput` naming the field."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from pydantic import ValidationError

from llm_grop.errors import BadInput


def problem(exc: ValidationError) -> BadInput:
    """The first of pydantic's complaints as a :class:`BadInput` naming the field."""
    first = exc.errors(include_url=False)[0]
    loc = first.get("loc", ())
    name = str(loc[0]) if loc else "settings"
    given = first.get("input")
    shown = None if isinstance(given, list | tuple | Mapping) else given
    return BadInput(first_reason(first), param=name, value=shown)


#: What a type error expected, in plain words.
_EXPECTED = {"int_type": "a whole number", "int_parsing": "a whole number",
             "int_from_float": "a whole number", "float_type": "a number",
             "float_parsing": "a number", "string_type": "text", "bool_type": "true or false",
             "bool_parsing": "true or false", "tuple_type": "a list", "finite_number":
             "a finite number", "literal_error": "one of {expected}"}
#: Plain words for a bound that was not kept.
_BOUNDS = {"greater_than": "must be greater than {gt}", "greater_than_equal":
           "must be at least {ge}", "less_than": "must be less than {lt}",
           "less_than_equal": "must be at most {le}", "string_too_short":
           "must not be empty", "string_too_long": "must be at most {max_length} characters"}


def first_reason(error: Mapping[str, Any]) -> str:
    """One pydantic error in plain words."""
    kind = error.get("type", "")
    ctx = dict(error.get("ctx") or {})
    if kind in _BOUNDS:
        return _BOUNDS[kind].format(**ctx)
    if kind in _EXPECTED:
        return "expected " + _EXPECTED[kind].format(**ctx)
    return str(error.get("msg", "not valid")).removeprefix("Value error, ")


def unknown_words(name: str, names: Sequence[str]) -> str:
    """What to say of a setting that does not exist, with the nearest of ``names``."""
    import difflib

    near = difflib.get_close_matches(name, list(names), n=3)
    return "unknown setting" + (f"; did you mean {', '.join(map(repr, near))}?" if near else "")


