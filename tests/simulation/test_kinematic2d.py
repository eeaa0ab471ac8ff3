"""The 2D kinematic simulator: outcomes follow its own true success model, seeded."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from llm_grop.geometry.obstacles import Obstacles
from llm_grop.planning.grop import build_plan, choose
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.kinematic2d import Kinematic2D, Kinematic2DOptions
from llm_grop.simulation.registry import available_simulators, create_simulator
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Box
from llm_grop.world.request import items_from_names
from llm_grop.world.robot import Robot
from llm_grop.world.scene import Chair
from scenes import config, placement, two_table_room

NAMES = ["dinner plate", "bread", "dinner fork"]


@dataclass(frozen=True)
class Constant:
    """A true success model with fixed probabilities (within reach)."""

    nav: float
    manip: float

    def navigation(self, clearance_m: float) -> float:
        return self.nav if clearance_m >= 0 else 0.0

    def manipulation(self, reach_m: float, robot: Robot) -> float:
        return self.manip if robot.reach_min_m <= reach_m <= robot.reach_max_m else 0.0


def sim(nav: float | None = None, manip: float | None = None, **options: int) -> Kinematic2D:
    """The simulator, with a constant truth when ``nav`` and ``manip`` are given."""
    truth = {} if nav is None else {"outcomes": Constant(nav, manip or 0.0)}
    return Kinematic2D(Kinematic2DOptions(**truth, **options))


def _setup(chairs: tuple[Chair, ...] = ()):  # type: ignore[no-untyped-def]
    scene = two_table_room(chairs=chairs)
    items = items_from_names(NAMES, Catalog.load())
    ctx = PlanningContext(scene, items)
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
    runs = [sim().execute(plan, scene, np.random.default_rng(7), replan=nav) for _ in range(2)]
    assert runs[0] == runs[1]


def test_certain_success_places_everything_near_its_target() -> None:
    scene, plan, nav = _setup()
    ex = sim(1.0, 1.0).execute(plan, scene, np.random.default_rng(0), replan=nav)
    assert ex.success and ex.failures == 0
    targets = {p.name: p for p in plan.configuration}
    for p in ex.final:
        assert abs(p.x - targets[p.name].x) < 0.03 and abs(p.y - targets[p.name].y) < 0.03
    assert {p.name: p.on for p in ex.final}["bread"] == "dinner plate"
    expected = sum(s.duration_s for s in plan.steps)
    assert ex.execution_time_s == pytest.approx(expected, rel=0.15)


def test_impossible_manipulation_is_retried_then_abandoned() -> None:
    scene, plan, nav = _setup()
    ex = sim(1.0, 0.0, manip_attempts=4).execute(plan, scene, np.random.default_rng(0),
                                                 replan=nav)
    assert not ex.success and ex.final == ()
    assert set(ex.unplaced) == set(NAMES)
    picks = [s for s in ex.steps if s.action == "pick"]
    assert len(picks) == 4 * len(NAMES) and not any(s.ok for s in picks)


def test_failed_navigation_retries_then_falls_back() -> None:
    scene, plan, nav = _setup()
    ex = sim(0.0, 1.0).execute(plan, scene, np.random.default_rng(0), replan=nav)
    navs = [s for s in ex.steps if s.action == "navigate"]
    assert navs and not any(s.ok for s in navs)
    # 3 attempts at the first pickup goal, then the object is given up.
    assert [s.attempt for s in navs[:3]] == [1, 2, 3]
    assert not ex.success


def test_support_that_never_arrives_leaves_its_load_on_the_table() -> None:
    scene, plan, nav = _setup()
    # The plate cannot be picked: its start is moved far out of reach.
    steps = tuple(s if not (s.action == "pick" and s.object == "dinner plate")
                  else type(s)(**{**s.__dict__, "pose": (5.9, 3.9, 0.0)}) for s in plan.steps)
    plan = type(plan)(**{**plan.__dict__, "steps": steps})
    ex = sim(1.0, 1.0).execute(plan, scene, np.random.default_rng(0), replan=nav)
    assert "dinner plate" in ex.unplaced
    assert {p.name: p.on for p in ex.final}.get("bread", "missing") is None


def test_robot_never_stands_inside_a_chair() -> None:
    chair = Chair("chair 1", Box(3.0, 1.25, 0.45, 0.45, 0.3))
    scene, plan, nav = _setup((chair,))
    obstacles = Obstacles(scene, include_chairs=True)
    r = scene.robot.base_radius_m
    for seed in range(10):
        ex = sim().execute(plan, scene, np.random.default_rng(seed), replan=nav)
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
