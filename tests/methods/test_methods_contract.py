"""Every registered method runs a tiny episode: deterministic for a seed, valid output."""

from __future__ import annotations

import json

import jsonschema
import pytest

from llm_grop.api import make_llm, run
from llm_grop.contract.run_json import run_to_dict
from llm_grop.contract.schemas import json_schema
from llm_grop.errors import BadInput
from llm_grop.files.jsonio import dumps
from llm_grop.llm.base import BackendOptions
from llm_grop.methods.registry import available_methods, get_method
from scripted import TASK1_GOOD, scripted

REQUEST = "set the table with a dinner plate, a dinner fork and a dinner knife"


def _without_wall_times(data: dict) -> dict:
    data = json.loads(dumps(data))
    data.pop("planning_time_s")
    for call in data["planned"].get("llm", {}).get("log", []):
        call.pop("latency_s")
    return data


def _run(server, method: str, seed: int) -> dict:
    log = make_llm("openai", BackendOptions(base_url=server.url, api_key="test", max_retries=0))
    result = run(REQUEST, method=method, seed=seed, chairs=1, llm=log)
    return run_to_dict(result)


def test_the_papers_four_methods_are_registered() -> None:
    assert available_methods()[:4] == ["tpra", "latp", "grop", "llm-grop"]
    with pytest.raises(BadInput, match="unknown method 'magic'"):
        get_method("magic")


@pytest.mark.parametrize("method", available_methods())
def test_method_contract(chat_server, method: str) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    first = _run(chat_server, method, seed=3)
    again = _run(chat_server, method, seed=3)
    assert _without_wall_times(first) == _without_wall_times(again)
    jsonschema.Draft202012Validator(json_schema("run")).validate(first)
    assert first["method"] == method and first["seed"] == 3
    assert isinstance(first["success"], bool)
    assert first["execution_time_s"] > 0 and first["planning_time_s"] >= 0
    names = {"dinner plate", "dinner fork", "dinner knife"}
    assert set(first["plan"]["order"]) == names
    placed = {o["name"] for o in first["final"]["objects"]}
    assert placed == names - set(first["unplaced"])
    assert first["success"] == (placed == names)
    w, d = first["final"]["table"]["size"]
    for o in first["final"]["objects"]:
        assert abs(o["x"]) <= w / 2 and abs(o["y"]) <= d / 2
    for step in first["steps"]:
        assert step["action"] in {"navigate", "pick", "place"}
        assert step["duration_s"] >= 0 and isinstance(step["ok"], bool)
        if step["action"] == "navigate":
            assert len(step["goal"]) == 3
        if step["action"] == "place" and step["ok"]:
            assert len(step["standing"]) == 3 and len(step["pose"]) == 3
    if get_method(method).uses_llm:
        assert first["planned"]["relations"]
        assert first["planned"]["llm"]["backend"] == "openai"
    else:
        assert first["planned"]["relations"] == [] and "llm" not in first["planned"]


def test_methods_see_the_same_chairs(chat_server) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    chairs = {m: _run(chat_server, m, seed=5)["scene"]["chairs"] for m in available_methods()}
    assert len({json.dumps(c) for c in chairs.values()}) == 1
