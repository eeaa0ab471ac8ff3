"""Template 1 and the parser of real, messy LLM answers."""

from __future__ import annotations

import pytest

from llm_grop.arrangement.relations import (
    followup_grammar,
    followup_prompt,
    parse_relations,
    template1_grammar,
    template1_prompt,
)
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import items_from_names

CATALOG = Catalog.load(use_env=False)
TASK1 = items_from_names(["dinner plate", "dinner fork", "dinner knife"], CATALOG)
FORK_LEFT = ("dinner fork", "to the left of", "dinner plate")
KNIFE_RIGHT = ("dinner knife", "to the right of", "dinner plate")
PLATE_CENTER = ("dinner plate", "center", None)


def _keys(text: str, items=TASK1) -> list[tuple]:
    return [r.key() for r in parse_relations(text, items, CATALOG).relations]


def test_template1_has_the_papers_slots() -> None:
    prompt = template1_prompt(TASK1, notes="The diner is left-handed.")
    assert prompt.startswith("The goal is to arrange a dining table with objects.")
    assert "above and to the right of, below and to the right of" in prompt
    assert "Place the water cup above and to the right of the dinner plate." in prompt
    assert ("What is a typical way of positioning a dinner plate, a dinner fork, and a dinner "
            "knife on a table?") in prompt
    assert prompt.endswith("The answer cannot include other objects. The diner is left-handed.")
    assert "Example" not in template1_prompt(TASK1, examples="")


@pytest.mark.parametrize(("text", "expected"), [
    ("Place the dinner plate in the center of the table.\n"
     "Place the dinner fork to the left of the dinner plate.\n"
     "Place the dinner knife to the right of the dinner plate.",
     [PLATE_CENTER, FORK_LEFT, KNIFE_RIGHT]),
    ("Sure! Here is a typical arrangement:\n\n1. **Place the plate** in the middle of the table.\n"
     "2) Place the forks on the left side of the plate.\n3) Knife: to the right-hand side of "
     "the plate.\nEnjoy your meal!", [PLATE_CENTER, FORK_LEFT, KNIFE_RIGHT]),
    ("Step 1: The fork goes left of the plate\n- Put the knife on the right of the plate.",
     [FORK_LEFT, KNIFE_RIGHT]),
    ("Place the fork to the left of the plate and the knife to the right of the plate.",
     [FORK_LEFT, KNIFE_RIGHT]),
    ("* PLACE THE DINNER PLATE AT THE CENTRE OF THE TABLE.", [PLATE_CENTER]),
    ("Place the fork in front of the plate. Place the knife behind the plate.",
     [("dinner fork", "below", "dinner plate"), ("dinner knife", "above", "dinner plate")]),
    ("Place the knife to the upper right of the plate.\nPlace the fork diagonally below and to "
     "the left of the plate.", [("dinner knife", "above and to the right of", "dinner plate"),
                                ("dinner fork", "below and to the left of", "dinner plate")]),
])
def test_messy_answers(text: str, expected: list[tuple]) -> None:
    assert _keys(text) == expected


def test_synonyms_stacking_and_unrequested_objects() -> None:
    items = items_from_names(["mug", "mug mat", "mug lid", "fruit bowl", "strawberry"], CATALOG)
    parsed = parse_relations(
        "1. Put the teacup on the coaster.\n2. The lid goes on top of the mug.\n"
        "3. Place the strawberries in the bowl.\n4. Place the napkin to the left of the bowl.\n"
        "5. Place the mug mat beneath the lid.", items, CATALOG)
    assert [r.key() for r in parsed.relations] == [
        ("mug", "on top of", "mug mat"), ("mug lid", "on top of", "mug"),
        ("strawberry", "on top of", "fruit bowl"),
        ("mug mat", "under", "mug lid")]
    assert "Place the napkin to the left of the bowl." in parsed.ignored
    assert parsed.missing == ()


def test_left_out_objects_and_self_relations() -> None:
    parsed = parse_relations("Place the plate in the center.\nPlace the fork to the left of the "
                             "fork.", TASK1, CATALOG)
    assert [r.key() for r in parsed.relations] == [PLATE_CENTER]
    assert parsed.missing == ("dinner fork", "dinner knife")


def test_repeated_kinds_map_to_instances() -> None:
    items = items_from_names(["dinner plate", "dinner fork", "dinner fork"], CATALOG)
    assert [i.name for i in items] == ["dinner plate", "dinner fork", "dinner fork 2"]
    keys = _keys("Place a fork to the left of the plate.\nPlace another fork to the left of the "
                 "fork.", items)
    assert keys == [("dinner fork", "to the left of", "dinner plate"),
                    ("dinner fork 2", "to the left of", "dinner fork")]


def test_followup_prompt_uses_the_authors_words() -> None:
    prompt = followup_prompt("dinner knife", "dinner plate")
    assert prompt.startswith("Where should a dinner knife be placed in relation to a dinner plate?")


def test_grammars_compile_in_llama_cpp() -> None:
    from llama_cpp import LlamaGrammar

    for grammar in (template1_grammar(TASK1), followup_grammar("dinner knife", "dinner plate")):
        LlamaGrammar.from_string(grammar, verbose=False)
    assert '"dinner fork " rel " the dinner fork"' not in template1_grammar(TASK1)
