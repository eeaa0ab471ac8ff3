"""The automatic rater (paper Table III) on hand-written arrangements."""

from __future__ import annotations

import copy
import json
from dataclasses import FrozenInstanceError
from pathlib import Path
from typing import Any

import pytest
import yaml

from llm_grop.errors import BadInput
from llm_grop.evaluation import Check, Rating, rate
from llm_grop.evaluation.conventions import load_conventions
from llm_grop.evaluation.rater import score_of
from llm_grop.world.catalog import Catalog

LABELLED = Path(__file__).parent / "labelled"
LABELS: dict[str, dict[str, Any]] = yaml.safe_load(
    (LABELLED / "labels.yaml").read_text(encoding="utf-8"))["labels"]
SRC = Path(__file__).resolve().parents[2] / "src" / "llm_grop"


def load(name: str) -> dict[str, Any]:
    return json.loads((LABELLED / name).read_text(encoding="utf-8"))


def failed_names(r: Rating) -> set[str]:
    return {c.name for c in r.failed}


@pytest.fixture(scope="module")
def catalog() -> Catalog:
    return Catalog.load(use_env=False)


def test_labelled_set_is_complete() -> None:
    files = sorted(p.name for p in LABELLED.glob("*.json"))
    assert len(files) >= 24
    assert sorted(LABELS) == files
    assert all(lab["score"] in range(1, 6) and lab["reason"] for lab in LABELS.values())


@pytest.mark.parametrize("name", [n for n, lab in LABELS.items() if lab["score"] == 5])
def test_canonical_good_settings_score_5(name: str, catalog: Catalog) -> None:
    r = rate(load(name), catalog=catalog)
    assert r.score == 5, r.summary
    assert not r.failed


@pytest.mark.parametrize("name", [n for n, lab in LABELS.items() if "fails" in lab])
def test_broken_settings_fail_for_the_stated_reason(name: str, catalog: Catalog) -> None:
    label = LABELS[name]
    r = rate(load(name), catalog=catalog)
    assert label["fails"] in failed_names(r), r.summary
    assert r.score < 5
    if label["score"] <= 3:
        assert r.score <= 3, r.summary


def _task1() -> dict[str, Any]:
    return load("01_task1_perfect.json")


def _obj(data: dict[str, Any], name: str) -> dict[str, Any]:
    return next(o for o in data["objects"] if o["name"] == name)


def test_fork_on_the_wrong_side_is_one_major_failure(catalog: Catalog) -> None:
    r = rate(load("12_task1_fork_right.json"), catalog=catalog)
    assert r.score == 3
    [c] = r.failed
    assert (c.name, c.severity) == ("cutlery sides", "major")
    assert "dinner fork" in c.detail and "+0.198" in c.detail


def test_swapped_cutlery_is_two_major_failures(catalog: Catalog) -> None:
    r = rate(load("13_task1_fork_knife_swapped.json"), catalog=catalog)
    assert r.score == 2
    assert [c.name for c in r.failed] == ["cutlery sides", "cutlery sides"]


def test_missing_item_and_off_table_score_1(catalog: Catalog) -> None:
    missing = rate(load("18_task1_missing_knife.json"), catalog=catalog)
    assert missing.score == 1 and "dinner knife missing" in missing.failed[0].detail
    off = rate(load("16_task1_knife_off_table.json"), catalog=catalog)
    assert off.score == 1
    assert any(c.name == "on table" and c.severity == "missing" for c in off.failed)


def test_overhang_beyond_20_percent_is_off_the_table(catalog: Catalog) -> None:
    data = _task1()
    _obj(data, "dinner knife")["x"] = 0.45  # half the knife's width over the right edge
    r = rate(data, catalog=catalog)
    assert r.score == 1 and "on table" in failed_names(r)
    _obj(data, "dinner knife")["x"] = 0.165
    _obj(data, "dinner plate")["y"] = -0.18  # rim 1.5 cm over the edge: 6 % of 27 cm
    r = rate(data, catalog=catalog)
    assert "on table" not in failed_names(r)
    assert "edge overhang" in failed_names(r)


def test_small_tilt_passes_and_crosswise_is_major(catalog: Catalog) -> None:
    data = _task1()
    _obj(data, "dinner knife")["yaw"] = 0.2  # 11 degrees: within 15
    assert rate(data, catalog=catalog).score == 5
    knife = _obj(data, "dinner knife")
    knife["x"], knife["yaw"] = 0.2, 0.35  # 20 degrees, moved out to clear the plate
    r = rate(data, catalog=catalog)
    assert [(c.name, c.severity) for c in r.failed] == [("cutlery parallel", "minor")]
    assert r.score == 4
    knife["yaw"] = 1.2  # 69 degrees: crosswise
    assert ("cutlery parallel", "major") in [(c.name, c.severity) for c in
                                             rate(data, catalog=catalog).failed]
    knife["x"], knife["yaw"] = 0.165, 3.1416  # pointing the other way: still parallel
    assert rate(data, catalog=catalog).score == 5


