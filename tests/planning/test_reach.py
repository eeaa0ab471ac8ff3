"""Several diners' configurations brought within sure reach (planning/reach.py)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from llm_grop.arrangement.fidelity import GAP_TOLERANCE_M
from llm_grop.errors import Infeasible
from llm_grop.planning import reach
from llm_grop.planning.grop import choose, evaluate
from llm_grop.planning.utility import PlanningContext
from llm_grop.world.arrangement import Configuration, Item, Placement
from llm_grop.world.catalog import Catalog
from llm_grop.world.fidelity import Fidelity
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.scene import ObjectSource, Scene, SceneTable
from llm_grop.world.seat import Seat

CATALOG = Catalog.load(use_env=False)
#: Two diners across a 1.0 m deep table: diner 0 at -y, diner 1 at +y.
SEATS = (Seat(0.0, -0.5, math.pi / 2), Seat(0.0, 0.5, -math.pi / 2))
NAMES = (("dinner plate", 0), ("water cup", 0), ("dinner plate 2", 1), ("water cup 2", 1))


def _scene() -> Scene:
    """A 6 x 4 m room: a 1.6 x 1.0 m dining table at (3, 2) with two diners, a counter
    at the west wall where the objects start."""
    return Scene(
        name="reach room", width=6.0, depth=4.0,
        tables=(SceneTable("dining table", Box(3.0, 2.0, 1.6, 1.0)),
                SceneTable("counter", Box(0.4, 2.0, 0.5, 1.2))),
        target="dining table", robot_start=Pose2D(1.5, 0.6, 0.0),
        sources=(ObjectSource("dinner plate", "counter", 0.45, 2.1),
                 ObjectSource("water cup", "counter", 0.45, 1.8)),
        diners=SEATS)


def _items() -> list[Item]:
    return [Item(n, CATALOG.resolve(n.rstrip(" 2"), "objects"), d) for n, d in NAMES]


def _ctx() -> PlanningContext:
    return PlanningContext(_scene(), _items())


def _p(name: str, x: float, y: float, diner: int | None) -> Placement:
    size = (0.27, 0.27) if "plate" in name else (0.08, 0.08)
    return Placement(name, x, y, 0.0, "circle", size, None, name.rstrip(" 2"), 0.02, diner)


def _config(cup_depth_m: float, plate_edge_m: float = 0.03, x: float = 0.0) -> Configuration:
    """Each diner's plate ``plate_edge_m`` from their edge and their cup ``cup_depth_m``
    (centre) from it, mirrored across the table."""
    plate = -0.5 + plate_edge_m + 0.135
    cup = -0.5 + cup_depth_m
    return Configuration((_p("dinner plate", x, plate, 0), _p("water cup", x + 0.2, cup, 0),
                          _p("dinner plate 2", -x, -plate, 1),
                          _p("water cup 2", -x - 0.2, -cup, 1)))


def _stated(config: Configuration, edge_m: float = 0.03) -> Fidelity:
    return Fidelity(origin="dinner plate, dinner plate 2", edge_stated_m=0.03,
                    edge_realised_m=edge_m)


def test_sure_reach_is_just_past_the_knee_of_the_default_belief() -> None:
    ctx = _ctx()
    r = np.linspace(0.3, 0.85, 1101)
    p = reach.placing(ctx.model, r, ctx.scene.robot)
    assert 0.6 < r[p >= reach.sure_p(ctx)].max() < 0.62


def test_one_diner_is_never_repaired() -> None:
    ctx = _ctx()
    far = Configuration(tuple(replace(p, diner=None) for p in _config(0.45).placements))
    assert reach.repair(ctx, far, Fidelity(), (far,)) is None
    assert reach.repair(ctx, far, None, (far,)) is None


def test_a_setting_within_sure_reach_is_left_as_it_is() -> None:
    near = _config(0.2)
    ctx = _ctx()
    assert reach.best_place_p(ctx, near.placements).min() >= reach.sure_p(ctx)
    assert reach.repair(ctx, near, _stated(near), (near,)) is None


def test_a_stated_setting_moves_whole_and_keeps_its_edge_within_tolerance() -> None:
    ctx = _ctx()
    # The cups lie deep; each plate is 4 cm from its diner's edge, 1 cm more than said.
    deep = _config(0.40, plate_edge_m=0.04)
    fixed = reach.repair(ctx, deep, _stated(deep, 0.04), (deep,))
    assert fixed is not None
    before, after = deep.by_name(), fixed.configuration.by_name()
    for plate, cup in (("dinner plate", "water cup"), ("dinner plate 2", "water cup 2")):
        # A rigid move: the cup keeps its offset from the plate.
        assert after[cup].x - after[plate].x == pytest.approx(before[cup].x - before[plate].x)
        assert after[cup].y - after[plate].y == pytest.approx(before[cup].y - before[plate].y)
    # Towards diner 0 is -y; at most to 1.5 cm short of the stated 3 cm.
    assert after["water cup"].y < before["water cup"].y
    edge = after["dinner plate"].y - 0.135 + 0.5
    assert edge >= 0.03 - GAP_TOLERANCE_M - 1e-9
    assert fixed.fidelity.origin_shift_m == pytest.approx(sum(fixed.shifted_m.values()))
    p_before = reach.best_place_p(ctx, deep.placements).min()
    assert reach.best_place_p(ctx, fixed.configuration.placements).min() > p_before


def test_random_configurations_take_each_object_from_a_draw() -> None:
    ctx = _ctx()
    deep, near = _config(0.42), _config(0.2, x=0.3)
    fixed = reach.repair(ctx, deep, None, (deep, near))
    assert fixed is not None
    drawn = {(p.name, p.x, p.y) for c in (deep, near) for p in c.placements}
    assert all((p.name, p.x, p.y) in drawn for p in fixed.configuration.placements)
    assert reach.best_place_p(ctx, fixed.configuration.placements).min() >= reach.sure_p(ctx)
    assert fixed.fidelity == Fidelity()


def test_a_given_configuration_is_never_moved() -> None:
    ctx = _ctx()
    deep = _config(0.42)
    assert reach.repair(ctx, deep, None, (deep,)) is None


@pytest.mark.parametrize("plate_edge_m", [0.03, 0.015])
def test_grop_plans_when_only_a_moved_configuration_is_reachable(plate_edge_m: float) -> None:
    ctx = _ctx()
    # Both cups in the table's middle, beyond the arm's reach from every standing
    # position as sampled (the base's centre is at least 0.35 m from the edge). With the
    # plate 3 cm from the edge (as said) the setting may come 1.5 cm nearer its diner;
    # with 1.5 cm, no nearer within tolerance, so only the last resort plans.
    deep = _config(0.50, plate_edge_m=plate_edge_m)
    assert reach.best_place_p(ctx, deep.placements).min() == 0.0
    assert isinstance(evaluate(ctx, deep, 0), str)
    cand = choose(ctx, [deep], fidelity=[_stated(deep, plate_edge_m)])
    assert min(cand.place_p) > 0
    moved = {p.name: p for p in cand.placements}
    was = deep.by_name()
    if plate_edge_m == 0.03:
        # Towards each diner, within the tolerance of the stated edge distance.
        assert moved["water cup"].y < was["water cup"].y
        assert moved["water cup 2"].y > was["water cup 2"].y
    else:
        # The last resort: no room towards the diner, so away, within reach of the far
        # side's standing positions.
        assert moved["water cup"].y != was["water cup"].y
    assert cand.fidelity.origin_shift_m > 0
    assert cand.fidelity.edge_realised_m == pytest.approx(
        moved["dinner plate"].y - 0.135 + 0.5)


def test_grop_still_refuses_what_no_move_brings_within_reach() -> None:
    ctx = _ctx()
    deep = _config(0.50)
    # With nothing stated, a lone configuration is planned as it is.
    with pytest.raises(Infeasible):
        choose(ctx, [deep])
