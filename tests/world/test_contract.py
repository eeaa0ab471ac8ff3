"""The JSON contract: published schemas are fresh, fields are only ever added, and what
llm-grop writes is valid against them."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from llm_grop.api import make_llm, run
from llm_grop.contract.models import ArrangementDoc, RunDoc
from llm_grop.contract.run_json import run_to_dict
from llm_grop.contract.schemas import DOCUMENTS, json_schema, schema_text
from llm_grop.contract.serialize import arrangement_from_dict, arrangement_to_dict, read_doc
from llm_grop.errors import BadInput
from llm_grop.llm.base import BackendOptions
from scripted import TASK1_GOOD, scripted

ROOT = Path(__file__).resolve().parents[2]
SCHEMAS = ROOT / "docs" / "schema"
FIELDS = Path(__file__).with_name("contract_fields.txt")
REQUEST = "set the table with a dinner plate, a dinner fork and a dinner knife"


def field_paths(schema: dict[str, Any], node: dict[str, Any], prefix: str,
                seen: tuple[str, ...] = ()) -> set[str]:
    """Every field a document of ``schema`` can hold, as ``run.steps[].goal``."""
    if "$ref" in node:
        name = node["$ref"].rsplit("/", 1)[-1]
        return set() if name in seen else field_paths(schema, schema["$defs"][name], prefix,
                                                       (*seen, name))
    out: set[str] = set()
    for sub in node.get("anyOf", []):
        out |= field_paths(schema, sub, prefix, seen)
    if isinstance(node.get("items"), dict):
        out |= field_paths(schema, node["items"], prefix + "[]", seen)
    for key, sub in node.get("properties", {}).items():
        out |= {f"{prefix}.{key}"} | field_paths(schema, sub, f"{prefix}.{key}", seen)
    return out


def current_fields() -> set[str]:
    return {p for name in DOCUMENTS for p in field_paths(json_schema(name), json_schema(name),
                                                          name)}


@pytest.mark.parametrize("name", sorted(DOCUMENTS))
def test_published_schema_is_fresh(name: str) -> None:
    path = SCHEMAS / f"{name}.schema.json"
    assert path.read_text(encoding="utf-8") == schema_text(name), (
        f"{path} is stale; run: llm-grop schema {name} > docs/schema/{name}.schema.json")


def test_fields_are_only_added() -> None:
    listed = {line for line in FIELDS.read_text().splitlines() if line.strip()}
    now = current_fields()
    assert not listed - now, f"fields removed or renamed: {sorted(listed - now)}"
    assert not now - listed, (f"new fields: add them to {FIELDS.name}: {sorted(now - listed)}")


def _validate(name: str, data: dict[str, Any]) -> None:
    jsonschema.Draft202012Validator(json_schema(name)).validate(data)


@pytest.fixture
def run_json(chat_server) -> dict[str, Any]:  # type: ignore[no-untyped-def]
    chat_server.reply = scripted([TASK1_GOOD])
    log = make_llm("openai", BackendOptions(base_url=chat_server.url, api_key="t",
                                            max_retries=0))
    return run_to_dict(run(REQUEST, seed=1, chairs=1, llm=log))


def test_run_json_is_valid(run_json: dict[str, Any]) -> None:
    _validate("run", run_json)
    _validate("arrangement", run_json["planned"])
    _validate("arrangement", run_json["final"])
    assert run_json["simulator"] == "kinematic2d"
    assert RunDoc.model_validate(run_json).to_json() == json.loads(json.dumps(run_json))
    later = json.loads(json.dumps(run_json))
    later["scene"]["lighting"] = "dim"
    later["steps"][0]["torque_nm"] = 1.5
    assert RunDoc.model_validate(later).to_json() == later


def test_run_json_from_before_the_executive_still_reads(run_json: dict[str, Any]) -> None:
    """A 0.8 run JSON: no reasons, heights, tilts or ``ik_failure_s``."""
    old = json.loads(json.dumps(run_json))
    old.pop("unplaced_reasons")
    old["scene"]["robot"].pop("ik_failure_s")
    for step in old["steps"]:
        step.pop("reason", None)
    for o in old["final"]["objects"]:
        o.pop("z_m"), o.pop("tilt_rad")
    _validate("run", old)
    assert RunDoc.model_validate(old).to_json() == old
    final = arrangement_from_dict(old["final"])
    assert all(p.z_m == 0.0 and p.tilt_rad == 0.0 and p.upright for p in final.placements)
    assert {o["name"] for o in run_json["final"]["objects"]} == \
        {p.name for p in final.placements}


def test_arrangement_reads_back(run_json: dict[str, Any]) -> None:
    planned = arrangement_from_dict(run_json["planned"])
    again = arrangement_to_dict(planned)
    for key in ("request", "table", "objects", "relations", "warnings"):
        assert again[key] == run_json["planned"][key]


def test_readers_keep_fields_a_later_version_adds() -> None:
    data = {"table": {"size": [0.9, 0.6], "legs": 4},
            "objects": [{"name": "mug", "x": 0.1, "y": 0.0, "colour": "blue"}],
            "future": {"anything": [1, 2]}}
    doc = read_doc(ArrangementDoc, data, "a.json")
    assert doc.to_json() == data


@pytest.mark.parametrize(("mutate", "needle"), [
    (lambda d: d.pop("table"), "a.json: table: required, but missing"),
    (lambda d: d["objects"][0].update(x="left"), "a.json: objects[0] ('mug').x: "),
    (lambda d: d["objects"][0].update(shape="oval"), "objects[0] ('mug').shape"),
    (lambda d: d.update(relations=[{"subject": "mug", "relation": "near",
                                    "reference": None}]), "relations[0].relation"),
])
def test_bad_documents_are_one_line_bad_input(mutate, needle: str) -> None:  # type: ignore[no-untyped-def]
    data = {"table": {"size": [0.9, 0.6]}, "objects": [{"name": "mug", "x": 0.1, "y": 0.0}]}
    mutate(data)
    with pytest.raises(BadInput) as exc:
        read_doc(ArrangementDoc, data, "a.json")
    assert needle in str(exc.value) and "\n" not in str(exc.value)
