"""Fuzzing the file parsers: catalog and scene YAML, replay JSONL, preferences YAML.

Each either returns or raises one of the project's errors with a one-line message
(see ``fuzz_inputs``); ``benchmarks/fuzz.py`` runs the same targets for longer.
"""

from __future__ import annotations

from fuzz_inputs import Input
from fuzz_strategies import FUZZ, files, holds, texts
from fuzz_targets import TARGETS
from hypothesis import given


@FUZZ
@given(files("catalog"))
def test_catalog_yaml(data: Input) -> None:
    holds(TARGETS["catalog"], data)


@FUZZ
@given(files("scene"))
def test_scene_yaml(data: Input) -> None:
    holds(TARGETS["scene"], data)


@FUZZ
@given(files("replay"))
def test_replay_file(data: Input) -> None:
    holds(TARGETS["replay"], data)


@FUZZ
@given(texts("answer"))
def test_replay_file_round_trip(text: str) -> None:
    holds(TARGETS["record_round_trip"], text)


@FUZZ
@given(files("preference_file"))
def test_preference_file(data: Input) -> None:
    holds(TARGETS["preference_file"], data)
