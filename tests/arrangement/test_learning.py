"""Learning a person's style from example settings (issue 42): the relations and gaps read
with the one meaning of each relation, what the examples contradict, bad examples, and
the learned sentences set a new table the same way."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from learning_support import (
    CATALOG,
    LEFT_HANDED,
    NO_CALLS,
    SETTING,
    STACKED,
    USUAL,
    arranged,
    write_example,
)
from llm_grop import BackendOptions, arrange, learn, run
from llm_grop.arrangement.examples import (
    OFF_TABLE_SLACK_M,
    observed_gap_m,
    read_example,
    relation_between,
)
from llm_grop.arrangement.fidelity import GAP_TOLERANCE_M, edge_gap_m
from llm_grop.arrangement.learning import Learning, learn_from
from llm_grop.arrangement.predicates import Footprint
from llm_grop.arrangement.preferences import load_preference_file, read_preferences
from llm_grop.contract.run_json import run_to_dict
from llm_grop.contract.serialize import arrangement_to_dict
from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Placement
from llm_grop.world.relation import DIRECTION, MEANINGS
from llm_grop.world.request import items_from_names
from llm_grop.world.table import Table

STACK_REQUEST = "a dinner plate, a mug, a mug lid and a mug mat"


def _said(learning: Learning) -> set[tuple[str, str | None, str | None]]:
    return {(s.subject, s.relation, s.reference) for s in learning.sentences}


#: Every object the styles name.
ITEMS = items_from_names(["dinner plate", "dinner fork", "dinner knife", "mug", "mug lid",
                          "mug mat"], CATALOG)


def _stated(style: tuple[str, ...]) -> dict[tuple[str, str, str | None], float | None]:
    """The relations a style's sentences state, with their gaps (metres), as the preference
    reader reads them."""
    read = read_preferences([s for s in style if "edge" not in s], [], ITEMS, CATALOG)
    return {r.key(): r.gap_m for r in read.relations}


def _relations(learning: Learning) -> set[tuple[str, str | None, str | None]]:
    """The learned relations, without the distances from the diner's edge."""
    return {k for k in _said(learning) if k[1] is not None}


@pytest.mark.parametrize(("style", "request_text"), [
    (LEFT_HANDED, SETTING), (USUAL, SETTING), (STACKED, STACK_REQUEST)],
    ids=["left-handed", "usual", "stacked"])
def test_two_examples_teach_the_style_they_were_set_in(style, request_text) -> None:
    learned = learn([arranged(style, 0, request_text), arranged(style, 1, request_text)],
                    catalog=CATALOG)
    stated = _stated(style)
    assert _relations(learned) == set(stated)
    assert [s.subject for s in learned.sentences if s.relation is None] == ["dinner plate"]
    for s in learned.sentences:
        assert s.sources == ("example 1", "example 2")
        low, high = s.spread_cm or (0, 0)
        if s.gap_cm is not None:
            assert low <= s.gap_cm <= high
        if s.relation is not None and stated.get((s.subject, s.relation, s.reference)):
            # The sampler keeps a stated gap within its tolerance; the median does too.
            assert abs(s.gap_cm / 100 - stated[(s.subject, s.relation, s.reference)]) \
                <= GAP_TOLERANCE_M + 1e-3
    assert not learned.contradictions and not learned.warnings


