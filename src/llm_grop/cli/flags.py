"""How the command line words errors: the names of the settings record's fields and the
API's parameters become its flags (``m`` -> ``--configurations``), from the record's own
metadata (:func:`llm_grop.settings.label`)."""

from __future__ import annotations

from llm_grop.errors import LLMGropError
from llm_grop.settings import flag, in_words, words

__all__ = ["cli_words", "flag", "reworded"]


def cli_words(text: str) -> str:
    """``text`` (a message or a warning of the API) with the settings it mentions spelled
    as flags (``guess=False`` -> ``--no-guess``)."""
    return words(text, "cli")


def reworded(exc: LLMGropError) -> str:
    """``exc``'s one-line message in the command line's words."""
    return in_words(exc, "cli")
