"""Fuzzing the text parsers: a request, an LLM answer (relations, or its reading of a whole
request), a distance, preferences.

Each either returns or raises one of the project's errors with a one-line message
(see ``fuzz_inputs``); ``benchmarks/fuzz.py`` runs the same targets for longer.
"""

from __future__ import annotations

from fuzz_strategies import FUZZ, holds, texts
from fuzz_targets import TARGETS
from hypothesis import given


@FUZZ
@given(texts("request"))
def test_request_parser(text: str) -> None:
    holds(TARGETS["request"], text)


@FUZZ
@given(texts("answer"))
def test_answer_reader(text: str) -> None:
    holds(TARGETS["answer"], text)


@FUZZ
@given(texts("reading"))
def test_reading_answer_reader(text: str) -> None:
    holds(TARGETS["reading_answer"], text)


@FUZZ
@given(texts("distance"))
def test_distance_parser(text: str) -> None:
    holds(TARGETS["distance"], text)


@FUZZ
@given(texts("preferences"))
def test_preferences(text: str) -> None:
    holds(TARGETS["preferences"], text)


@FUZZ
@given(texts("edge"))
def test_edge_preferences(text: str) -> None:
    holds(TARGETS["edge_preferences"], text)
