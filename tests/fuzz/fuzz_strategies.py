"""Hypothesis strategies for the fuzz tests: Unicode of every kind, and the shared
grammar-based generators of :mod:`fuzz_inputs` driven by Hypothesis's random streams."""

from __future__ import annotations

import random

from fuzz_inputs import SPECIAL_CHARS, Input, file_input, grammar_text, mutate
from fuzz_inputs import text_input as _text_input
from fuzz_targets import Target, check
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

#: Modest and repeatable: the benchmark (benchmarks/fuzz.py) runs the long campaigns.
FUZZ = settings(max_examples=200, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

_RANDOMS = st.randoms(use_true_random=False)
#: Any text without surrogates: every Unicode category, astral planes included.
UNICODE = st.text(st.characters(blacklist_categories=("Cs",)), max_size=300)
#: Look-alike digits, dashes, odd spaces and line breaks among plain characters.
SPECIAL = st.lists(st.sampled_from([*SPECIAL_CHARS, *"0123456789 .,-abcm\n"]),
                   max_size=80).map("".join)
#: A short piece repeated into a long one.
LONG = st.builds(lambda piece, n: piece * n, st.text(min_size=1, max_size=20),
                 st.integers(100, 2_000))


def texts(kind: str) -> st.SearchStrategy[str]:
    """Inputs for the text parser of ``kind`` (a key of ``fuzz_inputs._WORDS_BY_KIND``):
    raw Unicode, long text, the grammar of valid inputs, and mutations of it."""

    def grammar(rng: random.Random) -> str:
        return grammar_text(rng, kind)

    def mutated(rng: random.Random) -> str:
        return mutate(rng, grammar_text(rng, kind))

    def sample(rng: random.Random) -> str:
        return _text_input(rng, kind)

    return st.one_of(UNICODE, SPECIAL, LONG, _RANDOMS.map(grammar), _RANDOMS.map(mutated),
                     _RANDOMS.map(sample))


def files(kind: str) -> st.SearchStrategy[Input]:
    """Inputs for the file parser of ``kind``: the shared generator's YAML or JSONL (and
    bytes that are not UTF-8), plus raw Unicode."""

    def sample(rng: random.Random) -> Input:
        return file_input(rng, kind)

    return st.one_of(_RANDOMS.map(sample), _RANDOMS.map(sample), UNICODE, SPECIAL)


def holds(target: Target, data: Input) -> None:
    """Fails with the parser's own exception unless it returned or raised a project error
    with a one-line message."""
    error = check(target, data)
    if error is not None:
        raise error
