"""A plan from ``POST /v1/plans``, executed in ``kinematic2d``, is the run ``llm-grop run``
makes with the same seed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from llm_grop import execute, plan_from_dict
from llm_grop.cli import main
from llm_grop.contract.run_json import run_to_dict
from service_support import RECORDING, Server


@pytest.mark.parametrize("seed", [5, 6])
def test_executing_the_served_plan_is_the_cli_run(server: Server, tmp_path: Path,
                                                  seed: int) -> None:
    out = tmp_path / "run.json"
    assert main(["run", "--task", "8", "--seed", str(seed), "--llm", "replay", "--replay",
                 str(RECORDING), "--json", str(out), "-q"]) == 0
    cli = json.loads(out.read_text(encoding="utf-8"))
    with server.client() as c:  # the packaged room, its chair sampled for the seed
        r = c.post("/v1/plans", json={"task": 8, "seed": seed})
    assert r.status_code == 200, r.text
    served = r.json()["plan"]
    assert served["plan"]["order"] == cli["plan"]["order"]
    assert served["plan"]["standing"] == cli["plan"]["standing"]
    executed = run_to_dict(execute(plan_from_dict(served), simulator="kinematic2d"))
    for key in ("steps", "final", "success", "execution_time_s", "unplaced", "scene"):
        assert executed[key] == cli[key], key


def test_a_plan_for_a_given_arrangement(server: Server) -> None:
    with server.client() as c:
        arranged = c.post("/v1/arrangements", json={
            "request": "a dinner plate, a dinner fork and a dinner knife"}).json()
        r = c.post("/v1/plans", json={"arrangement": arranged["arrangement"], "seed": 1,
                                      "robot": [0.6, 0.6, 0.0], "chairs": []})
    assert r.status_code == 200, r.text
    p = r.json()["plan"]
    assert p["scene"]["robot"]["start"] == [0.6, 0.6, 0.0] and p["scene"]["chairs"] == []
    targets = {s["object"]: s["pose"][:2] for s in p["steps"] if s["action"] == "place"}
    given = {o["name"]: [o["x"], o["y"]] for o in arranged["arrangement"]["objects"]}
    assert targets == given
