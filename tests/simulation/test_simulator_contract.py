"""Every registered simulator keeps the simulator contract on a tiny scene: the same seed
gives the same execution, the final arrangement is valid, and the steps agree with it."""

from __future__ import annotations

import math

import jsonschema
import pytest

from llm_grop import seeds
from llm_grop.api import run
from llm_grop.contract.run_json import run_to_dict
from llm_grop.contract.schemas import json_schema
from llm_grop.execution import ExecutionPolicy, execute
from llm_grop.planning.grop import build_plan, choose
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.registry import available_simulators, create_simulator
from llm_grop.world.catalog import Catalog
from llm_grop.world.plan import REASONS, Execution, Plan
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import Scene
from scenes import config, placement, two_table_room

NAMES = ["dinner plate", "bread", "dinner fork"]


def tiny_plan() -> tuple[Scene, Plan, Navigator]:
    scene = two_table_room()
    ctx = PlanningContext(scene, items_from_names(NAMES, Catalog.load()))
    cfg = config(placement("dinner plate", 0.0, -0.05),
                 placement("bread", 0.0, -0.05, "box", (0.1, 0.08), on="dinner plate"),
                 placement("dinner fork", -0.22, -0.05, "box", (0.025, 0.2)))
    nav = Navigator(scene, scene.robot.base_radius_m)
    return scene, build_plan(ctx, choose(ctx, [cfg]), nav, seed=0, configurations=1), nav


def check_execution(ex: Execution, plan: Plan, scene: Scene,
                    policy: ExecutionPolicy | None = None) -> None:
    """The final arrangement is valid, the steps agree with it, and success is physical:
    it holds exactly when every object rests upright on its intended support, within
    tolerance of its target (for an object on another, its target moved with its
    support)."""
    policy = policy or ExecutionPolicy()
    names = [p.name for p in ex.final]
    assert len(names) == len(set(names)) and set(names) <= set(plan.order)
    assert set(plan.order) - set(names) <= set(ex.unplaced) <= set(plan.order)
    assert dict(ex.unplaced_reasons).keys() == set(ex.unplaced)
    assert set(dict(ex.unplaced_reasons).values()) <= set(REASONS)
    table = scene.target_top
    final = {p.name: p for p in ex.final}
    for p in ex.final:
        assert abs(p.x) <= table.width / 2 and abs(p.y) <= table.depth / 2, p
        assert p.on is None or p.on in names, p
        assert p.tilt_rad >= 0 and p.z_m >= -0.01, p
    targets = {p.name: p for p in plan.configuration}

    def goal(name: str) -> tuple[float, float]:
        # An object that goes on another belongs where its support really lies.
        t = targets[name]
        support = final.get(t.on or "")
        if support is None:
            return t.x, t.y
        return (t.x + support.x - targets[support.name].x,
                t.y + support.y - targets[support.name].y)

    def in_place(name: str) -> bool:
        p, t = final.get(name), targets[name]
        return (p is not None and p.tilt_rad <= policy.max_tilt_rad and p.on == t.on
                and math.dist((p.x, p.y), goal(name)) <= policy.max_offset_m + 1e-4)

    assert ex.success == all(in_place(n) for n in plan.order)
    assert set(ex.unplaced) == {n for n in plan.order if not in_place(n)}
    for s in ex.steps:
        assert s.action in ("navigate", "pick", "place") and s.duration_s >= 0
        assert s.attempt >= 1 and (s.ok or (s.note and s.reason in REASONS)), s
        assert s.ok == (s.reason is None), s
    assert ex.execution_time_s == pytest.approx(sum(s.duration_s for s in ex.steps))
    assert ex.failures == sum(not s.ok for s in ex.steps)


@pytest.mark.parametrize("name", available_simulators())
def test_simulator_contract(name: str) -> None:
    scene, plan, nav = tiny_plan()
    sim = create_simulator(name)
    assert sim.name == name
    items = items_from_names(NAMES, Catalog.load())
    runs = [execute(create_simulator(name), plan, scene, items, seeds.stream(s, "simulator"),
                    replan=nav) for s in (4, 4, 5)]
    assert runs[0] == runs[1]
    for ex in runs:
        check_execution(ex, plan, scene)


@pytest.mark.parametrize("name", available_simulators())
def test_simulator_name_reaches_the_run_json(name: str) -> None:
    result = run("a dinner plate and a dinner fork", method="grop", seed=2, chairs=0,
                 simulator=name)
    data = run_to_dict(result)
    assert data["simulator"] == name == result.simulator
    jsonschema.Draft202012Validator(json_schema("run")).validate(data)
    check_execution(result.execution, result.plan, result.scene)