def test_the_learned_file_sets_a_new_table_the_same_way(tmp_path: Path) -> None:
    examples = [write_example(tmp_path / f"ex{k}.json", LEFT_HANDED, k) for k in range(3)]
    learned = learn(examples, catalog=CATALOG)
    path = tmp_path / "prefs.yaml"
    path.write_text(learned.preference_file(), encoding="utf-8")
    sentences = load_preference_file(path)
    assert sentences == tuple(s.sentence for s in learned.sentences)
    assert "ex0.json" in path.read_text().splitlines()[1]
    result = arrange(SETTING, llm="replay",
                     llm_options=BackendOptions(replay_path=str(NO_CALLS)), seed=11,
                     catalog=CATALOG, preferences_file=str(path))
    placed = {p.name: p for p in result.arrangement.placements}
    for s in learned.sentences:
        if s.relation is None:
            p = placed[s.subject]
            edge = float(edge_gap_m(p.y, Footprint.of_placement(p), result.arrangement.table))
            assert abs(edge - s.gap_cm / 100) <= GAP_TOLERANCE_M + 1e-3
            continue
        subject, reference = placed[s.subject], placed[s.reference]
        assert relation_between(subject, reference) == s.relation, s.sentence
        assert abs(observed_gap_m(s.relation, subject, reference) - s.gap_cm / 100) \
            <= GAP_TOLERANCE_M + 1e-3, s.sentence
    # Learning again from what the learned file set gives the same relations.
    again = learn([arrangement_to_dict(result.arrangement)], catalog=CATALOG)
    assert _said(again) == _said(learned)


def test_examples_that_disagree_are_reported_not_learned(tmp_path: Path) -> None:
    left = write_example(tmp_path / "left.json", LEFT_HANDED, 0)
    usual = write_example(tmp_path / "usual.json", USUAL, 0)
    learned = learn([left, usual], catalog=CATALOG)
    pairs = {(c.subject, c.reference) for c in learned.contradictions}
    assert ("dinner fork", "dinner plate") in pairs
    assert not any(s.subject == "dinner fork" for s in learned.sentences)
    fork = next(c for c in learned.contradictions if c.subject == "dinner fork")
    assert fork.readings == (("to the right of", (str(left),)), ("to the left of", (str(usual),)))
    assert fork.message() == (
        "the examples disagree on where the dinner fork goes: to the right of the dinner "
        f"plate in {left}; to the left of it in {usual}; not learned")
    # What they agree on is still learned: the plate's distance from the diner's edge.
    edge = next(s for s in learned.sentences if s.relation is None)
    assert edge.subject == "dinner plate" and edge.sources == (str(left), str(usual))
    assert edge.spread_cm is not None and edge.spread_cm[0] < edge.spread_cm[1]


def test_stacking_is_read_from_on_and_a_stack_is_not_related_through(tmp_path: Path) -> None:
    doc = arranged(STACKED, 0, STACK_REQUEST)
    learned = learn([doc], catalog=CATALOG)
    said = _said(learned)
    assert ("mug lid", "on top of", "mug") in said and ("mug", "on top of", "mug mat") in said
    assert not any({"mug lid", "mug mat"} == {s.subject, s.reference} for s in learned.sentences)
    # Without `on` the lid and the mug overlap on both axes: no relation is read.
    for o in doc["objects"]:
        o["on"] = None
    learned = learn([doc], catalog=CATALOG)
    assert any("overlap" in w and "neither rests on the other" in w for w in learned.warnings)
    assert not any(s.relation == "on top of" for s in learned.sentences)


def test_each_diner_is_read_in_their_own_frame() -> None:
    doc = arranged(USUAL, 0, f"set the table for two with {SETTING}", Table(1.8, 0.9))
    learned = learn([doc], catalog=CATALOG)
    assert _relations(learned) == set(_stated(USUAL))
    assert all(s.sources == ("example 1 (diner 1)", "example 1 (diner 2)")
               for s in learned.sentences)


def test_a_shared_object_is_left_out_with_a_warning() -> None:
    doc = arranged(USUAL, 0, f"set the table for two with {SETTING}", Table(1.8, 0.9))
    doc["objects"][0]["diner"] = None
    learned = learn([doc, arranged(USUAL, 1)], catalog=CATALOG)
    assert learned.warnings == ("example 1: left out dinner plate: shared by the diners, in "
                                "no one's setting",)
    # The first diner's setting without its plate is still read: its fork, knife and mug.
    assert _relations(learned) == set(_stated(USUAL))


