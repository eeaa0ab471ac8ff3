"""The catalog matcher (the fast path): natural-language requests into catalog items."""

from __future__ import annotations

import pytest

from llm_grop.errors import BadInput, UnknownObject
from llm_grop.language.request import parse_request, read_request
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import MAX_COUNT, MAX_OBJECTS, Request, items_from_names


@pytest.fixture(scope="module")
def catalog() -> Catalog:
    return Catalog.load(use_env=False)


def names(text: str, catalog: Catalog) -> list[str]:
    return [item.name for item in parse_request(text, catalog).items]


@pytest.mark.parametrize(("text", "expected"), [
    ("set the table with a plate, two forks and a knife",
     ["dinner plate", "dinner fork", "dinner fork 2", "dinner knife"]),
    ("I'd like a mug with its lid and a dinner plate", ["mug", "mug lid", "dinner plate"]),
    ("Set the table with a dinner plate, a dinner fork and a dinner knife",
     ["dinner plate", "dinner fork", "dinner knife"]),
    ("a bread plate, a water cup, and bread", ["bread plate", "water cup", "bread"]),
    ("mug, bread plate, mug mat", ["mug", "bread plate", "mug mat"]),
    ("3 strawberries", ["strawberry", "strawberry 2", "strawberry 3"]),
    ("three strawberries", ["strawberry", "strawberry 2", "strawberry 3"]),
    ("a pair of forks", ["dinner fork", "dinner fork 2"]),
    ("a couple of knives", ["dinner knife", "dinner knife 2"]),
    ("twelve forks", [f"dinner fork{'' if k == 1 else f' {k}'}" for k in range(1, 13)]),
    ("Please set the table for dinner: a plate & a fork + a knife.",
     ["dinner plate", "dinner fork", "dinner knife"]),
    ("can you put a teacup on a coaster on the table?", ["mug", "mug mat"]),
    ("a fruit bowl plus one strawberry and a mug", ["fruit bowl", "strawberry", "mug"]),
    ("a Dinner-Knife", ["dinner knife"]),
    ("the mug\u2019s lid", ["mug lid"]),
    ("a bread and butter plate", ["bread plate"]),
    ("two glasses", ["water cup", "water cup 2"]),
    ("some bread", ["bread"]),
])
def test_requests_resolve_to_items_in_order(text: str, expected: list[str], catalog: Catalog
                                            ) -> None:
    assert names(text, catalog) == expected


def test_longest_name_wins(catalog: Catalog) -> None:
    request = parse_request("a dinner knife, a mug lid and a mug mat", catalog)
    assert [i.kind for i in request.items] == ["dinner knife", "mug lid", "mug mat"]


def test_repeated_mentions_add_instances_grouped_by_kind(catalog: Catalog) -> None:
    assert names("a fork, a plate and another fork", catalog) == [
        "dinner fork", "dinner fork 2", "dinner plate"]


def test_items_carry_their_catalog_spec(catalog: Catalog) -> None:
    request = parse_request("two forks", catalog)
    assert isinstance(request, Request)
    assert all(i.spec == catalog.specs["dinner fork"] for i in request.items)


def test_text_is_kept(catalog: Catalog) -> None:
    assert parse_request("  a mug  ", catalog).text == "a mug"


@pytest.mark.parametrize("text", ["", "   ", "\n\t"])
def test_empty_request_is_bad_input(text: str, catalog: Catalog) -> None:
    with pytest.raises(BadInput, match=r"^request: empty; name the objects"):
        parse_request(text, catalog)


def test_request_naming_nothing_is_bad_input(catalog: Catalog) -> None:
    with pytest.raises(BadInput, match="no object named in 'please set the table'"):
        parse_request("please set the table", catalog)


def test_unknown_object_is_named_with_suggestions(catalog: Catalog) -> None:
    with pytest.raises(UnknownObject) as info:
        parse_request("set the table with a plate and a spork", catalog)
    assert info.value.name == "spork"
    assert "dinner fork" in info.value.suggestions
    assert str(info.value).startswith("request: unknown object 'spork'; did you mean")
    assert "\n" not in str(info.value)


