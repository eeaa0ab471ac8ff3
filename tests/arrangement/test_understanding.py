"""Requests in people's own words: the matcher, then the LLM for what it cannot read."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from llm_grop import ArrangeOptions, BackendOptions, arrange, make_llm, understand
from llm_grop.arrangement.understanding import (
    items_grammar,
    items_schema,
    may_name_tableware,
    read_items_answer,
)
from llm_grop.errors import BadInput, LLMGropError, UnknownObject
from llm_grop.llm.base import CallLog
from llm_grop.llm.openai_backend import OpenAILLM
from llm_grop.world.catalog import Catalog
from scripted import TASK1_GOOD, scripted

if TYPE_CHECKING:
    from conftest import ChatServer

NO_CALLS = Path(__file__).with_name("no_calls.jsonl")


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


def kinds(request: Any) -> list[str]:
    return [it.kind for it in request.items]


def test_what_the_matcher_reads_costs_no_llm_call(catalog: Catalog) -> None:
    log = no_llm()
    request = understand("I'd like to have breakfast: a mug of coffee on a coaster and a "
                         "bread plate with bread", catalog=catalog, llm=log)
    assert kinds(request) == ["mug", "mug mat", "bread plate", "bread"]
    assert request.source == "catalog" and not log.calls
    assert [(r.subject, r.relation, r.reference, r.source) for r in request.relations] == [
        ("mug", "on top of", "mug mat", "request")]


@pytest.mark.parametrize("text", ["set the table with happiness", "тарелка и вилка",
                                  "テーブルを準備して", "a plate and some joy"])
def test_a_chunk_that_names_no_tableware_is_refused_without_asking(text: str,
                                                                   catalog: Catalog) -> None:
    log = no_llm()
    with pytest.raises(UnknownObject) as err:
        understand(text, catalog=catalog, llm=log)
    assert "\n" not in str(err.value) and str(err.value).startswith("request: unknown object")
    assert not log.calls


def test_the_llm_reads_what_the_matcher_cannot(chat_server: ChatServer,
                                               catalog: Catalog) -> None:
    log = openai(chat_server, "1 soup spoon")
    request = understand("a soup bowl and something to eat soup with", catalog=catalog,
                         llm=log, seed=3)
    assert kinds(request) == ["soup bowl", "soup spoon"]
    assert request.source == "llm" and len(request.calls) == 1 == len(log.calls)
    prompt = chat_server.requests[-1]["messages"][-1]["content"]
    assert '"something to eat soup"' in prompt and "soup spoon" in prompt
    assert any("something to eat soup" in w for w in request.warnings)


def test_openai_is_asked_for_json_that_names_catalog_objects(chat_server: ChatServer,
                                                            catalog: Catalog) -> None:
    log = openai(chat_server, json.dumps({"objects": [{"name": "mug", "count": 2}]}))
    request = understand("tea for me", catalog=catalog, llm=log)
    assert kinds(request) == ["mug", "mug"]
    sent = chat_server.requests[-1]["response_format"]
    assert sent["type"] == "json_schema" and sent["json_schema"]["strict"] is True
    names = sent["json_schema"]["schema"]["properties"]["objects"]["items"]["properties"]
    assert names["name"]["enum"] == catalog.names()
    assert log.llm.structured_output is True  # type: ignore[attr-defined]


def test_a_server_without_structured_output_is_asked_again_in_lines(
        chat_server: ChatServer, catalog: Catalog) -> None:
    chat_server.refuse_response_format = True
    log = openai(chat_server, "2 dinner fork")
    request = understand("cutlery", catalog=catalog, llm=log)
    assert kinds(request) == ["dinner fork", "dinner fork"]
    assert [("response_format" in b) for b in chat_server.requests] == [True, False]
    understand("cutlery", catalog=catalog, llm=log)
    assert "response_format" not in chat_server.requests[-1]  # not asked again


def test_an_answer_outside_the_catalog_is_one_line_with_suggestions(
        chat_server: ChatServer, catalog: Catalog) -> None:
    with pytest.raises(UnknownObject) as err:
        understand("a plate and something salty", catalog=catalog,
                   llm=openai(chat_server, "1 salt shaker"))
    message = str(err.value)
    assert message.startswith("request: the openai LLM read 'something salty' as: unknown "
                              "object 'salt shaker'") and "\n" not in message


def test_none_ignores_a_chunk_beside_objects_and_refuses_it_alone(
        chat_server: ChatServer, catalog: Catalog) -> None:
    request = understand("a bowl, a spoon and cereal", catalog=catalog,
                         llm=openai(chat_server, "none"))
    assert kinds(request) == ["fruit bowl", "soup spoon"]
    assert any("no object in 'cereal'" in w for w in request.warnings)
    with pytest.raises(UnknownObject, match="unknown object 'cereal'"):
        understand("cereal please", catalog=catalog, llm=openai(chat_server, "none"))


def test_without_an_llm_an_unread_chunk_is_unknown(catalog: Catalog) -> None:
    with pytest.raises(UnknownObject, match="'something to drink'"):
        understand("a plate and something to drink", catalog=catalog, llm=None)


def test_recorded_answers_replay_the_same_reading(chat_server: ChatServer, tmp_path: Path,
                                                  catalog: Catalog) -> None:
    chat_server.reply = lambda body: "1 dinner plate\n1 dinner fork\n1 dinner knife"
    rec = tmp_path / "calls.jsonl"
    live = make_llm("openai", BackendOptions(base_url=chat_server.url), record=rec)
    first = understand("the usual for two", catalog=catalog, llm=live, seed=5)
    again = understand("the usual for two", catalog=catalog, seed=5,
                       llm=make_llm("replay", BackendOptions(replay_path=rec)))
    assert first.items == again.items and first.diners == again.diners == 2
    assert kinds(first) == ["dinner plate", "dinner fork", "dinner knife"] * 1 + [
        "dinner plate", "dinner fork", "dinner knife"]


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
                                       "contradict each other"):
        arrange("a mug on a coaster", llm="openai", options=options,
                llm_options=BackendOptions(base_url=chat_server.url, max_retries=0))


def test_the_items_call_belongs_to_the_arrangement(chat_server: ChatServer) -> None:
    chat_server.reply = scripted([TASK1_GOOD], items="1 dinner fork\n1 dinner knife")
    result = arrange("a dinner plate and cutlery", llm="openai",
                     llm_options=BackendOptions(base_url=chat_server.url, max_retries=0))
    a = result.arrangement
    assert [p.kind for p in a.placements] == ["dinner plate", "dinner fork", "dinner knife"]
    assert a.read_by == "llm" and a.llm is not None
    assert "ask the robot to put on the table" in a.llm.calls[0].prompt


@pytest.mark.parametrize(("answer", "expected"), [
    ('{"objects": [{"name": "fork", "count": 2}, {"name": "plate", "count": 1}]}',
     [("dinner fork", 2), ("dinner plate", 1)]),
    ('```json\n[{"name": "mug", "count": 1}]\n```', [("mug", 1)]),
    ("- 2 x fork\n- knife\n* one plate.", [("dinner fork", 2), ("dinner knife", 1),
                                           ("dinner plate", 1)]),
    ("Here are the objects the robot should set:\nfork x2\n", [("dinner fork", 2)]),
    ("1. dinner plate\n2. dinner fork", [("dinner plate", 1), ("dinner fork", 1)]),
    ("none", []),
    ("0 forks\n99 plates", []),
])
def test_the_answer_reader_takes_json_and_lines(answer: str, expected: list[tuple[str, int]],
                                               catalog: Catalog) -> None:
    mentions, unknown = read_items_answer(answer, catalog)
    assert [(m.spec.name, m.count) for m in mentions] == expected and not unknown


def test_a_huge_answer_is_read_in_part(catalog: Catalog) -> None:
    mentions, _ = read_items_answer("1 mug\n" + "x" * 1_000_000, catalog)
    assert [m.spec.name for m in mentions] == ["mug"]


def test_the_gate_counts_catalog_words_and_dining_words(catalog: Catalog) -> None:
    assert may_name_tableware("a steak", catalog) and may_name_tableware("mugs", catalog)
    assert not may_name_tableware("happiness", catalog)


def test_the_schema_and_grammar_list_every_catalog_name(catalog: Catalog) -> None:
    grammar = items_grammar(catalog)
    assert all(f'"{name}"' in grammar for name in catalog.names())
    schema = items_schema(catalog)
    assert schema["required"] == ["objects"] and schema["additionalProperties"] is False


@pytest.mark.embedded
def test_the_embedded_model_answers_in_catalog_names_repeatably(catalog: Catalog) -> None:
    first = understand("the usual", catalog=catalog, llm="embedded", seed=2)
    again = understand("the usual", catalog=catalog, llm="embedded", seed=2)
    assert first.items == again.items and first.items
    assert all(it.kind in catalog for it in first.items)


_PIECES = ["a", "the", "two", "²", "①", "of", "for", "on", "on top of", "to the left of",
           "in the middle", "under", "behind", "and", ",", "with", "my", "wife's", "mug's",
           "coffee", "soup", "happiness", "usual", "cutlery", "'s", "-", "—", "or", "for two",
           "plates", "mugs", "plate", "mug", "coaster", "glass", "bowl", "lid", "1e3", "0",
           "31", "тарелка", "\u0000", "\ud800", "ｐｌａｔｅ", "\n", "[", "]", "'"]


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
    st.sampled_from(["1", "two", "x2", "×", "- ", "* ", "1.", "fork", "dinner plate", "none",
                     '{"objects": [', '{"name": "mug", "count": 2}', "]}", "\n", ",", "mug",
                     "salt shaker", "```json", "```", '"count": true', "null"]),
    max_size=20).map("".join))
def test_any_items_answer_reads_to_catalog_objects(answer: str) -> None:
    catalog = Catalog.load(use_env=False)
    mentions, unknown = read_items_answer(answer, catalog)
    assert all(m.spec.name in catalog and 1 <= m.count <= 30 for m in mentions)
    assert all(isinstance(u, str) and len(u.split()) <= 4 for u in unknown)