def test_a_run_json_is_read_by_its_final(tmp_path: Path) -> None:
    from llm_grop.arrangement.pipeline import ArrangeOptions

    episode = run(SETTING, llm="replay", llm_options=BackendOptions(replay_path=str(NO_CALLS)),
                  seed=0, catalog=CATALOG, options=ArrangeOptions(preference_pool=LEFT_HANDED),
                  chairs=0)
    path = tmp_path / "run.json"
    path.write_text(json.dumps(run_to_dict(episode)), encoding="utf-8")
    learned = learn([path, arranged(LEFT_HANDED, 1)], catalog=CATALOG)
    assert learned.examples == (str(path), "example 2")
    assert ("dinner fork", "to the right of", "dinner plate") in _said(learned)


def test_sizes_left_out_are_taken_from_the_catalog() -> None:
    doc = arranged(USUAL, 0)
    for o in doc["objects"]:
        del o["size"], o["shape"], o["kind"]
    assert _said(learn([doc], catalog=CATALOG)) == _said(learn([arranged(USUAL, 0)],
                                                               catalog=CATALOG))


# -- bad examples: one line each -----------------------------------------------------------

def _broken(tmp_path: Path, name: str, change) -> Path:  # type: ignore[no-untyped-def]
    doc = arranged(USUAL, 0)
    change(doc)
    path = tmp_path / name
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def _unknown(doc: dict) -> None:
    doc["objects"][1]["name"] = doc["objects"][1]["kind"] = "flying saucer"


def _off(doc: dict) -> None:
    doc["objects"][1]["x"] = 0.5


def _no_objects(doc: dict) -> None:
    doc["objects"] = []


def _lost_support(doc: dict) -> None:
    doc["objects"][1]["on"] = "tray"


@pytest.mark.parametrize(("change", "message"), [
    (_unknown, "bad.json: objects[1] ('flying saucer'): unknown object 'flying saucer'"),
    (_off, "bad.json: objects[1] ('dinner fork'): lies off the 0.9 x 0.6 m table (centre at "
           "(+0.500, "),
    (_no_objects, "bad.json: no objects; an example is a table setting"),
    (_lost_support, "bad.json: objects[1] ('dinner fork').on: 'tray' is not an object of "
                    "the example"),
])
def test_an_example_that_is_not_a_setting_is_one_line(tmp_path: Path, change, message) -> None:
    bad = _broken(tmp_path, "bad.json", change)
    with pytest.raises(BadInput) as caught:
        learn([bad], catalog=CATALOG)
    assert str(caught.value).startswith(f"{tmp_path}/{message}")
    assert "\n" not in str(caught.value)


def test_unreadable_json_names_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text("{ not json", encoding="utf-8")
    with pytest.raises(BadInput, match=r"bad\.json: not valid JSON \(line 1: "):
        learn([bad], catalog=CATALOG)


def test_a_bad_example_among_several_is_a_warning(tmp_path: Path) -> None:
    bad = _broken(tmp_path, "bad.json", _off)
    good = [write_example(tmp_path / f"ex{k}.json", LEFT_HANDED, k) for k in range(2)]
    learned = learn([good[0], bad, good[1]], catalog=CATALOG)
    assert learned.examples == tuple(map(str, good))
    assert len(learned.warnings) == 1 and learned.warnings[0].startswith(f"{bad}: objects[1]")
    assert learned.warnings[0].endswith("; skipped")
    assert ("dinner fork", "to the right of", "dinner plate") in _said(learned)
    with pytest.raises(BadInput, match=r"^none of the 2 examples is a table setting: .*bad\.json"):
        learn([bad, _broken(tmp_path, "empty.json", _no_objects)], catalog=CATALOG)


def test_an_object_just_over_the_edge_by_rounding_is_on_the_table() -> None:
    doc = arranged(USUAL, 0)
    fork = doc["objects"][1]
    fork["x"] = -0.45 + fork["size"][0] / 2 - OFF_TABLE_SLACK_M / 2
    read_example(doc, CATALOG)


# -- one meaning of each relation ----------------------------------------------------------

_LYING = [n for n, m in MEANINGS.items() if m.reference and m.rests is None]
_HALF = st.floats(0.005, 0.2)


