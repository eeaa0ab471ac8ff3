"""One table of number words and one of dashes, read alike by the request reader and the
reader of the LLM's distances."""

from __future__ import annotations

import pytest

from llm_grop.language.distance import DASHES, parse_distance_cm, plain_dashes
from llm_grop.language.vocabulary import request_words
from llm_grop.language.words import distance_at, normalized, tokens

NUMBERS = request_words().numbers


def test_the_table_runs_from_zero_to_ninety() -> None:
    assert NUMBERS["zero"] == 0 and NUMBERS["nineteen"] == 19 and NUMBERS["ninety"] == 90
    assert set(range(20)) | set(range(20, 100, 10)) == set(NUMBERS.values())


@pytest.mark.parametrize("word", sorted(NUMBERS))
def test_every_number_word_is_a_distance_to_both_readers(word: str) -> None:
    assert parse_distance_cm(f"{word} cm") == NUMBERS[word]
    assert distance_at([word, "cm"], 0, NUMBERS) == (NUMBERS[word], 2)


@pytest.mark.parametrize("tens", [w for w, n in NUMBERS.items() if n >= 20])
def test_a_tens_word_and_a_word_below_twenty_are_one_number(tens: str) -> None:
    assert parse_distance_cm(f"{tens}-two cm") == NUMBERS[tens] + 2


@pytest.mark.parametrize("dash", list(DASHES))
def test_every_dash_is_a_minus_sign_and_a_range_to_both_readers(dash: str) -> None:
    assert plain_dashes(f"{dash}5") == "-5"
    assert normalized(f"{dash}5 cm") == "-5 cm"
    assert [t.word for t in tokens(f"a fork {dash}5 cm")] == ["a", "fork", "-", "5", "cm"]
    assert parse_distance_cm(f"{dash}5 cm") is None  # negative
    assert parse_distance_cm(f"5{dash}7 cm") == 6.0
