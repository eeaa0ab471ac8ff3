"""GROP's plans: a 2-object scene solved by hand, supports first, and exact optimality."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from llm_grop.errors import Infeasible
from llm_grop.planning.grop import build_plan, choose, evaluate
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import GropOptions, PlanningContext
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Box
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import Chair
from scenes import config, placement, two_table_room


@pytest.fixture(scope="module")
def catalog() -> Catalog:
    return Catalog.load()


def _ctx(catalog: Catalog, names: list[str], **kw: object) -> PlanningContext:
    scene = kw.pop("scene", None) or two_table_room()
    return PlanningContext(scene, items_from_names(names, catalog), **kw)  # type: ignore[arg-type]


def test_two_objects_known_by_hand(catalog: Catalog) -> None:
    # Both objects sit at the table's west end, next to the counter they come from: the
    # best place to stand is the west side, facing east (+x), for both, plate first.
    ctx = _ctx(catalog, ["dinner plate", "bread"])
    cfg = config(placement("dinner plate", -0.28, 0.0),
                 placement("bread", -0.28, 0.0, "box", (0.1, 0.08), on="dinner plate"))
    cand = evaluate(ctx, cfg, 0)
    assert not isinstance(cand, str)
    assert [cfg.placements[j].name for j in cand.order] == ["dinner plate", "bread"]
    for j in range(2):
        pose = ctx.candidates[cand.stand[j]].pose
        assert pose.x < 3.0 - 0.45, pose
        assert abs(pose.y - 2.0) < 0.2
        assert abs(math.remainder(pose.theta, 2 * math.pi)) < 0.3
    robot = ctx.scene.robot
    # Expected duration: start -> counter -> west side -> counter -> west side, plus
    # 2 picks and 2 places; every leg is at least its straight-line length.
    assert cand.cost_s > 2 * (robot.pick_time_s + robot.place_time_s)
    assert 0 < cand.feasibility <= 1


def test_supports_come_first_whatever_the_cost(catalog: Catalog) -> None:
    ctx = _ctx(catalog, ["bread", "dinner plate", "mug"])
    cfg = config(placement("bread", 0.3, 0.1, "box", (0.1, 0.08), on="dinner plate"),
                 placement("dinner plate", 0.3, 0.1),
                 placement("mug", -0.3, 0.1, size=(0.08, 0.08)))
    cand = evaluate(ctx, cfg, 0)
    assert not isinstance(cand, str)
    names = [cfg.placements[j].name for j in cand.order]
    assert names.index("dinner plate") < names.index("bread")


def _brute_force_utility(ctx: PlanningContext, cfg, w: float) -> float:  # type: ignore[no-untyped-def]
    placements = [cfg.by_name()[i.name] for i in ctx.items]
    feas = ctx.place_feasibility(placements)
    v = ctx.speed
    field = [p.field for p in ctx.pickups]
    best = -np.inf
    n, P = feas.shape
    for order in itertools.permutations(range(n)):
        if any(placements[j].on is not None and
               [placements[k].name for k in order].index(placements[j].on) >
               list(order).index(j) for j in order):
            continue
        for stands in itertools.product(range(P), repeat=n):
            if any(feas[j, stands[j]] <= 0 for j in range(n)):
                continue
            u = -ctx.start_dist_m[field[order[0]]] / v
            for pos, j in enumerate(order):
                s = stands[j]
                u += w * feas[j, s] - ctx.dist_m[s, field[j]] / v
                if pos + 1 < n:
                    u -= ctx.dist_m[s, field[order[pos + 1]]] / v
            best = max(best, u)
    return best - ctx.fixed_costs_s()


def test_utility_is_the_exact_optimum(catalog: Catalog) -> None:
    # Few candidates keep brute force small: every order x every standing position.
    opts = GropOptions(spacing_m=0.6, standoffs_m=(0.05, 0.2))
    ctx = _ctx(catalog, ["dinner plate", "dinner fork", "mug"], options=opts)
    cfg = config(placement("dinner plate", 0.0, -0.05),
                 placement("dinner fork", -0.2, -0.05, "box", (0.025, 0.2)),
                 placement("mug", 0.3, 0.2, size=(0.08, 0.08)))
    cand = evaluate(ctx, cfg, 0)
    assert not isinstance(cand, str)
    assert cand.utility == pytest.approx(_brute_force_utility(ctx, cfg, opts.w), abs=1e-6)


def test_best_configuration_is_chosen(catalog: Catalog) -> None:
    ctx = _ctx(catalog, ["dinner plate"])
    near = config(placement("dinner plate", -0.28, 0.0))
    far = config(placement("dinner plate", 0.28, 0.0))
    best = choose(ctx, [far, near])
    assert best.index == 1


def test_plan_steps_and_paths(catalog: Catalog) -> None:
    ctx = _ctx(catalog, ["dinner plate", "dinner fork"])
    cfg = config(placement("dinner plate", 0.0, 0.0),
                 placement("dinner fork", -0.2, 0.0, "box", (0.025, 0.2)))
    cand = choose(ctx, [cfg])
    nav = Navigator(ctx.scene, ctx.scene.robot.base_radius_m)
    plan = build_plan(ctx, cand, nav, seed=0, configurations=1)
    assert [s.action for s in plan.steps] == ["navigate", "pick", "navigate", "place"] * 2
    for s in plan.steps:
        if s.action == "navigate":
            assert s.path[-1] == pytest.approx((s.goal.x, s.goal.y))
            assert s.duration_s > 0
    assert plan.order[0] in {"dinner plate", "dinner fork"}


def test_chairs_on_every_side_are_infeasible(catalog: Catalog) -> None:
    chairs = tuple(Chair(f"chair {k}", Box(x, y, w, d)) for k, (x, y, w, d) in enumerate([
        (3.0, 2.55, 1.6, 0.4), (3.0, 1.45, 1.6, 0.4), (2.3, 2.0, 0.4, 0.8),
        (3.7, 2.0, 0.4, 0.8)]))
    with pytest.raises(Infeasible, match="dining table"):
        _ctx(catalog, ["dinner plate"], scene=two_table_room(chairs=chairs))


def test_unreachable_object_is_reported(catalog: Catalog) -> None:
    from dataclasses import replace

    from llm_grop.world.scene import SceneTable

    room = two_table_room()
    big = replace(room, tables=(SceneTable("dining table", Box(3.0, 2.0, 2.4, 2.0)),
                                room.tables[1]))
    ctx = _ctx(catalog, ["dinner plate"], scene=big)
    with pytest.raises(Infeasible, match="no standing position can reach 'dinner plate'"):
        choose(ctx, [config(placement("dinner plate", 0.0, 0.0))])


@pytest.mark.parametrize("capacity", [2, 3])
def test_more_capacity_never_plans_a_slower_run(catalog: Catalog, capacity: int) -> None:
    from dataclasses import replace

    from llm_grop.world.robot import Robot

    names = ["dinner plate", "dinner fork", "dinner knife", "mug"]
    cfg = config(placement("dinner plate", 0.0, 0.0),
                 placement("dinner fork", -0.2, 0.0, "box", (0.025, 0.2)),
                 placement("dinner knife", 0.2, 0.0, "box", (0.02, 0.23)),
                 placement("mug", 0.3, 0.15, size=(0.09, 0.09)))
    durations = []
    for cap in (1, capacity):
        scene = replace(two_table_room(), robot=Robot(capacity=cap))
        ctx = _ctx(catalog, names, scene=scene)
        cand = choose(ctx, [cfg])
        plan = build_plan(ctx, cand, Navigator(scene, 0.3), seed=0, configurations=1)
        durations.append(sum(s.duration_s for s in plan.steps))
        carried = 0
        for s in plan.steps:
            carried += {"pick": 1, "place": -1}.get(s.action, 0)
            assert 0 <= carried <= cap
    assert durations[1] <= durations[0] + 1e-9


def test_pickup_stances_the_robot_cannot_reach_are_not_used() -> None:
    from dataclasses import replace

    from llm_grop.api import run
    from llm_grop.files.scene_file import load_scene

    # Turned this way, the side table leaves a pocket between it and the corner walls
    # where the arm would reach best but the base cannot drive.
    scene = load_scene(None)
    tables = tuple(replace(t, box=replace(t.box, x=7.0, y=1.0, yaw=0.7))
                   if t.name == "side table" else t for t in scene.tables)
    result = run(task=1, method="grop", scene=replace(scene, tables=tables), seed=0)
    assert result.plan.order
    for step in result.plan.steps:
        if step.action == "pick":
            assert step.standing is not None


def test_trips_are_the_best_over_every_order_and_cut(catalog: Catalog) -> None:
    import itertools
    from dataclasses import replace

    from llm_grop.planning.trips import cut_order, plan_trips, trip_costs
    from llm_grop.world.robot import Robot

    names = ["dinner plate", "dinner fork", "dinner knife", "mug", "bread"]
    cfg = config(placement("dinner plate", 0.0, 0.0),
                 placement("dinner fork", -0.2, 0.0, "box", (0.025, 0.2)),
                 placement("dinner knife", 0.2, 0.0, "box", (0.02, 0.23)),
                 placement("mug", 0.3, 0.15, size=(0.09, 0.09)),
                 placement("bread", -0.3, 0.15, size=(0.08, 0.08)))
    # Quick loads and unloads, so that trips of two pay off.
    scene = replace(two_table_room(), robot=Robot(capacity=2, pick_time_s=0.5,
                                                  place_time_s=0.5))
    ctx = _ctx(catalog, names, scene=scene)
    cand = choose(ctx, [cfg])
    before = [(0, 3)]  # as if the mug rested on the plate
    costs = trip_costs(ctx, cand.stand, 2)
    trips, saved = plan_trips(ctx, cand.order, cand.stand, 2, before, costs)
    order = [j for t in trips for j in t]
    assert sorted(order) == list(range(5)) and order.index(0) < order.index(3)
    assert all(1 <= len(t) <= 2 for t in trips) and saved > 0
    assert all(costs.fits(t) for t in trips)
    ours = cut_order(ctx, order, cand.stand, costs)[1]
    best = min(cut_order(ctx, p, cand.stand, costs)[1]
               for p in itertools.permutations(range(5)) if p.index(0) < p.index(3))
    assert ours == pytest.approx(best)


def test_trips_fit_the_tray_and_pay_for_their_loads(catalog: Catalog) -> None:
    from dataclasses import replace

    from llm_grop.planning.trips import cut_order, handling_s, plan_trips, trip_costs
    from llm_grop.world.robot import Robot
    from llm_grop.world.tray import load_tray

    names = ["dinner plate", "dinner plate 2", "dinner fork", "dinner knife"]
    items = items_from_names(["dinner plate", "dinner plate", "dinner fork",
                              "dinner knife"], catalog)
    assert [i.name for i in items] == names
    cfg = config(placement("dinner plate", -0.3, 0.0),
                 placement("dinner plate 2", 0.3, 0.0),
                 placement("dinner fork", -0.5, 0.0, "box", (0.025, 0.2)),
                 placement("dinner knife", 0.5, 0.0, "box", (0.02, 0.23)))

    def planned(pick_s: float) -> tuple[PlanningContext, object, tuple[tuple[int, ...], ...],
                                        float]:
        robot = Robot(capacity=4, pick_time_s=pick_s, place_time_s=pick_s)
        ctx = PlanningContext(replace(two_table_room(), robot=robot), items)
        cand = choose(ctx, [cfg])
        trips, saved = plan_trips(ctx, cand.order, cand.stand, 4)
        return ctx, cand, trips, saved

    # Loads and unloads nearly free: the two plates never share the tray (one large slot).
    ctx, cand, trips, saved = planned(0.1)
    tray = load_tray()
    assert saved > 0 and any(len(t) > 1 for t in trips)
    for t in trips:
        assert len(t) == 1 or tray.assign([(items[j].spec.shape, items[j].spec.size)
                                           for j in t]) is not None
        assert not {0, 1} <= set(t)
    # A trip of several costs one load and one unload per object at the belief's times.
    assert handling_s(ctx) == pytest.approx(0.2)
    costs = trip_costs(ctx, cand.stand, 4)
    apart = cut_order(ctx, [2, 3], cand.stand, replace(costs, capacity=1))
    priced = cut_order(ctx, [2, 3], cand.stand, replace(costs, capacity=2, handling_s=1e3))
    assert priced[0] == ((2,), (3,)) and priced[1] == pytest.approx(apart[1])
    # Loads and unloads as slow as the robot's own picks and places (8 s each) cost more
    # than the drive trips save here: one object per trip, as with capacity 1.
    _, cand8, trips8, saved8 = planned(8.0)
    assert saved8 == 0 and all(len(t) == 1 for t in trips8)