def test_sloppy_spacing_is_minor_failures(catalog: Catalog) -> None:
    r = rate(load("23_task1_sloppy_spacing.json"), catalog=catalog)
    assert {c.severity for c in r.failed} == {"minor"}
    assert {"plate gap", "cutlery bottoms aligned"} <= failed_names(r)
    assert r.score == 3  # more than two minor failures


def test_lid_beside_mug_breaks_stacking_and_inferred_stack_passes(catalog: Catalog) -> None:
    r = rate(load("20_task5_lid_beside_mug.json"), catalog=catalog)
    assert [(c.name, c.severity) for c in r.failed] == [("stacking", "major")]
    data = load("05_task5_perfect.json")
    _obj(data, "mug lid")["on"] = None  # centred on the mug: taken as resting on it
    assert rate(data, catalog=catalog).score == 5


def test_wrong_support_is_a_convention_break(catalog: Catalog) -> None:
    r = rate(load("38_task3_mug_on_bread_plate.json"), catalog=catalog)
    assert "support allowed" in failed_names(r)
    data = load("05_task5_perfect.json")
    _obj(data, "mug lid")["x"] = 0.32  # says 'on' the mug, but lies beside it
    assert "stack geometry" in failed_names(rate(data, catalog=catalog))


def test_rules_without_their_reference_are_skipped_not_failed(catalog: Catalog) -> None:
    r = rate(load("02_task2_perfect.json"), catalog=catalog)
    by_name = {c.name: c for c in r.checks}
    for name in ("cutlery sides", "cutlery parallel", "plate gap", "napkin position"):
        assert by_name[name].skipped and by_name[name].passed
    assert by_name["centre object"].passed and not by_name["centre object"].skipped
    assert "bread plate" in by_name["centre object"].detail


def test_requested_names_are_normalised(catalog: Catalog) -> None:
    data = _task1()
    assert rate(data, ["dinner plate", "fork", "dinner knife"], catalog).score == 5
    r = rate(data, ["dinner plate", "dinner fork", "dinner fork 2", "dinner knife"], catalog)
    assert r.score == 1
    assert "dinner fork missing (requested 2, found 1)" in r.failed[0].detail
    two = load("36_two_forks_with_kinds.json")
    assert rate(two, ["dinner plate", "dinner fork", "dinner fork 2", "dinner knife"],
                catalog).score == 5


def test_kind_defaults_to_the_name_without_its_number(catalog: Catalog) -> None:
    data = load("36_two_forks_with_kinds.json")
    for o in data["objects"]:
        del o["kind"]
    assert rate(data, catalog=catalog).score == 5


def test_no_request_skips_the_presence_check(catalog: Catalog) -> None:
    data = load("18_task1_missing_knife.json")
    del data["request"]
    r = rate(data, catalog=catalog)
    assert next(c for c in r.checks if c.name == "all items present").skipped
    assert r.score == 5


MUTATIONS = [
    lambda d: d.pop("relations", None),
    lambda d: d.update(relations=[]),
    lambda d: d.update(relations=[{"subject": "dinner fork", "relation": "to the right of",
                                   "reference": "dinner plate"}]),
    lambda d: d.update(relations="not even a list"),
    lambda d: d.update(relations=[{"nonsense": 1}], llm={"backend": 3}),
    lambda d: d.update(llm="garbage"),
]


@pytest.mark.parametrize("name", sorted(LABELS))
def test_rater_ignores_relations_and_llm(name: str, catalog: Catalog) -> None:
    base = rate(load(name), catalog=catalog)
    for mutate in MUTATIONS:
        data = copy.deepcopy(load(name))
        mutate(data)
        assert rate(data, catalog=catalog) == base


MALFORMED = [
    (lambda d: d.pop("table"), "table"),
    (lambda d: d["table"].update(size=[0.9]), "table.size"),
    (lambda d: d["table"].update(size=[0.9, -1]), "table.size"),
    (lambda d: d["table"].update(shape="oval"), "table.shape"),
    (lambda d: d.update(objects={"a": 1}), "objects"),
    (lambda d: d["objects"].append(3), "objects[3]"),
    (lambda d: d["objects"][1].pop("x"), "objects[1] ('dinner fork').x"),
    (lambda d: d["objects"][1].update(x="left"), "objects[1] ('dinner fork').x"),
    (lambda d: d["objects"][1].update(y=True), "objects[1] ('dinner fork').y"),
    (lambda d: d["objects"][1].update(yaw=float("nan")), "objects[1] ('dinner fork').yaw"),
    (lambda d: d["objects"][0].update(shape="oval"), "objects[0] ('dinner plate').shape"),
    (lambda d: d["objects"][0].update(size=[0.27]), "objects[0] ('dinner plate').size"),
    (lambda d: d["objects"][0].update(size=[0.27, 0.2]), "objects[0] ('dinner plate').size"),
    (lambda d: d["objects"][2].update(name=""), "objects[2].name"),
    (lambda d: d["objects"][2].pop("name"), "objects[2].name"),
    (lambda d: d["objects"][2].update(name="dinner fork"), "objects[2].name"),
    (lambda d: d["objects"][2].update(on="teapot"), "objects[2] ('dinner knife').on"),
    (lambda d: d["objects"][2].update(on=5), "objects[2] ('dinner knife').on"),
    (lambda d: d["objects"][2].update(kind=7), "objects[2] ('dinner knife').kind"),
    (lambda d: d["objects"].append({"name": "teapot", "x": 0, "y": 0}), "('teapot').shape"),
    (lambda d: d.update(request=42), "request"),
]


