"""Requests in people's own words: the matcher when it reads every word, else the LLM reads
the whole request; answers checked, guesses marked, relations the request does not state
dropped; ambiguous relations decided by the LLM's relations or clingo."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from llm_grop import ArrangeOptions, BackendOptions, arrange, make_llm, understand
from llm_grop.errors import BadInput, LLMGropError, UnknownObject
from llm_grop.language.llm_reading import (
    read_reading_answer,
    reading_grammar,
    reading_schema,
)
from llm_grop.language.understanding import may_name_tableware
from llm_grop.language.vocabulary import READING_RELATIONS
from llm_grop.llm.base import CallLog
from llm_grop.llm.openai_backend import OpenAILLM
from llm_grop.world.catalog import Catalog
from scripted import TASK1_GOOD, scripted

if TYPE_CHECKING:
    from conftest import ChatServer

NO_CALLS = Path(__file__).parents[1] / "arrangement" / "no_calls.jsonl"


@pytest.fixture(scope="module")
def catalog() -> Catalog:
    return Catalog.load(use_env=False)


def no_llm() -> CallLog:
    """A replay of no recorded call: any LLM call fails the test with ReplayMissing."""
    return make_llm("replay", BackendOptions(replay_path=NO_CALLS))


def openai(server: ChatServer, reply: str | None = None) -> CallLog:
    if reply is not None:
        server.reply = lambda body: reply
    return CallLog(OpenAILLM(BackendOptions(base_url=server.url, max_retries=0)))


def answer(*objects: tuple[str, int, str], relations: tuple[dict[str, Any], ...] = (),
           diners: int = 1) -> str:
    """A JSON answer in the reading's schema."""
    rels = [{"reference": None, "distance_cm": None, "partner": None, "words": "", **r}
            for r in relations]
    return json.dumps({"diners": diners, "relations": rels,
                       "objects": [{"name": n, "count": c, "words": w} for n, c, w in objects]})


def kinds(request: Any) -> list[str]:
    return [it.kind for it in request.items]


def test_what_the_matcher_reads_costs_no_llm_call(catalog: Catalog) -> None:
    log = no_llm()
    request = understand("For breakfast: a mug of coffee on a coaster and a bread plate "
                         "with bread on it, if you can", catalog=catalog, llm=log)
    assert kinds(request) == ["mug", "mug mat", "bread plate", "bread"]
    assert request.source == "catalog" and not log.calls
    assert [(r.subject, r.relation, r.reference, r.source, r.line) for r in request.relations] \
        == [("mug", "on top of", "mug mat", "request", "a mug of coffee on a coaster"),
            ("bread", "on top of", "bread plate", "request", "bread on it")]
    assert [(it.source, it.words) for it in request.items][:2] == [
        ("request", "a mug"), ("request", "a coaster")]


@pytest.mark.parametrize("text", ["happiness", "hello there", "what's the weather?",
                                  "тарелка и вилка", "テーブルを準備して"])
def test_a_request_with_no_dining_word_is_refused_without_asking(text: str,
                                                                 catalog: Catalog) -> None:
    log = no_llm()
    with pytest.raises(BadInput) as err:
        understand(text, catalog=catalog, llm=log)
    assert "\n" not in str(err.value) and str(err.value).startswith("request: ")
    assert not log.calls


def test_an_unknown_word_never_refuses_before_the_llm_is_asked(chat_server: ChatServer,
                                                               catalog: Catalog) -> None:
    log = openai(chat_server, answer(("soup bowl", 1, "a soup bowl"),
                                     ("soup spoon", 1, "something to eat soup with")))
    request = understand("a soup bowl and something to eat soup with", catalog=catalog,
                         llm=log, seed=3)
    assert kinds(request) == ["soup bowl", "soup spoon"]
    assert request.source == "llm" and len(request.calls) == 1 == len(log.calls)
    prompt = chat_server.requests[-1]["messages"][-1]["content"]
    assert '"a soup bowl and something to eat soup with"' in prompt and "soup spoon" in prompt
    assert [it.source for it in request.items] == ["request", "llm"]
    assert request.guessed == ("soup spoon",)
    assert request.warnings == ("the openai LLM chose what the request does not say: 1 soup "
                                "spoon (for 'something to eat soup with'); guess=False refuses "
                                "this",)


