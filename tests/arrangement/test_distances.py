"""Template 2 and the distance parser, on messy answers."""

from __future__ import annotations

import pytest

from llm_grop.arrangement.distances import (
    DEFAULT_GAP_CM,
    MAX_GAP_CM,
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


def test_template2_articles_follow_the_names() -> None:
    prompt = template2_prompt(Relation("water cup", "above and to the right of", "egg cup"))
    assert prompt.startswith("A water cup is placed above and to the right of an egg cup. ")
    assert template2_prompt(Relation("egg cup", "below", "mug")).startswith("An egg cup is ")


@pytest.mark.parametrize("relation", [Relation("mug lid", "on top of", "mug"),
                                      Relation("mug mat", "under", "mug"),
                                      Relation("dinner plate", "center", None)])
def test_template2_refuses_relations_without_a_gap(relation: Relation) -> None:
    with pytest.raises(ValueError, match=relation.relation):
        template2_prompt(relation)


@pytest.mark.parametrize(("text", "cm"), [
    # the paper's example answer
    ("Generally, the dinner knife should be placed about 5-7 centimeters to the right of the "
     "dinner plate.", 6.0),
    ("About 5 centimeters.", 5.0),
    ("12-15 centimeters.", 13.5),
    ("5 to 7 cm", 6.0),
    ("5 – 7 cm", 6.0),
    ("5cm-7cm", 6.0),
    ("5 cm to 7 cm apart", 6.0),
    ("Between 5 and 7 cm.", 6.0),
    ("Anywhere from 2 to 4 centimetres should do.", 3.0),
    ("5 or 6 cm", 5.5),
    ("about 3 cm", 3.0),
    ("~3cm", 3.0),
    ("3cm", 3.0),
    ("3 cms", 3.0),
    ("2.5 centimetres away", 2.5),
    ("It should be placed 10 centimeters to the left.", 10.0),
    ("2 inches", 5.08),
    ("2 in", 5.08),
    ("Roughly 1 in.", 2.54),
    ("about 1 in, measured edge to edge", 2.54),
    ("1-2 inches (2.5-5 cm)", 3.81),
    ("30 mm", 3.0),
    ("30 millimeters", 3.0),
    ("0.05 m", 5.0),
    ("0.05 meters", 5.0),
    ("0.1 metre", 10.0),
    ("one foot", 30.48),
    ("1 ft", 30.48),
    ("a foot away", 30.48),
    ("five centimeters", 5.0),
    ("Twenty-two centimeters to the left.", 22.0),
    ("twenty five cm", 25.0),
    ("ten to fifteen centimeters", 12.5),
    ("two and a half inches", 6.35),
    ("half an inch", 1.27),
    ("an inch or two", 2.54),
    ("one and a half centimeters", 1.5),
    ("Place it 2½ cm away", 2.5),
    ("1. The fork should be 4 cm from the plate.", 4.0),
    ("Step 2: keep a 3 cm gap.", 3.0),
    ("**3-5 cm** is typical", 4.0),
    ("The knife goes 1 inch to the right of the plate, in line with the plate's edge.", 2.54),
    ("Place it 5 cm in front of the plate", 5.0),
    ("It should be 0 cm away: touching.", 0.0),
    ("About 10.", 10.0),
    ("10", 10.0),
    ("8-10", 9.0),
    ("1. About 7", 7.0),
    ("Around 2 to 3", 2.5),
    ("Sure!\n\nAbout 6 CENTIMETERS to the right.", 6.0),
])
def test_distances(text: str, cm: float) -> None:
    assert parse_distance_cm(text) == pytest.approx(cm)


@pytest.mark.parametrize("text", [
    "",
    "It depends on the table.",
    "-5 cm",
    "minus 5 cm",
    "500 centimeters",
    "3 m",
    "put it in the middle",
    "a few centimeters",
    "Place it in the center, one of the common choices.",
    "It should be about a hand's width away.",
    "Place the fork in line with the plate in a typical setting.",
])
def test_unreadable_distances_use_the_default(text: str) -> None:
    assert parse_distance_cm(text) is None
    assert parse_distance_m(text) == (DEFAULT_GAP_CM / 100, True)


def test_distance_in_metres() -> None:
    assert parse_distance_m("About 5-7 centimeters.") == (pytest.approx(0.06), False)
    assert parse_distance_cm(f"{MAX_GAP_CM:g} cm") == MAX_GAP_CM
    assert parse_distance_cm(f"{MAX_GAP_CM + 1:g} cm") is None


def test_grammar_compiles_and_its_answers_parse() -> None:
    from llama_cpp import LlamaGrammar

    grammar = template2_grammar()
    LlamaGrammar.from_string(grammar, verbose=False)
    assert "About " in grammar and "centimeters." in grammar
    for answer in ("About 5 centimeters.", "5-7 centimeters.", "12 to 15 centimeters."):
        assert parse_distance_cm(answer) is not None


@pytest.mark.parametrize(("text", "cm"), [
    ("1,000 mm", 100.0),  # a thousands group, not "000 mm"
    ("1,500 millimeters apart", 150.0),
    ("1e3 mm", 100.0),
    ("1E1 cm", 10.0),
    ("2e-1 m", 20.0),
    ("5\u202fcm", 5.0),  # narrow no-break space
    ("5\u2009cm", 5.0),  # thin space
    ("5\u00a0cm", 5.0),  # no-break space
    ("１０ cm", 10.0),  # fullwidth digits
    ("１０ ｃｍ", 10.0),
    ("5\u20137 cm", 6.0),  # en dash as a range's dash
    ("5\u22127 cm", 6.0),  # a minus sign between two numbers is a range's dash too
    ("2¼ cm", 2.25),
    ("¾ inch", 1.905),
    ("5 cm²", 5.0),  # the superscript is no number
    ("① Place it 4 cm away", 4.0),  # nor is the circled digit
    ("2″", 5.08),  # NFKC makes the double prime two primes
])
def test_unicode_and_number_forms(text: str, cm: float) -> None:
    assert parse_distance_cm(text) == pytest.approx(cm)


@pytest.mark.parametrize("text", [
    "1,000 cm",  # read as 1000 cm, then refused as above MAX_GAP_CM
    "1e3 cm",
    "1e999 cm",  # overflows to infinity: refused, no exception
    "\u22125 cm",  # Unicode minus: negative
    "\u20135 cm",  # en dash as a minus
    "\u20105 cm",  # Unicode hyphen
    "\uff0d5 cm",  # fullwidth hyphen-minus (NFKC)
    "² cm",
    "①",
    "⅓ cm",  # NFKC would read "1⁄3" as 3
    "\u0663 cm",  # Arabic-Indic three: only ASCII digits are read
])
def test_unicode_and_number_forms_that_give_no_distance(text: str) -> None:
    assert parse_distance_cm(text) is None
    assert parse_distance_m(text) == (DEFAULT_GAP_CM / 100, True)
