"""Occupancy, cost-to-go fields, OMPL paths, the feasibility model and standing positions."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from llm_grop.errors import Infeasible
from llm_grop.geometry.motion import path_length_m as path_length
from llm_grop.geometry.obstacles import Obstacles
from llm_grop.planning.feasibility import DEFAULT_FEASIBILITY, ParametricFeasibility
from llm_grop.planning.navigation import PATH_MARGIN_M, NavGraph, Navigator
from llm_grop.planning.occupancy import build_grid
from llm_grop.planning.standing import (
    blocked_reason,
    candidate_standing_poses,
    pickup_pose,
    reach,
)
from llm_grop.world.geometry2d import Box
from llm_grop.world.robot import Robot
from llm_grop.world.scene import Chair, ObjectSource, Scene
from scenes import doorway_room, two_table_room


def test_clearance_matches_shapely() -> None:
    scene = two_table_room(chairs=(Chair("chair 1", Box(3.0, 1.2, 0.45, 0.45, 0.4)),))
    obstacles = Obstacles(scene)
    rng = np.random.default_rng(0)
    pts = rng.uniform([0, 0], [6, 4], size=(300, 2))
    shapes = [Polygon(b.corners()) for b in scene.static_obstacles()] \
        + [Polygon(c.box.corners()) for c in scene.chairs]
    union = shapely.union_all(shapes + [shapely.box(0, 0, 6, 4).exterior])
    expected = shapely.distance(union, shapely.points(pts))
    expected[shapely.contains_xy(union, pts[:, 0], pts[:, 1])] = 0.0
    assert np.allclose(obstacles.clearance(pts), expected, atol=1e-9)
    for (x, y), c in zip(pts, expected, strict=True):
        if abs(c - 0.3) > 1e-6:
            assert obstacles.free(float(x), float(y), 0.3) == (c > 0.3)


def test_chairs_are_left_out_of_the_prebuilt_map() -> None:
    scene = two_table_room(chairs=(Chair("chair 1", Box(3.0, 1.2, 0.45, 0.45)),))
    pt = np.array([[3.0, 1.2]])
    assert Obstacles(scene).clearance(pt)[0] == 0.0
    assert Obstacles(scene, include_chairs=False).clearance(pt)[0] > 0.2


def test_cost_fields_are_close_to_euclidean_in_the_open() -> None:
    scene = two_table_room()
    field = NavGraph(build_grid(scene), 0.3).fields([(5.0, 0.6)])[0]
    pts = np.array([[5.0, 3.4], [1.0, 0.6], [5.6, 3.5]])
    straight = np.hypot(*(pts - [5.0, 0.6]).T)
    got = field.cost_at(pts)
    assert np.all(got >= straight - 0.05)
    assert np.all(got <= straight * 1.04 + 0.05)


def test_cost_fields_go_round_the_table() -> None:
    scene = two_table_room()
    field = NavGraph(build_grid(scene), 0.3).fields([(3.0, 1.2)])[0]
    # Straight across the table is 1.6 m; the base has to go round it.
    assert field.cost_at(np.array([[3.0, 2.8]]))[0] > 2.2


def test_unreachable_cells_cost_infinity() -> None:
    walls = (Box(2.0, 2.0, 0.1, 4.0),)
    scene = two_table_room()
    from dataclasses import replace
    walled = replace(scene, walls=walls)
    field = NavGraph(build_grid(walled), 0.3).fields([(1.0, 0.6)])[0]
    assert math.isinf(field.cost_at(np.array([[5.0, 3.0]]))[0])
    assert math.isfinite(field.cost_at(np.array([[1.0, 3.0]]))[0])


def test_navigator_paths_are_free_deterministic_and_short() -> None:
    scene = two_table_room(chairs=(Chair("chair 1", Box(3.0, 1.15, 0.45, 0.45)),))
    nav = Navigator(scene, 0.3)
    start, goal = (3.0, 0.4), (3.0, 3.4)
    a = nav.plan(start, goal, seed=7)
    assert a is not None and a == nav.plan(start, goal, seed=7)
    assert a[0] == start and a[-1] == goal
    for p, q in zip(a, a[1:], strict=False):
        assert nav.segment_free(p, q)
    field = NavGraph(build_grid(scene), 0.3).fields([start])[0]
    assert path_length(a) <= field.cost_at(np.array([goal]))[0] * 1.15


def test_navigator_gives_up_after_its_iterations_not_its_clock() -> None:
    scene = doorway_room(0.74)
    start, goal = (1.0, 0.6), (5.0, 3.2)
    # With this seed, a path that keeps the 6 cm margin through the doorway takes RRTConnect
    # about 8,000 iterations; with fewer it gives up and plans without the margin.
    kept = Navigator(scene, 0.3).plan(start, goal, seed=8)
    hurried = Navigator(scene, 0.3, iterations=2_000).plan(start, goal, seed=8)
    assert kept is not None and hurried is not None
    assert _keeps(scene, kept, PATH_MARGIN_M) and not _keeps(scene, hurried, PATH_MARGIN_M)
    assert _keeps(scene, hurried, 0.0)
    # However long it may run, a search that ends on its iterations finds the same path.
    assert Navigator(scene, 0.3, time_limit_s=1e6).plan(start, goal, seed=8) == kept


def _keeps(scene: Scene, path: tuple[tuple[float, float], ...], margin_m: float) -> bool:
    """Whether ``path`` keeps the 0.3 m base's radius plus ``margin_m`` (tapered at its
    ends) all along."""
    nav = Navigator(scene, 0.3)
    pts = np.concatenate([np.linspace(p, q, 50) for p, q in zip(path, path[1:],
                                                                 strict=False)])
    ends = np.array([path[0], path[-1]])
    return bool((nav.obstacles.clearance(pts)
                 >= nav.required_m(pts, ends, margin_m) - 1e-9).all())


def test_navigator_refuses_goals_in_collision() -> None:
    nav = Navigator(two_table_room(), 0.3)
    assert nav.plan((1.5, 0.6), (3.0, 2.0), seed=0) is None


def test_feasibility_model_shape() -> None:
    model = ParametricFeasibility()
    nav = model.navigation(np.array([-0.01, 0.0, 0.02, 0.05, 0.2]))
    assert nav[0] == 0.0
    assert np.all(np.diff(nav[1:]) > 0) and nav[-1] <= 0.98
    assert nav[2] == pytest.approx(0.49)
    robot = Robot()
    r = np.array([0.1, 0.3, 0.55, 0.7, 0.84, 0.85, 1.0])
    manip = model.manipulation(r, robot)
    assert manip[0] == 0.0 and manip[1] == manip[2] == pytest.approx(0.97)
    assert manip[2] > manip[3] > manip[4] > 0
    assert manip[5] == manip[6] == 0.0


def test_standing_positions_surround_the_table_and_face_it() -> None:
    scene = two_table_room()
    poses = candidate_standing_poses(scene, "dining table", scene.robot)
    box = scene.target_table.box
    sides = set()
    for s in poses:
        u, v = box.to_local(s.pose.x, s.pose.y)
        assert s.clearance_m >= 0
        top = Polygon(box.corners())
        assert top.distance(shapely.Point(s.pose.x, s.pose.y)) >= scene.robot.base_radius_m
        sides.add((int(np.sign(round(u / 0.5))), int(np.sign(round(v / 0.35)))))
        near = (box.x + np.clip(u, -0.45, 0.45), box.y + np.clip(v, -0.3, 0.3))
        heading = math.atan2(near[1] - s.pose.y, near[0] - s.pose.x)
        assert abs(math.remainder(heading - s.pose.theta, 2 * math.pi)) < 1e-6
    assert {(-1, 0), (1, 0), (0, -1), (0, 1)} <= sides
    assert len(poses) > 60


def test_robot_never_stands_inside_a_chair() -> None:
    chair = Chair("chair 1", Box(3.0, 1.2, 0.45, 0.45))
    scene = two_table_room(chairs=(chair,))
    radius = scene.robot.base_radius_m
    for s in candidate_standing_poses(scene, "dining table", scene.robot):
        assert Polygon(chair.box.corners()).distance(shapely.Point(s.pose.x, s.pose.y)) \
            >= radius - 1e-9


def test_reach_and_pickup_pose() -> None:
    scene = two_table_room()
    source = ObjectSource("mug", "counter", 0.45, 2.5)
    stand = pickup_pose(scene, source, scene.robot, DEFAULT_FEASIBILITY)
    assert stand.table == "counter"
    d = reach([stand], np.array([[source.x, source.y]]))[0, 0]
    assert scene.robot.reach_min_m <= d <= 0.7 * scene.robot.reach_max_m
    far = ObjectSource("mug", "counter", 0.2, 2.0)
    big_arm_short = Robot(reach_min_m=0.0, reach_max_m=0.32)
    with pytest.raises(Infeasible, match="out of the arm's reach"):
        pickup_pose(scene, far, big_arm_short, DEFAULT_FEASIBILITY)


def test_chairs_all_round_are_reported() -> None:
    chairs = tuple(Chair(f"chair {i}", Box(x, y, w, d)) for i, (x, y, w, d) in enumerate(
        [(3.0, 1.35, 1.6, 0.5), (3.0, 2.65, 1.6, 0.5), (2.2, 2.0, 0.5, 0.8),
         (3.8, 2.0, 0.5, 0.8)], 1))
    scene = two_table_room(chairs=chairs)
    assert candidate_standing_poses(scene, "dining table", scene.robot) == ()
    assert "block every side" in blocked_reason(scene, "dining table", scene.robot)


def test_free_lookup_gives_the_exact_answers() -> None:
    # The clearance grid only decides where it is sure; every answer is Obstacles.free's.
    scene = two_table_room(chairs=(Chair("chair 1", Box(3.0, 1.2, 0.45, 0.45, 0.4)),))
    nav = Navigator(scene, 0.3)
    lookup = nav.free_lookup()
    rng = np.random.default_rng(1)
    for x, y in rng.uniform([0, 0], [6, 4], size=(3000, 2)):
        for r in (0.3, 0.33, 0.36):
            assert lookup.free(float(x), float(y), r) == nav.obstacles.free(float(x), float(y), r)


def test_grid_of_a_room_is_kept_but_chairs_are_each_episodes() -> None:
    chair = Chair("chair 1", Box(3.0, 1.2, 0.45, 0.45, 0.4))
    with_chair = build_grid(two_table_room(chairs=(chair,)))
    without = build_grid(two_table_room())
    direct = Obstacles(two_table_room(chairs=(chair,))).clearance(
        (np.stack(np.meshgrid(np.arange(with_chair.shape[1]), np.arange(with_chair.shape[0])),
                  axis=-1).reshape(-1, 2) + 0.5) * with_chair.resolution_m)
    assert np.array_equal(with_chair.clearance_m.ravel(), direct)
    assert (without.clearance_m >= with_chair.clearance_m).all()
    assert (without.clearance_m > with_chair.clearance_m).any()