@settings(max_examples=200, deadline=None)
@given(relation=st.sampled_from(_LYING), sub=st.tuples(st.booleans(), _HALF, _HALF),
       ref=st.tuples(st.booleans(), _HALF, _HALF), gap=st.floats(0.0, 0.3),
       across=st.floats(-0.99, 0.99))
def test_the_relation_read_back_is_the_one_placed(relation, sub, ref, gap, across) -> None:
    def placement(name: str, shape: tuple[bool, float, float], x: float, y: float) -> Placement:
        circle, hx, hy = shape
        size = (2 * hx, 2 * hx) if circle else (2 * hx, 2 * hy)
        return Placement(name, x, y, 0.0, "circle" if circle else "box", size)

    r = placement("reference", ref, 0.1, -0.2)
    s0 = placement("subject", sub, 0.0, 0.0)
    fs, fr = Footprint.of_placement(s0), Footprint.of_placement(r)
    dx, dy = DIRECTION[relation]
    # Along each axis the relation moves on, `gap` between the edges; across, aligned.
    x = r.x + (dx * (gap + fs.hx + fr.hx) if dx else across * max(fs.hx, fr.hx))
    y = r.y + (dy * (gap + fs.hy + fr.hy) if dy else across * max(fs.hy, fr.hy))
    s = placement("subject", sub, x, y)
    assert relation_between(s, r) == relation
    assert math.isclose(observed_gap_m(relation, s, r), gap, abs_tol=1e-9)


def test_learning_reads_observations_as_given() -> None:
    from llm_grop.arrangement.examples import Observation

    items = items_from_names(["dinner plate", "dinner fork"], CATALOG)
    plate = Placement("dinner plate", 0.0, -0.1, 0.0, "circle", (0.27, 0.27))
    fork = Placement("dinner fork", -0.1675, -0.1, 0.0, "box", (0.025, 0.2))
    learned = learn_from([Observation("hand", items, (plate, fork), Table())], CATALOG)
    assert [s.sentence for s in learned.sentences] == [
        "the dinner plate 6.5 cm from the diner's edge of the table",
        "the dinner fork 2 cm to the left of the dinner plate"]


def test_each_object_is_tied_to_its_nearest_larger_neighbour() -> None:
    # In these two settings the mug lies nearer the knife than the plate (by median).
    docs = [arranged(LEFT_HANDED, seed) for seed in (1, 2)]
    learned = learn(docs, catalog=CATALOG)
    mug = next(s for s in learned.sentences if s.subject == "mug")
    assert (mug.relation, mug.reference) == ("above and to the left of", "dinner plate")
    assert len(learned.sentences) == 4  # the edge and one tie per object but the plate


def test_a_big_object_on_a_small_one_closes_no_cycle() -> None:
    from llm_grop.arrangement.examples import Observation

    items = items_from_names(["dinner plate", "mug mat", "mug"], CATALOG)
    plate = Placement("dinner plate", 0.0, -0.1, 0.0, "circle", (0.27, 0.27), on="mug mat")
    mat = Placement("mug mat", 0.0, -0.1, 0.0, "circle", (0.11, 0.11))
    mug = Placement("mug", 0.2, 0.1, 0.0, "circle", (0.09, 0.09))
    learned = learn_from([Observation("hand", items, (plate, mat, mug), Table())], CATALOG)
    assert {(s.subject, s.relation, s.reference) for s in learned.sentences} == {
        ("dinner plate", None, None), ("dinner plate", "on top of", "mug mat"),
        ("mug", "above and to the right of", "mug mat")}


def test_an_object_a_run_left_tipped_over_is_left_out() -> None:
    doc = arranged(USUAL, 0)
    doc["objects"][3]["tilt_rad"] = 1.5
    learned = learn([doc, arranged(USUAL, 1)], catalog=CATALOG)
    assert learned.warnings == ("example 1: left out mug: tipped over",)
    mug = next(s for s in learned.sentences if s.subject == "mug")
    assert mug.sources == ("example 2",)