def test_request_with_only_an_unknown_object(catalog: Catalog) -> None:
    with pytest.raises(UnknownObject) as info:
        parse_request("a teapot", catalog)
    assert info.value.name == "teapot"


def test_unknown_modifier_is_part_of_the_unknown_name(catalog: Catalog) -> None:
    with pytest.raises(UnknownObject) as info:
        parse_request("a plate and a blue mug", catalog)
    assert info.value.name == "blue mug"
    assert info.value.suggestions[0] == "mug"


@pytest.mark.parametrize(("text", "message"), [
    ("strawberries", "how many 'strawberries'"),
    ("a plate and some knives", "how many 'knives'"),
    ("a few strawberries", "how many 'strawberries'"),
    ("two and a plate", "'two' is not followed by an object name"),
    ("0 forks", "a count must be at least 1"),
    ("a mug or a cup", "'or' leaves the choice open"),
    (f"{MAX_COUNT + 1} forks", f"at most {MAX_COUNT} of one object"),
    ("12 forks, 12 knives and 7 plates", f"31 objects is too many; at most {MAX_OBJECTS}"),
])
def test_bad_counts_and_choices_are_bad_input(text: str, message: str, catalog: Catalog
                                              ) -> None:
    with pytest.raises(BadInput, match=message) as info:
        parse_request(text, catalog)
    assert not isinstance(info.value, UnknownObject)


def test_exactly_the_caps_are_allowed(catalog: Catalog) -> None:
    assert len(parse_request("12 forks, 12 knives and 6 plates", catalog).items) == MAX_OBJECTS
    assert len(parse_request(f"{MAX_COUNT} strawberries", catalog).items) == MAX_COUNT


def test_user_catalog_objects_are_recognised(tmp_path, catalog: Catalog) -> None:
    extra = tmp_path / "extra.yaml"
    extra.write_text("objects:\n  - name: chopstick rest\n    shape: box\n"
                     "    size: [0.05, 0.02]\n    height: 0.01\n    synonyms: [hashioki]\n")
    mine = Catalog.load([extra], use_env=False)
    assert names("a hashioki and two chopstick rests", mine) == [
        "chopstick rest", "chopstick rest 2", "chopstick rest 3"]
    with pytest.raises(UnknownObject):
        parse_request("a hashioki", catalog)


def test_items_from_names_counts_repetitions(catalog: Catalog) -> None:
    items = items_from_names(["dinner fork", "mug", "fork", "Dinner Forks"], catalog)
    assert [i.name for i in items] == ["dinner fork", "dinner fork 2", "dinner fork 3", "mug"]


def test_items_from_names_rejects_unknown_names(catalog: Catalog) -> None:
    with pytest.raises(UnknownObject, match=r"^task 3: unknown object 'spork'"):
        items_from_names(["mug", "spork"], catalog, where="task 3")
    with pytest.raises(BadInput, match="no objects"):
        items_from_names([], catalog)


@pytest.mark.parametrize("text", [
    "set the table for six people, each with a dinner plate, a dinner fork, a dinner knife "
    "and a water cup",
    "set the table for six: a dinner plate, a dinner fork, a dinner knife and a water cup each",
    "for 6 guests, a dinner plate, a dinner fork, a dinner knife and a water cup apiece",
    "six place settings, per person a dinner plate, a dinner fork, a dinner knife and a "
    "water cup",
])
def test_each_diner_is_read_where_several_are_set_for(text: str, catalog: Catalog) -> None:
    reading = read_request(text, catalog)
    assert reading.diners == 6 and not reading.unread and not reading.doubts
    assert reading.reading is not None
    assert [(o.name, o.count) for o in reading.reading.objects] == [
        ("dinner plate", 1), ("dinner fork", 1), ("dinner knife", 1), ("water cup", 1)]


def test_each_is_left_unread_for_one_diner(catalog: Catalog) -> None:
    # With one diner "each" says something the matcher cannot read ("a fork each side"?).
    reading = read_request("a dinner plate and a dinner fork each", catalog)
    assert [u.text for u in reading.unread] == ["each"] and reading.reading is None
