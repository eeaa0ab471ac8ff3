"""Relations the user states as preferences: they win over the LLM, clingo-checked."""

from __future__ import annotations

from pathlib import Path

import pytest

from llm_grop import BackendOptions, arrange
from llm_grop.arrangement.pipeline import ArrangeOptions
from llm_grop.arrangement.preferences import covers, read_edge_preferences, read_preferences
from llm_grop.arrangement.sampling import violations
from llm_grop.cli import main
from llm_grop.errors import BadInput
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import items_from_names
from llm_grop.world.table import Table
from scripted import TASK1_GOOD, scripted

CATALOG = Catalog.load(use_env=False)
ITEMS = tuple(items_from_names(["dinner plate", "dinner fork", "dinner knife"], CATALOG))

REQUEST = "a dinner plate, a dinner fork and a dinner knife"
#: An LLM with the fork and knife on the wrong sides.
SWAPPED = TASK1_GOOD.replace("left", "LEFT").replace("right", "left").replace("LEFT", "right")


def _arrange(server, options: ArrangeOptions, request: str = REQUEST):
    opts = BackendOptions(base_url=server.url, api_key="test", max_retries=0)
    return arrange(request, llm="openai", llm_options=opts, seed=2, options=options)


def _rels(result) -> set[tuple]:
    return {(r.subject, r.relation, r.reference) for r in result.arrangement.relations}


def test_a_preference_overrides_the_llm_on_its_pair(chat_server) -> None:
    chat_server.reply = scripted([SWAPPED])
    result = _arrange(chat_server, ArrangeOptions(
        preferences=("the dinner fork to the left of the dinner plate",)))
    rels = _rels(result)
    assert ("dinner fork", "to the left of", "dinner plate") in rels
    assert ("dinner fork", "to the right of", "dinner plate") not in rels
    assert ("dinner knife", "to the left of", "dinner plate") in rels  # the LLM's, kept
    assert any("overridden by a stated relation" in w for w in result.arrangement.warnings)
    for config in result.configurations:
        assert not violations(config, result.arrangement.relations, result.arrangement.table)


def test_preferences_for_every_object_skip_template_1(chat_server) -> None:
    chat_server.reply = scripted([SWAPPED])
    pool = ("the dinner fork to the left of the dinner plate",
            "the dinner knife to the right of the dinner plate",
            "the mug lid on top of the mug")  # not requested: does not apply
    result = _arrange(chat_server, ArrangeOptions(preference_pool=pool))
    assert _rels(result) == {("dinner fork", "to the left of", "dinner plate"),
                             ("dinner knife", "to the right of", "dinner plate")}
    prompts = [c.prompt for c in result.arrangement.llm.calls]
    assert prompts and all("centimeters" in p for p in prompts)  # Template 2 only
    pos = {p.name: p.x for p in result.arrangement.placements}
    assert pos["dinner fork"] < pos["dinner plate"] < pos["dinner knife"]


def test_preferences_in_two_groups_still_ask_template_1(chat_server) -> None:
    # Every object is named, but nothing says where the mug and its lid go from the plate.
    chat_server.reply = scripted([
        "dinner fork to the left of dinner plate\nmug above and to the right of dinner plate\n"
        "mug lid on top of mug"])
    pool = ("the dinner fork to the left of the dinner plate", "the mug lid on top of the mug")
    result = _arrange(chat_server, ArrangeOptions(preference_pool=pool),
                      request="a dinner plate, a dinner fork, a mug and a mug lid")
    assert ("mug", "above and to the right of", "dinner plate") in _rels(result)
    prompts = [c.prompt for c in result.arrangement.llm.calls]
    assert not all("centimeters" in p for p in prompts)  # Template 1 was asked


def test_covers_asks_for_one_connected_group() -> None:
    items = tuple(items_from_names(["dinner plate", "dinner fork", "mug", "mug lid"], CATALOG))
    read = read_preferences(["the dinner fork to the left of the dinner plate",
                             "the mug lid on top of the mug"], [], items, CATALOG)
    assert not covers(read.relations, items)
    more = read_preferences(["the mug to the right of the dinner fork"], [], items, CATALOG)
    assert covers((*read.relations, *more.relations), items)
    assert not covers((), items)


@pytest.mark.parametrize(("sentence", "gap_m"), [
    ("the dinner fork 2 to the left of the dinner plate", None),
    ("the dinner fork 2 3 cm to the left of the dinner plate", 0.03),
    ("the dinner fork 2 to the left of the dinner plate, 4 cm apart", 0.04),
])
def test_a_numbered_objects_number_is_no_distance(sentence: str, gap_m: float | None
                                                  ) -> None:
    items = tuple(items_from_names(["dinner plate", "dinner fork", "dinner fork"], CATALOG))
    (read,) = read_preferences([sentence], [], items, CATALOG).relations
    assert (read.subject, read.gap_m) == ("dinner fork 2", gap_m)