def test_openai_is_asked_for_json_in_the_reading_schema(chat_server: ChatServer,
                                                        catalog: Catalog) -> None:
    log = openai(chat_server, answer(("mug", 2, "tea for two")))
    request = understand("tea for me and a friend", catalog=catalog, llm=log)
    assert kinds(request) == ["mug", "mug"]
    sent = chat_server.requests[-1]["response_format"]
    assert sent["type"] == "json_schema" and sent["json_schema"]["strict"] is True
    schema = sent["json_schema"]["schema"]
    assert schema == reading_schema(catalog)
    names = schema["properties"]["objects"]["items"]["properties"]["name"]["enum"]
    relations = schema["properties"]["relations"]["items"]["properties"]["relation"]["enum"]
    assert names == catalog.names() and relations == list(READING_RELATIONS)
    assert log.llm.structured_output is True  # type: ignore[attr-defined]


def test_a_server_without_structured_output_answers_in_lines(chat_server: ChatServer,
                                                             catalog: Catalog) -> None:
    chat_server.refuse_response_format = True
    log = openai(chat_server, 'diners: 1\nobject: 1 dinner plate | "a plate"\n'
                              'object: 1 dinner fork | "a fork"\n'
                              'relation: dinner fork | to the left of | dinner plate | 2 cm | '
                              '"a fork, say 2 cm to its left"')
    request = understand("a plate and a fork, say 2 cm to its left", catalog=catalog, llm=log)
    assert [("response_format" in b) for b in chat_server.requests] == [True, False]
    assert [(r.subject, r.relation, r.reference, r.gap_m) for r in request.relations] == [
        ("dinner fork", "to the left of", "dinner plate", 0.02)]
    understand("a plate and a fork, say 2 cm to its left", catalog=catalog, llm=log)
    assert "response_format" not in chat_server.requests[-1]  # not asked again


def test_an_answer_outside_the_catalog_is_one_line_with_suggestions(
        chat_server: ChatServer, catalog: Catalog) -> None:
    with pytest.raises(UnknownObject) as err:
        understand("a plate and something salty", catalog=catalog,
                   llm=openai(chat_server, answer(("salt shaker", 1, "something salty"))))
    message = str(err.value)
    assert message.startswith("request: the openai LLM's reading: unknown object 'salt "
                              "shaker'") and "\n" not in message
    with pytest.raises(UnknownObject, match="unknown object 'cereal bowl'; did you mean "
                                            "'fruit bowl'"):
        understand("a plate and something for cereal", catalog=catalog,
                   llm=openai(chat_server, answer(("cereal bowl", 1, "for cereal"))))


def test_nothing_named_even_after_the_llm_is_bad_input(chat_server: ChatServer,
                                                       catalog: Catalog) -> None:
    with pytest.raises(BadInput, match="the openai LLM read no object in 'set the table with "
                                       "happiness'; name the objects to set"):
        understand("set the table with happiness", catalog=catalog,
                   llm=openai(chat_server, answer()))


@pytest.mark.parametrize(("reply", "message"), [
    (answer(("dinner fork", 13, "forks")), "13 dinner fork: a count is 1 to 12"),
    (answer(("dinner plate", 1, "")), None),
    (answer(("dinner plate", 1, ""), diners=13), "13 diners; between 1 and 12"),
    (answer(("dinner plate", 1, ""), ("dinner fork", 1, ""), relations=(
        {"subject": "dinner fork", "relation": "to the left of", "reference": "dinner plate",
         "distance_cm": -2},)), "a distance must not be negative"),
    (answer(("dinner plate", 1, ""), ("dinner fork", 1, ""), relations=(
        {"subject": "dinner fork", "relation": "to the left of", "reference": "dinner plate",
         "distance_cm": "\u20132 cm"},)), "a distance must not be negative"),
])
def test_the_reading_is_checked_before_any_arranging(reply: str, message: str | None,
                                                     chat_server: ChatServer,
                                                     catalog: Catalog) -> None:
    log = openai(chat_server, reply)
    if message is None:
        assert kinds(understand("a plate, whatever else fits", catalog=catalog,
                                llm=log)) == ["dinner plate"]
        return
    with pytest.raises(BadInput, match=message) as err:
        understand("a plate, whatever else fits", catalog=catalog, llm=log)
    assert str(err.value).startswith("request: the openai LLM's reading: ")


