"""The 2D kinematic simulator: outcomes follow its own true success model, seeded."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from llm_grop.execution import ExecutionPolicy, execute
from llm_grop.geometry.obstacles import Obstacles
from llm_grop.planning.grop import build_plan, choose
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.kinematic2d import Kinematic2D, Kinematic2DOptions
from llm_grop.simulation.registry import available_simulators, create_simulator
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.plan import Execution, Plan
from llm_grop.world.request import items_from_names
from llm_grop.world.robot import Robot
from llm_grop.world.scene import Chair, ObjectSource, Scene
from scenes import Constant, config, placement, two_table_room

NAMES = ["dinner plate", "bread", "dinner fork"]
ITEMS = items_from_names(NAMES, Catalog.load())




def sim(nav: float | None = None, manip: float | None = None, **options: Any) -> Kinematic2D:
    """The simulator, with a constant truth when ``nav`` and ``manip`` are given."""
    truth = {} if nav is None else {"outcomes": Constant(nav, manip or 0.0)}
    return Kinematic2D(Kinematic2DOptions(**truth, **options))


def run(simulator: Kinematic2D, plan: Plan, scene: Scene, seed: int, nav: Navigator,
        **policy: Any) -> Execution:
    """``plan`` executed by the executive on ``simulator``."""
    return execute(simulator, plan, scene, ITEMS, np.random.default_rng(seed), replan=nav,
                   policy=ExecutionPolicy(**policy))


def _setup(chairs: tuple[Chair, ...] = ()):  # type: ignore[no-untyped-def]
    scene = two_table_room(chairs=chairs)
    ctx = PlanningContext(scene, ITEMS)
    cfg = config(placement("dinner plate", 0.0, -0.05),
                 placement("bread", 0.0, -0.05, "box", (0.1, 0.08), on="dinner plate"),
                 placement("dinner fork", -0.22, -0.05, "box", (0.025, 0.2)))
    nav = Navigator(scene, scene.robot.base_radius_m)
    plan = build_plan(ctx, choose(ctx, [cfg]), nav, seed=0, configurations=1)
    return scene, plan, nav


def test_registry_has_kinematic2d() -> None:
    assert "kinematic2d" in available_simulators()
    assert create_simulator("kinematic2d").name == "kinematic2d"


def test_same_seed_same_execution() -> None:
    scene, plan, nav = _setup()
    runs = [run(sim(), plan, scene, 7, nav) for _ in range(2)]
    assert runs[0] == runs[1]


def test_certain_success_places_everything_near_its_target() -> None:
    scene, plan, nav = _setup()
    ex = run(sim(1.0, 1.0), plan, scene, 0, nav)
    assert ex.success and ex.failures == 0
    targets = {p.name: p for p in plan.configuration}
    for p in ex.final:
        assert abs(p.x - targets[p.name].x) < 0.03 and abs(p.y - targets[p.name].y) < 0.03
    assert {p.name: p.on for p in ex.final}["bread"] == "dinner plate"
    expected = sum(s.duration_s for s in plan.steps)
    assert ex.execution_time_s == pytest.approx(expected, rel=0.15)


def test_impossible_manipulation_is_retried_then_abandoned() -> None:
    scene, plan, nav = _setup()
    ex = run(sim(1.0, 0.0), plan, scene, 0, nav, manip_attempts=4)
    assert not ex.success and ex.final == ()
    assert set(ex.unplaced) == set(NAMES)
    assert dict(ex.unplaced_reasons) == dict.fromkeys(NAMES, "grasp_missed")
    picks = [s for s in ex.steps if s.action == "pick"]
    assert len(picks) == 4 * len(NAMES) and not any(s.ok for s in picks)
    assert {s.reason for s in picks} == {"grasp_missed"}


def test_failed_navigation_retries_then_falls_back() -> None:
    scene, plan, nav = _setup()
    ex = run(sim(0.0, 1.0), plan, scene, 0, nav)
    navs = [s for s in ex.steps if s.action == "navigate"]
    assert navs and not any(s.ok for s in navs)
    # 3 attempts at the first pickup goal, then the object is given up.
    assert [s.attempt for s in navs[:3]] == [1, 2, 3]
    assert {s.reason for s in navs} == {"contact"}
    assert not ex.success


def test_support_that_never_arrives_leaves_its_load_on_the_table() -> None:
    scene, plan, nav = _setup()
    # The plate really lies in the counter's far corner, out of the arm's reach from where
    # the plan has the robot stand to pick it.
    real = scene.with_sources(tuple(ObjectSource("dinner plate", "counter", 0.17, 1.42)
                                    if s.object == "dinner plate" else s
                                    for s in scene.sources))
    ex = run(sim(1.0, 1.0), plan, real, 0, nav)
    assert "dinner plate" in ex.unplaced and dict(ex.unplaced_reasons)["dinner plate"] == "no_ik"
    picks = [s for s in ex.steps if s.action == "pick" and s.object == "dinner plate"]
    assert len(picks) == 10 and {s.reason for s in picks} == {"no_ik"}
    assert all(s.duration_s == scene.robot.ik_failure_s for s in picks)
    # Its load goes on the table where the plate should be, but not on its support.
    assert {p.name: p.on for p in ex.final}.get("bread", "missing") is None
    assert dict(ex.unplaced_reasons)["bread"] == "wrong_support"


def test_robot_never_stands_inside_a_chair() -> None:
    chair = Chair("chair 1", Box(3.0, 1.25, 0.45, 0.45, 0.3))
    scene, plan, nav = _setup((chair,))
    obstacles = Obstacles(scene, include_chairs=True)
    r = scene.robot.base_radius_m
    for seed in range(10):
        ex = run(sim(), plan, scene, seed, nav)
        for s in ex.steps:
            if s.standing is not None:
                c = obstacles.clearance(np.array([[s.standing.x, s.standing.y]]))[0]
                assert c >= r - 1e-6, (seed, s)
            for x, y in s.path:
                assert not chair.box.contains(x, y, margin=r - 0.01), (seed, s)


def test_default_truth_matches_the_planners_default_belief() -> None:
    """As the README says: by default the world is as the planner believes it to be."""
    from llm_grop.planning.feasibility import DEFAULT_FEASIBILITY
    from llm_grop.simulation.outcomes import ParametricOutcomes

    truth, robot = ParametricOutcomes(), Robot()
    for c in np.linspace(-0.05, 0.3, 36):
        belief = float(DEFAULT_FEASIBILITY.navigation(np.array([c]))[0])
        assert truth.navigation(float(c)) == pytest.approx(belief, abs=1e-12)
    for r in np.linspace(0.0, 1.0, 101):
        belief = float(DEFAULT_FEASIBILITY.manipulation(np.array([r]), robot)[0])
        assert truth.manipulation(float(r), robot) == pytest.approx(belief, abs=1e-12)


def test_arrivals_record_their_error() -> None:
    scene, plan, nav = _setup()
    ex = run(sim(1.0, 1.0), plan, scene, 0, nav)
    drives = [s for s in ex.steps if s.action == "navigate"]
    assert drives and all(s.arrival_error_m is not None for s in drives)
    errors = [s.arrival_error_m for s in drives if s.arrival_error_m is not None]
    # The 2D arrival noise: 2 cm per axis.
    assert 0.0 < max(errors) < 0.15


def test_a_truth_other_than_kinematic2d_s_own_needs_kinematic2d(capsys) -> None:  # type: ignore[no-untyped-def]
    from cli_support import one_line_error
    from llm_grop.cli import main

    assert main(["run", "a mug", "--simulator", "mujoco", "--truth", "mujoco", "-q"]) == 2
    assert "--truth mujoco: needs the kinematic2d simulator" in one_line_error(capsys)
    assert main(["run", "a mug", "--truth", "nope", "-q"]) == 2
    assert "--truth: unknown profile 'nope'" in one_line_error(capsys)


def test_a_pile_starts_stacked_and_closes_up_when_one_is_picked() -> None:
    plates = items_from_names(["dinner plate"] * 3, Catalog.load())
    scene = two_table_room(sources=(
        ObjectSource("dinner plate", "counter", 0.45, 2.1),
        ObjectSource("dinner plate 2", "counter", 0.45, 2.1, "dinner plate"),
        ObjectSource("dinner plate 3", "counter", 0.45, 2.1, "dinner plate 2")))
    nav = Navigator(scene, scene.robot.base_radius_m)
    session = sim(1.0, 1.0).session(scene, plates, np.random.default_rng(0), replan=nav)
    top = scene.table("counter").height
    start = session.objects()
    assert [(start[p.name].z, start[p.name].on) for p in plates] == [
        (top, None), (pytest.approx(top + 0.025), "dinner plate"),
        (pytest.approx(top + 0.05), "dinner plate 2")]
    stand = Pose2D(1.0, 2.1, np.pi)
    assert session.navigate(stand).ok
    # Plates of a pile are alike: taking the middle one stands for taking the top one,
    # and the pile closes up.
    assert session.pick("dinner plate 2").ok
    after = session.objects()
    assert after["dinner plate 2"].held
    assert (after["dinner plate 3"].z, after["dinner plate 3"].on) == (
        pytest.approx(top + 0.025), "dinner plate")
    assert (after["dinner plate"].z, after["dinner plate"].on) == (top, None)