@pytest.mark.parametrize(("mutate", "field"), MALFORMED)
def test_malformed_arrangement_is_bad_input_naming_the_field(mutate, field: str,
                                                             catalog: Catalog) -> None:
    data = _task1()
    mutate(data)
    with pytest.raises(BadInput) as exc:
        rate(data, catalog=catalog)
    message = str(exc.value)
    assert field in message
    assert "\n" not in message


def test_not_a_mapping_and_unknown_request_are_bad_input(catalog: Catalog) -> None:
    with pytest.raises(BadInput, match="expected a JSON object"):
        rate([1, 2], catalog=catalog)  # type: ignore[arg-type]
    data = _task1()
    data["request"] = "a dinner plate and a teapot"
    with pytest.raises(BadInput, match="teapot"):
        rate(data, catalog=catalog)
    with pytest.raises(BadInput, match="requested"):
        rate(_task1(), "dinner plate", catalog)


def test_shape_and_size_default_to_the_catalog(catalog: Catalog) -> None:
    data = _task1()
    for o in data["objects"]:
        del o["shape"], o["size"], o["yaw"], o["on"]
    assert rate(data, catalog=catalog).score == 5


def test_score_mapping() -> None:
    def checks(*severities: str) -> list[Check]:
        return [Check("c", False, s, "x") for s in severities]  # type: ignore[arg-type]

    assert score_of([Check("c", True, "major", "ok")]) == 5
    assert score_of(checks("minor")) == 4
    assert score_of(checks("minor", "minor")) == 4
    assert score_of(checks("minor", "minor", "minor")) == 3
    assert score_of(checks("major")) == 3
    assert score_of(checks("major", "minor")) == 3
    assert score_of(checks("major", "major")) == 2
    assert score_of(checks("major", "major", "missing")) == 1


def test_rating_is_frozen_and_serialisable(catalog: Catalog) -> None:
    r = rate(load("15_task8_mug_overlaps_plate.json"), catalog=catalog)
    with pytest.raises(FrozenInstanceError):
        r.score = 5  # type: ignore[misc]
    data = json.loads(json.dumps(r.to_dict()))
    assert data["score"] == r.score == 2
    assert len(data["checks"]) == len(r.checks)
    assert {"name", "passed", "severity", "detail", "skipped"} <= set(data["checks"][0])
    assert all(c.passed is False for c in r.failed)
    assert r.summary.startswith("2/5")
    assert "mug" in r.failed[0].detail and "cm²" in r.failed[0].detail


def test_conventions_name_only_catalog_kinds(catalog: Catalog) -> None:
    conv = load_conventions()
    kinds = {k for ks in conv.roles.values() for k in ks}
    kinds |= set(conv.centre_preferred) | {k for pair in conv.order for k in pair}
    kinds |= set(conv.supports) | {k for ks in conv.supports.values() for k in ks}
    kinds |= {k for gs in conv.expected_stacks.values() for g in gs for k in g}
    assert kinds <= set(catalog.names())


def test_a_tipped_object_counts_as_not_placed(catalog: Catalog) -> None:
    doc = load("08_task8_perfect.json")
    assert rate(doc, catalog=catalog).score == 5
    doc["objects"][3] |= {"tilt_rad": 1.5708, "z_m": 0.0}  # the mug on its side
    r = rate(doc, catalog=catalog)
    assert r.score == 1
    assert any(c.name == "upright" and "mug lies tipped over" in c.detail for c in r.failed)
    assert any(c.name == "all items present" and "mug missing" in c.detail for c in r.failed)
    doc["objects"][3]["tilt_rad"] = 0.2  # leaning a little still stands
    assert rate(doc, catalog=catalog).score == 5


def test_a_fork_on_its_napkin_is_a_common_setting(catalog: Catalog) -> None:
    doc = {"request": "set the table with a dinner plate, a dinner fork and a napkin",
           "table": {"shape": "rectangle", "size": [0.9, 0.6]},
           "objects": [
               {"name": "dinner plate", "x": 0.0, "y": -0.13},
               {"name": "napkin", "x": -0.2, "y": -0.175},
               {"name": "dinner fork", "x": -0.2, "y": -0.175, "on": "napkin"}]}
    r = rate(doc, catalog=catalog)
    assert r.score == 5, r.summary
    # It is still a fork at its side: on the napkin right of the plate, it is on the
    # wrong side.
    for o in doc["objects"][1:]:
        o["x"] = 0.2
    assert "cutlery sides" in failed_names(rate(doc, catalog=catalog))