def test_contradicting_relations_are_refused_in_the_request_s_words(
        chat_server: ChatServer, catalog: Catalog) -> None:
    text = "the fork left of the plate; oh and the plate left of the fork, ok?"
    reply = answer(("dinner fork", 1, "the fork"), ("dinner plate", 1, "the plate"), relations=(
        {"subject": "dinner fork", "relation": "to the left of", "reference": "dinner plate",
         "words": "the fork left of the plate"},
        {"subject": "dinner plate", "relation": "to the left of", "reference": "dinner fork",
         "words": "the plate left of the fork"}))
    with pytest.raises(BadInput) as err:
        understand(text, catalog=catalog, llm=openai(chat_server, reply))
    assert str(err.value) == ("request: the request's relations contradict each other: 'the "
                              "fork left of the plate' (the request); 'the plate left of the "
                              "fork' (the request)")


def test_guesses_are_marked_and_no_guess_refuses_them(chat_server: ChatServer,
                                                      catalog: Catalog) -> None:
    reply = answer(("mug", 1, "coffee"), ("bread plate", 1, "toast"), ("bread", 1, "toast"))
    request = understand("coffee and toast", catalog=catalog, llm=openai(chat_server, reply))
    assert [(it.kind, it.source, it.words) for it in request.items] == [
        ("mug", "llm", "coffee"), ("bread plate", "llm", "toast"), ("bread", "llm", "toast")]
    assert len(request.warnings) == 1 and "chose what the request does not say" in \
        request.warnings[0]
    with pytest.raises(BadInput, match=r"chose what 'a plate and coffee' does not say \(1 "
                                       r"mug\), and guess=False forbids it"):
        understand("a plate and coffee", catalog=catalog, guess=False, llm=openai(
            chat_server, answer(("dinner plate", 1, "a plate"), ("mug", 1, "coffee"))))
    log = no_llm()
    with pytest.raises(BadInput, match="nothing in 'breakfast for two' names an object, and "
                                       "guess=False forbids"):
        understand("breakfast for two", catalog=catalog, llm=log, guess=False)
    assert not log.calls


def test_a_count_the_request_leaves_open_is_a_guess(chat_server: ChatServer,
                                                    catalog: Catalog) -> None:
    reply = answer(("fruit bowl", 1, "a bowl"), ("strawberry", 5, "some strawberries"))
    request = understand("a bowl and some strawberries", catalog=catalog,
                         llm=openai(chat_server, reply))
    assert [it.source for it in request.items] == ["request"] + ["llm"] * 5
    with pytest.raises(BadInput, match="how many 'strawberries'"):
        understand("a bowl and some strawberries", catalog=catalog, llm=None)


def test_a_typo_still_names_the_object(chat_server: ChatServer, catalog: Catalog) -> None:
    reply = answer(("dinner plate", 1, "a plait"), ("dinner fork", 1, "a frok"))
    request = understand("a plait and a frok", catalog=catalog,
                         llm=openai(chat_server, reply))
    assert [it.source for it in request.items] == ["request", "request"]
    assert not request.warnings


def test_relations_the_request_does_not_state_are_dropped(chat_server: ChatServer,
                                                          catalog: Catalog) -> None:
    reply = answer(("dinner plate", 1, "plate"), ("dinner fork", 1, "fork"), relations=(
        {"subject": "dinner fork", "relation": "to the left of", "reference": "dinner plate",
         "words": "Place the fork to the left of the plate"},
        {"subject": "dinner plate", "relation": "center", "words": ""}))
    request = understand("a plate & a fork, cheers mate", catalog=catalog,
                         llm=openai(chat_server, reply))
    # "place" and "left" are not the request's words; the centre relation has no words but
    # relates only what the request names, so it stays.
    assert [(r.subject, r.relation) for r in request.relations] == [("dinner plate", "center")]
    assert request.warnings == ("ignored the LLM's relation(s) the request does not state: "
                                "dinner fork to the left of dinner plate",)


def test_the_request_s_diner_phrase_wins_over_an_answer_of_one(chat_server: ChatServer,
                                                              catalog: Catalog) -> None:
    request = understand("the usual for two", catalog=catalog,
                         llm=openai(chat_server, answer(("dinner plate", 1, ""))))
    assert request.diners == 2 and kinds(request) == ["dinner plate", "dinner plate"]


