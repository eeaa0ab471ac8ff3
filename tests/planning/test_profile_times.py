"""A profile's times reach the plan (step durations, expected retries) and the 2D truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from llm_grop.files.profiles import load_profile
from llm_grop.planning.feasibility import ParametricFeasibility, feasibility_profile
from llm_grop.planning.grop import build_plan, choose, expected_duration_s
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.kinematic2d import Kinematic2D, Kinematic2DOptions
from llm_grop.simulation.outcomes import ParametricOutcomes
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.request import items_from_names
from scenes import config, placement, two_table_room

TIMED = ParametricFeasibility(pick_time_s=5.0, place_time_s=6.0, leg_overhead_s=2.0,
                              failed_attempt_s=3.0)


def test_a_profile_s_times_make_the_plan_s_durations() -> None:
    scene = two_table_room()
    ctx = PlanningContext(scene, items_from_names(["dinner plate"], Catalog.load()), TIMED)
    cand = choose(ctx, [config(placement("dinner plate", 0.0, 0.0))])
    plan = build_plan(ctx, cand, Navigator(scene, 0.3), seed=0, configurations=1)
    plain = build_plan(PlanningContext(scene, ctx.items), cand, Navigator(scene, 0.3), seed=0,
                       configurations=1)
    by_action = {s.action: s for s in plan.steps}
    assert by_action["pick"].duration_s == 5.0 and by_action["place"].duration_s == 6.0
    for timed, own in zip(plan.steps, plain.steps, strict=True):
        if timed.action == "navigate":
            assert timed.duration_s == pytest.approx(own.duration_s + 2.0)
    retries = sum(1 / s.success_p - 1 for s in plan.steps)
    assert plan.expected_duration_s == pytest.approx(
        sum(s.duration_s for s in plan.steps) + 3.0 * retries)
    assert expected_duration_s(plan.steps, 0.0) == pytest.approx(
        sum(s.duration_s for s in plan.steps))


def test_the_fitted_profile_is_one_file_for_belief_and_truth() -> None:
    p = load_profile("mujoco").curves
    belief, truth = feasibility_profile("mujoco"), ParametricOutcomes.from_profile("mujoco")
    assert p.pick_time_s is not None and p.place_time_s is not None
    assert (belief.nav_max, belief.reach_max_m, belief.pick_time_s) == \
        (truth.nav_max, truth.reach_max_m, truth.pick_time_s) == \
        (p.nav_max, p.reach_max_m, p.pick_time_s)
    robot = two_table_room().robot
    for r in (0.3, 0.6, 0.9, 1.1):
        assert truth.manipulation(r, robot) == pytest.approx(
            float(belief.manipulation(np.array([r]), robot)[0]))
        assert truth.placing(r, robot) == pytest.approx(
            float(belief.placing(np.array([r]), robot)[0]))


def test_2d_draws_its_durations_and_reach_from_its_truth() -> None:
    p = load_profile("mujoco").curves
    assert p.reach_max_m is not None
    scene = two_table_room()
    sim = Kinematic2D(Kinematic2DOptions(outcomes=ParametricOutcomes.from_profile("mujoco")))
    items = items_from_names(["dinner plate"], Catalog.load())
    source = scene.source_for("dinner plate", "dinner plate")
    assert source is not None
    # Stand beyond the robot's own 0.85 m reach but within the profile's.
    reach = (scene.robot.reach_max_m + p.reach_max_m) / 2
    stand = Pose2D(source.x + reach, source.y, math.pi)
    picks = []
    for seed in range(20):
        s = sim.session(scene, items, np.random.default_rng(seed), replan=Navigator(scene, 0.3))
        s.pose = stand
        picks.append(s.pick("dinner plate"))
    assert all(step.reason != "no_ik" for step in picks)
    assert {step.duration_s for step in picks if step.ok} == {p.pick_time_s}


def test_a_profile_s_load_and_unload_times_price_trips_and_the_2d_truth() -> None:
    from dataclasses import replace

    from llm_grop.planning.trips import handling_s
    from llm_grop.world.robot import Robot

    scene = replace(two_table_room(), robot=Robot(capacity=4))
    items = items_from_names(["dinner plate", "dinner fork"], Catalog.load())
    quiet = ParametricFeasibility(pick_time_s=5.0, place_time_s=6.0, manip_max=1.0 - 1e-12)
    loads = replace(quiet, load_time_s=9.0, unload_time_s=8.0)
    # Unstated: a load is a place and an unload a pick, as before.
    assert quiet.action_times(scene.robot).load_s == 6.0
    assert quiet.action_times(scene.robot).unload_s == 5.0
    plain = handling_s(PlanningContext(scene, items, quiet))
    priced = handling_s(PlanningContext(scene, items, loads))
    assert plain == pytest.approx(11.0) and priced == pytest.approx(17.0)
    # The 2D truth charges the profile's load and unload.
    truth = ParametricOutcomes(pick_time_s=5.0, place_time_s=6.0, load_time_s=9.0,
                               unload_time_s=8.0)
    s = Kinematic2D(Kinematic2DOptions(outcomes=truth)).session(
        scene, items, np.random.default_rng(0), replan=None)  # type: ignore[arg-type]
    s.pose = Pose2D(1.0, 2.0, math.pi)  # facing the counter, in reach of both
    pick = s.pick("dinner plate")
    assert pick.ok and pick.duration_s == 5.0
    load = s.load("dinner plate")
    assert load.tray and load.duration_s == 9.0
    if load.ok and s.objects()["dinner plate"].tray:
        assert s.unload("dinner plate").duration_s == 8.0
    # The fitted MuJoCo profile states them; the default one does not.
    assert load_profile("mujoco").curves.load_time_s == 9.32
    assert load_profile("mujoco").curves.unload_time_s == 8.96
    assert load_profile("default").curves.load_time_s is None