def test_contradicting_preferences_are_bad_input(chat_server) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    with pytest.raises(BadInput, match="preferences contradict each other"):
        _arrange(chat_server, ArrangeOptions(preferences=(
            "the dinner fork to the left of the dinner plate",
            "the dinner plate to the left of the dinner fork")))


def test_unreadable_preference_is_bad_input(chat_server) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    with pytest.raises(BadInput, match="^preferences: 'the mug near the plate': "
                                       "cannot read it"):
        _arrange(chat_server, ArrangeOptions(preferences=("the mug near the plate",)))


def test_cli_preferences_file(chat_server, tmp_path: Path, capsys) -> None:
    chat_server.reply = scripted([SWAPPED])
    prefs = tmp_path / "prefs.yaml"
    prefs.write_text("preferences:\n  - the dinner fork to the left of the dinner plate\n"
                     "  - the dinner knife to the right of the dinner plate\n")
    args = ["arrange", REQUEST, "--llm", "openai", "--base-url", chat_server.url,
            "--preferences", str(prefs)]
    assert main(args) == 0
    assert "to the left of" in capsys.readouterr().out
    prefs.write_text("preferences: the fork\n")
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "prefs.yaml: preferences: expected a list, got 'the fork'" in err


def test_a_stated_distance_replaces_template_2(chat_server) -> None:
    chat_server.reply = scripted([SWAPPED], distance="About 9 centimeters.")
    result = _arrange(chat_server, ArrangeOptions(preference_pool=(
        "the dinner fork 2 cm to the left of the dinner plate",
        "the dinner knife to the right of the dinner plate")))
    gaps = result.gaps_m
    assert gaps[("dinner fork", "to the left of", "dinner plate")] == pytest.approx(0.02)
    assert gaps[("dinner knife", "to the right of", "dinner plate")] == pytest.approx(0.09)
    # Template 2 for the knife, and the plate's distance from the diner's edge.
    assert len(result.arrangement.llm.calls) == 2


def test_a_stated_distance_from_the_edge_replaces_the_question(chat_server) -> None:
    chat_server.reply = scripted([SWAPPED], distance="About 9 centimeters.")
    result = _arrange(chat_server, ArrangeOptions(preference_pool=(
        "the dinner fork 2 cm to the left of the dinner plate",
        "the dinner knife 2 cm to the right of the dinner plate",
        "the plate 4 cm from the diner's edge of the table",
        "the mug 1 cm from the edge")))
    assert result.edge_gap_m == pytest.approx(0.04)
    assert result.layout.origin == "dinner plate"
    assert result.arrangement.llm.calls == ()
    for config in result.configurations:
        plate = config.by_name()["dinner plate"]
        assert plate.y - 0.135 + 0.3 == pytest.approx(0.04, abs=0.015)


@pytest.mark.parametrize("sentence, error", [
    ("the dinner plate from the diner's edge", "no distance from the edge"),
    ("the dinner plate -3 cm from the diner's edge", "must not be negative"),
    # Any dash of the one table is a minus sign, as it is to the distance reader.
    ("the dinner plate \u20133 cm from the diner's edge", "must not be negative"),
    ("the dinner plate 90 cm from the edge", "does not fit"),
    ("the mug 3 cm from the edge", "names no requested object"),
])
def test_bad_edge_preferences_are_one_line_errors(sentence: str, error: str) -> None:
    with pytest.raises(BadInput, match=error):
        read_edge_preferences([sentence], [], ITEMS, CATALOG, Table())


@pytest.mark.parametrize(("sentence", "needle"), [
    ("the dinner fork -5 cm to the left of the dinner plate", "must not be negative"),
    ("the dinner fork 200 cm to the left of the dinner plate", "does not fit"),
])
def test_bad_stated_distances(chat_server, sentence: str, needle: str) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    with pytest.raises(BadInput, match=needle):
        _arrange(chat_server, ArrangeOptions(preferences=(sentence,)))


def test_unreadable_pool_sentence_is_bad_input(chat_server) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    with pytest.raises(BadInput, match="cannot read 'gibberish here'"):
        _arrange(chat_server, ArrangeOptions(preference_pool=("gibberish here",)))
    # A readable sentence about objects not requested simply does not apply.
    result = _arrange(chat_server, ArrangeOptions(preference_pool=("the mug lid on the mug",)))
    assert result.arrangement.relations


def test_an_ambiguous_preference_is_a_choice_the_llm_decides(chat_server) -> None:
    from llm_grop.arrangement.preferences import read_preferences

    read = read_preferences(["the dinner knife beside the dinner plate, 2 cm away"], (), ITEMS,
                            CATALOG)
    assert read.relations == () and len(read.choices) == 1
    assert {r.gap_m for option in read.choices[0].options for r in option} == {0.02}
    chat_server.reply = scripted([TASK1_GOOD])
    result = _arrange(chat_server, ArrangeOptions(
        preferences=("the dinner knife beside the dinner plate",)))
    assert ("dinner knife", "to the right of", "dinner plate") in _rels(result)
    assert any("as the LLM's relations have it" in w for w in result.arrangement.warnings)