def test_recorded_answers_replay_the_same_reading(chat_server: ChatServer, tmp_path: Path,
                                                  catalog: Catalog) -> None:
    chat_server.reply = lambda body: "object: 1 dinner plate\nobject: 1 dinner fork\n" \
                                     "object: 1 dinner knife"
    rec = tmp_path / "calls.jsonl"
    live = make_llm("openai", BackendOptions(base_url=chat_server.url), record=rec)
    first = understand("the usual for two", catalog=catalog, llm=live, seed=5)
    again = understand("the usual for two", catalog=catalog, seed=5,
                       llm=make_llm("replay", BackendOptions(replay_path=rec)))
    assert first.items == again.items and first.diners == again.diners == 2
    assert kinds(first) == ["dinner plate", "dinner fork", "dinner knife"] * 2


def test_the_request_s_relations_are_stated_preferences(chat_server: ChatServer) -> None:
    chat_server.reply = scripted(["Place the mug to the right of the mug mat."])
    result = arrange("a mug on a coaster", llm="openai",
                     llm_options=BackendOptions(base_url=chat_server.url, max_retries=0))
    rels = {(r.subject, r.relation, r.reference): r.source
            for r in result.arrangement.relations}
    assert rels == {("mug", "on top of", "mug mat"): "request"}
    assert next(p for p in result.arrangement.placements if p.name == "mug").on == "mug mat"


def test_the_request_and_a_preference_that_contradict_are_refused(
        chat_server: ChatServer) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    options = ArrangeOptions(preferences=("the mug mat on top of the mug",))
    with pytest.raises(BadInput, match="the request's relations and the preferences "
                                       "contradict each other: 'a mug on a coaster' \\(the "
                                       "request\\); 'the mug mat on top of the mug' \\(a "
                                       "preference\\)"):
        arrange("a mug on a coaster", llm="openai", options=options,
                llm_options=BackendOptions(base_url=chat_server.url, max_retries=0))


def test_beside_is_decided_by_the_llm_s_relations(chat_server: ChatServer) -> None:
    chat_server.reply = scripted(["Place the dinner knife to the right of the dinner plate."])
    result = arrange("a plate with a knife beside it", llm="openai",
                     llm_options=BackendOptions(base_url=chat_server.url, max_retries=0))
    a = result.arrangement
    assert [(r.subject, r.relation, r.reference, r.source) for r in a.relations] == [
        ("dinner knife", "to the right of", "dinner plate", "request")]
    assert "'a knife beside it' read as the dinner knife to the right of the dinner plate (as " \
           "the LLM's relations have it)" in a.warnings


def test_beside_is_decided_by_clingo_when_the_other_relations_force_it(
        chat_server: ChatServer) -> None:
    chat_server.reply = scripted(["Place the dinner plate to the left of the dinner fork."])
    result = arrange("the fork to the left of the plate, and the plate beside the fork",
                     llm="openai",
                     llm_options=BackendOptions(base_url=chat_server.url, max_retries=0))
    a = result.arrangement
    assert ("dinner plate", "to the right of", "dinner fork") in [r.key() for r in a.relations]
    assert any("the only way the other relations allow" in w for w in a.warnings)
    # Every object is related by the stated relations: Template 1 was never asked.
    assert not any("Place" in c.prompt[:40] for c in a.llm.calls)  # type: ignore[union-attr]


def test_either_side_of_puts_one_on_each_side(chat_server: ChatServer) -> None:
    chat_server.reply = scripted(["Place the dinner fork to the left of the dinner plate.\n"
                                  "Place the dinner knife to the right of the dinner plate."])
    result = arrange("a plate with the fork and the knife either side of it", llm="openai",
                     llm_options=BackendOptions(base_url=chat_server.url, max_retries=0))
    by = {p.name: p for p in result.arrangement.placements}
    assert by["dinner fork"].x < by["dinner plate"].x < by["dinner knife"].x


def test_the_reading_call_belongs_to_the_arrangement(chat_server: ChatServer) -> None:
    chat_server.reply = scripted([TASK1_GOOD], reading=answer(
        ("dinner plate", 1, "a dinner plate"), ("dinner fork", 1, "cutlery"),
        ("dinner knife", 1, "cutlery")))
    result = arrange("a dinner plate and cutlery", llm="openai",
                     llm_options=BackendOptions(base_url=chat_server.url, max_retries=0))
    a = result.arrangement
    assert [p.kind for p in a.placements] == ["dinner plate", "dinner fork", "dinner knife"]
    assert a.read_by == "llm" and a.llm is not None
    assert a.llm.calls[0].prompt.startswith("A robot sets a dining table for people.")
    assert dict((n, s) for n, s, _ in a.origins) == {
        "dinner plate": "request", "dinner fork": "llm", "dinner knife": "llm"}


