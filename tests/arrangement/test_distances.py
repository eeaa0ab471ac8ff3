"""Template 2 and the distance parser."""

from __future__ import annotations

import pytest

from llm_grop.arrangement.distances import (
    DEFAULT_GAP_CM,
    parse_distance_cm,
    parse_distance_m,
    template2_grammar,
    template2_prompt,
)
from llm_grop.world.relation import Relation


def test_template2_wording() -> None:
    prompt = template2_prompt(Relation("dinner knife", "to the right of", "dinner plate"))
    assert prompt == ("A dinner knife is placed to the right of a dinner plate. How many "
                      "centimeters to the right of the dinner plate should the dinner knife "
                      "be placed?")
    with pytest.raises(ValueError):
        template2_prompt(Relation("mug lid", "on top of", "mug"))


@pytest.mark.parametrize(("text", "cm"), [
    ("Generally, the dinner knife should be placed about 5-7 centimeters to the right of the "
     "dinner plate.", 6.0),
    ("5 to 7 cm", 6.0),
    ("Between 5 and 7 cm.", 6.0),
    ("about 3 cm", 3.0),
    ("3cm", 3.0),
    ("2.5 centimetres away", 2.5),
    ("2 inches", 5.08),
    ("Roughly 1 in.", 2.54),
    ("30 mm", 3.0),
    ("0.05 m", 5.0),
    ("one foot", 30.48),
    ("five centimeters", 5.0),
    ("Twenty-two centimeters to the left.", 22.0),
    ("1. The fork should be 4 cm from the plate.", 4.0),
    ("About 10.", 10.0),
    ("**3-5 cm** is typical", 4.0),
])
def test_distances(text: str, cm: float) -> None:
    assert parse_distance_cm(text) == pytest.approx(cm)


@pytest.mark.parametrize("text", ["", "It depends on the table.", "-5 cm",
                                  "500 centimeters", "put it in the middle"])
def test_unreadable_distances_use_the_default(text: str) -> None:
    assert parse_distance_cm(text) is None
    assert parse_distance_m(text) == (DEFAULT_GAP_CM / 100, True)


def test_grammar_compiles() -> None:
    from llama_cpp import LlamaGrammar

    LlamaGrammar.from_string(template2_grammar(), verbose=False)