def test_the_gate_counts_catalog_words_and_dining_words(catalog: Catalog) -> None:
    assert may_name_tableware("a steak", catalog) and may_name_tableware("mugs", catalog)
    assert may_name_tableware("set the table", catalog)
    assert not may_name_tableware("happiness and joy", catalog)


def test_the_grammar_lists_every_catalog_name_and_relation(catalog: Catalog) -> None:
    grammar = reading_grammar(catalog)
    assert all(f'"{name}"' in grammar for name in catalog.names())
    assert '"beside"' in grammar and '"either side of | "' in grammar


@pytest.mark.embedded
def test_the_embedded_model_reads_in_catalog_names_repeatably(catalog: Catalog) -> None:
    first = understand("the usual", catalog=catalog, llm="embedded", seed=2)
    again = understand("the usual", catalog=catalog, llm="embedded", seed=2)
    assert first.items == again.items and first.items
    assert all(it.kind in catalog for it in first.items)


_PIECES = ["a", "the", "two", "²", "①", "of", "for", "on", "on top of", "to the left of",
           "in the middle", "under", "behind", "beside", "either side of", "its", "it", "and",
           ",", "with", "my", "wife's", "mug's", "coffee", "soup", "happiness", "usual",
           "cutlery", "'s", "-", "—", "or", "for two", "2 cm", "-3 cm", "an inch", "plates",
           "mugs", "plate", "mug", "coaster", "glass", "bowl", "lid", "1e3", "0", "13", "31",
           "тарелка", "\u0000", "\ud800", "ｐｌａｔｅ", "\n", "[", "]", "'", "on the left"]


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.lists(st.sampled_from(_PIECES) | st.text(max_size=8), max_size=14))
def test_any_request_reads_or_fails_in_one_line(pieces: list[str]) -> None:
    text = " ".join(pieces)
    catalog = Catalog.load(use_env=False)
    try:
        request = understand(text, catalog=catalog, llm=None)
    except LLMGropError as exc:
        assert "\n" not in str(exc) and str(exc)
    else:
        assert request.items and all(it.kind in catalog for it in request.items)
        names = {it.name for it in request.items}
        assert all(r.subject in names for r in request.relations)


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.text(max_size=300) | st.lists(
    st.sampled_from(["diners: 2\n", "object: ", "1 ", "13 ", "dinner plate", "fork", " | ",
                     "relation: ", "to the left of", "beside", "center", "mug 2", "\n",
                     '{"objects": [', '{"name": "mug", "count": 2}', "]}", ",", "salt shaker",
                     "```json", "```", '"count": true', "null", '"words": "x"', "2 cm"]),
    max_size=20).map("".join))
def test_any_reading_answer_reads_or_fails_in_one_line(text: str) -> None:
    catalog = Catalog.load(use_env=False)
    try:
        reading, _ = read_reading_answer(text, "a request", catalog)
    except LLMGropError as exc:
        assert "\n" not in str(exc) and str(exc).startswith("request")
    else:
        assert reading.objects and all(o.name in catalog.specs for o in reading.objects)


def test_no_guess_still_asks_the_llm_about_a_typo(chat_server: ChatServer,
                                                 catalog: Catalog) -> None:
    log = openai(chat_server, answer(("dinner fork", 1, "a frok")))
    request = understand("a frok please", catalog=catalog, llm=log, guess=False)
    assert [(it.kind, it.source) for it in request.items] == [("dinner fork", "request")]


def test_a_reading_that_leaves_out_everything_named_is_refused(chat_server: ChatServer,
                                                                catalog: Catalog) -> None:
    with pytest.raises(BadInput, match=r"leaves out everything 'a frok and a plate' names "
                                       r"\(dinner plate\)"):
        understand("a frok and a plate", catalog=catalog,
                   llm=openai(chat_server, answer(("water cup", 10, ""))))


def test_the_request_s_numbers_win_or_are_marked(chat_server: ChatServer,
                                                 catalog: Catalog) -> None:
    reply = answer(("dinner plate", 4, "a plate"), ("dinner fork", 1, "a frok"), diners=3)
    request = understand("a plate and a frok for two", catalog=catalog,
                         llm=openai(chat_server, reply))
    assert request.diners == 2
    assert {(it.kind, it.source) for it in request.items} == {
        ("dinner plate", "llm"), ("dinner fork", "request")}
    assert request.warnings[0] == "the request sets the table for 2; the openai LLM read 3 diners"
    assert "4 dinner plate (for 'a plate')" in request.warnings[-1]
