"""Episode set-up: objects' starts on the supply tables and chairs around the target table."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import yaml
from shapely.geometry import Point, Polygon
from shapely.geometry import box as rect

from llm_grop import seeds
from llm_grop.errors import BadInput, Infeasible
from llm_grop.files.scene_file import load_scene, parse_scene, scene_to_dict
from llm_grop.geometry.obstacles import Obstacles
from llm_grop.simulation.scenario import prepare_episode
from llm_grop.simulation.supply import FINGER_ROOM_M, supply_layout, sure_reach_m
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Box
from llm_grop.world.request import for_diners, items_from_names
from llm_grop.world.scene import Chair, ObjectSource, Scene, SceneTable
from scenes import two_table_room


@pytest.fixture(scope="module")
def catalog() -> Catalog:
    return Catalog.load(use_env=False)


@pytest.fixture(scope="module")
def scene() -> Scene:
    return load_scene(None)


def _items(catalog: Catalog, *names: str) -> list[Item]:
    """Items named as the request parser names them ("mug", "mug 2", ...)."""
    seen: dict[str, int] = {}
    out = []
    for kind in names:
        seen[kind] = seen.get(kind, 0) + 1
        name = kind if seen[kind] == 1 else f"{kind} {seen[kind]}"
        out.append(Item(name, catalog.resolve(kind)))
    return out


def _poly(b: Box) -> Polygon:
    return Polygon(b.corners())


TASK = ("dinner plate", "dinner fork", "dinner knife", "mug", "mug", "bread", "water cup")


def test_same_seed_same_episode(scene: Scene, catalog: Catalog) -> None:
    items = _items(catalog, *TASK)
    a = prepare_episode(scene, items, 7, chairs=3)
    b = prepare_episode(scene, items, 7, chairs=3)
    c = prepare_episode(scene, items, 8, chairs=3)
    assert a == b
    assert a != c


def test_chairs_do_not_depend_on_the_items(scene: Scene, catalog: Catalog) -> None:
    few = prepare_episode(scene, _items(catalog, "mug"), 3, chairs=2)
    many = prepare_episode(scene, _items(catalog, *TASK), 3, chairs=2)
    assert few.chairs == many.chairs


@pytest.mark.parametrize("seed", range(5))
def test_every_item_starts_on_a_supply_table(scene: Scene, catalog: Catalog,
                                             seed: int) -> None:
    items = _items(catalog, *TASK)
    episode = prepare_episode(scene, items, seed)
    assert [s.object for s in episode.sources] == [i.name for i in items]
    supply = {t.name: t for t in scene.supply_tables}
    for s in episode.sources:
        assert s.table in supply
        # The object's disc (radius 0.06 m) stays 0.05 m inside the edge.
        assert supply[s.table].box.contains(s.x, s.y, margin=-0.11 + 1e-9)
        assert episode.source_for(s.object, "") == s
    for k, a in enumerate(episode.sources):
        for b in episode.sources[:k]:
            assert math.hypot(a.x - b.x, a.y - b.y) >= 0.12 - 1e-9
    assert len({s.table for s in episode.sources}) == len(supply)


def test_given_sources_are_kept(catalog: Catalog) -> None:
    room = two_table_room(sources=(ObjectSource("mug", "counter", 0.45, 2.5),
                                   ObjectSource("dinner fork 2", "counter", 0.3, 1.5)))
    items = _items(catalog, "mug", "mug", "dinner fork", "dinner fork")
    episode = prepare_episode(room, items, 0)
    by_name = {s.object: s for s in episode.sources}
    assert by_name["mug"] == ObjectSource("mug", "counter", 0.45, 2.5)
    assert by_name["dinner fork 2"] == ObjectSource("dinner fork 2", "counter", 0.3, 1.5)
    # The kind's source goes to the first mug only; the second gets a spot of its own.
    assert by_name["mug 2"].table == "counter"
    for name in ("mug 2", "dinner fork"):
        s = by_name[name]
        assert min(math.hypot(s.x - o.x, s.y - o.y)
                   for o in episode.sources if o.object != name) >= 0.12 - 1e-9


def test_objects_that_do_not_fit(catalog: Catalog) -> None:
    room = replace(two_table_room(), sources=(), tables=(
        SceneTable("dining table", Box(3.0, 2.0, 0.9, 0.6)),
        SceneTable("counter", Box(0.4, 2.0, 0.3, 0.3))))
    prepare_episode(room, _items(catalog, "mug"), 0)
    with pytest.raises(Infeasible) as err:
        prepare_episode(room, _items(catalog, "mug", "mug"), 0)
    assert str(err.value) == (
        "the supply tables hold 1 of the 2 objects: 'mug 2' does not fit: no free spot "
        "within the arm's sure reach (0.595 m) of the open sides of 'counter' (south, "
        "north, east)")


@pytest.mark.parametrize("seed", range(10))
def test_chairs_stand_in_the_band(scene: Scene, catalog: Catalog, seed: int) -> None:
    episode = prepare_episode(scene, _items(catalog, "mug"), seed, chairs=4)
    table = scene.target_table.box
    lo, hi = scene.chair_band_m
    obstacles = [_poly(b) for b in scene.static_obstacles()]
    start = scene.robot_start
    keep_off = Point(start.x, start.y).buffer(scene.robot.base_radius_m + 0.1)
    room = rect(0, 0, scene.width, scene.depth)
    assert [c.name for c in episode.chairs] == ["chair 1", "chair 2", "chair 3", "chair 4"]
    for k, chair in enumerate(episode.chairs):
        box = chair.box
        assert (box.width, box.depth, box.yaw) == (0.45, 0.45, table.yaw)
        u, v = table.to_local(box.x, box.y)
        assert abs(u) <= table.width / 2 + 1e-4
        gap = abs(v) - table.depth / 2 - box.depth / 2
        assert lo - 1e-4 <= gap <= hi + 1e-4
        poly = _poly(box)
        assert room.contains(poly)
        assert not any(poly.intersects(o) for o in obstacles)
        assert not poly.intersects(keep_off)
        assert not any(poly.intersects(_poly(o.box)) for o in episode.chairs[:k])


def test_episode_round_trips_through_json(scene: Scene, catalog: Catalog) -> None:
    episode = prepare_episode(scene, _items(catalog, *TASK), 11, chairs=4)
    assert parse_scene(yaml.dump(scene_to_dict(episode)), "run json") == episode


def test_chair_count_and_size(scene: Scene, catalog: Catalog) -> None:
    items = _items(catalog, "mug")
    assert prepare_episode(scene, items, 0, chairs=0).chairs == ()
    one = prepare_episode(scene, items, 0, chairs=1, chair_size_m=(0.5, 0.4))
    assert [(c.box.width, c.box.depth) for c in one.chairs] == [(0.5, 0.4)]


def test_scene_chairs_are_kept_without_a_count(catalog: Catalog) -> None:
    chairs = (Chair("chair 1", Box(3.0, 2.6, 0.45, 0.45)),)
    room = two_table_room(chairs=chairs)
    assert prepare_episode(room, _items(catalog, "mug"), 0).chairs == chairs
    assert prepare_episode(room, _items(catalog, "mug"), 0, chairs=0).chairs == ()


def test_too_many_chairs(scene: Scene, catalog: Catalog) -> None:
    with pytest.raises(Infeasible, match="cannot place 30 chairs near 'dining table'"):
        prepare_episode(scene, _items(catalog, "mug"), 0, chairs=30)


def test_negative_chairs(scene: Scene, catalog: Catalog) -> None:
    with pytest.raises(BadInput, match="chairs: must not be negative"):
        prepare_episode(scene, _items(catalog, "mug"), 0, chairs=-1)


def test_waiting_objects_are_within_easy_reach_of_a_standing_position() -> None:
    from llm_grop.planning.feasibility import DEFAULT_FEASIBILITY
    from llm_grop.planning.standing import pickup_pose, reach
    from llm_grop.world.catalog import Catalog
    from llm_grop.world.request import items_from_names

    scene = load_scene(None)
    items = items_from_names(["dinner plate", "dinner fork", "dinner knife", "mug",
                              "mug lid", "bread", "water cup"], Catalog.load())
    for seed in range(5):
        episode = prepare_episode(scene, items, seed, chairs=1)
        for source in episode.sources:
            stand = pickup_pose(episode, source, episode.robot, DEFAULT_FEASIBILITY)
            r = reach([stand], np.array([[source.x, source.y]]))
            p = DEFAULT_FEASIBILITY.manipulation(r, episode.robot)[0, 0]
            assert p >= 0.8, (seed, source)


SETTING = ("dinner plate", "dinner fork", "dinner knife", "water cup")


def _settings(catalog: Catalog, diners: int) -> tuple[Item, ...]:
    return for_diners(items_from_names(SETTING, catalog), diners)


@pytest.mark.parametrize("seed", range(5))
def test_the_packaged_room_supplies_six_settings(scene: Scene, catalog: Catalog,
                                                 seed: int) -> None:
    items = _settings(catalog, 6)
    episode = prepare_episode(scene, items, seed, chairs=0)
    by_name = {s.object: s for s in episode.sources}
    # The six plates wait in one pile, each on the one before.
    plates = [by_name["dinner plate"], *(by_name[f"dinner plate {k}"] for k in range(2, 7))]
    assert plates[0].on is None
    assert [p.on for p in plates[1:]] == ["dinner plate", *(f"dinner plate {k}"
                                                            for k in range(2, 6))]
    assert len({(p.table, p.x, p.y) for p in plates}) == 1
    heights = {i.name: i.spec.height for i in items}
    table_z = scene.table(plates[0].table).height
    assert [episode.resting_z(p.object, "dinner plate", heights) for p in plates] == \
        pytest.approx([table_z + 0.025 * k for k in range(6)])
    # Whatever does not pile up keeps its own spot: discs apart, or footprints with room
    # for a finger of the open gripper between them.
    alone = [s for s in episode.sources if s.on is None]
    assert len(alone) == 19
    radius = {i.name: _disc(i) for i in items}
    for k, a in enumerate(alone):
        for b in alone[:k]:
            apart = math.hypot(a.x - b.x, a.y - b.y) >= radius[a.object] + radius[b.object]
            sa, sb = (catalog.resolve(_kind(o.object)).size for o in (a, b))
            assert apart or abs(a.x - b.x) >= (sa[0] + sb[0]) / 2 + FINGER_ROOM_M - 1e-9 \
                or abs(a.y - b.y) >= (sa[1] + sb[1]) / 2 + FINGER_ROOM_M - 1e-9, (a, b)


def _kind(name: str) -> str:
    return name.rstrip("0123456789 ")


def _disc(item: Item) -> float:
    sx, sy = item.spec.size
    return max(0.06, sx / 2 if item.spec.shape == "circle" else math.hypot(sx, sy) / 2)


@pytest.mark.parametrize("seed", range(3))
def test_every_spot_is_within_sure_reach_of_a_free_standing_position(
        scene: Scene, catalog: Catalog, seed: int) -> None:
    from llm_grop.planning.feasibility import DEFAULT_FEASIBILITY
    from llm_grop.planning.standing import pickup_pose, reach

    episode = prepare_episode(scene, _settings(catalog, 6), seed, chairs=2)
    for source in episode.sources:
        # The planner's own choice of where to stand (it weighs the stance's clearance
        # too) leaves the pick as sure as for the paper's tasks.
        stand = pickup_pose(episode, source, episode.robot, DEFAULT_FEASIBILITY)
        r = reach([stand], np.array([[source.x, source.y]]))
        assert DEFAULT_FEASIBILITY.manipulation(r, episode.robot)[0, 0] >= 0.8, (seed, source)


def test_the_layout_says_where_to_stand(scene: Scene, catalog: Catalog) -> None:
    items = _settings(catalog, 2)
    spots = supply_layout(scene, items, seeds.stream(0, "scene"))
    obstacles = Obstacles(scene, include_chairs=False)
    for spot in spots:
        assert spot.side in {"north", "south", "east", "west"}
        assert spot.approach is not None
        a, s = spot.approach, spot.source
        assert obstacles.free(a.x, a.y, scene.robot.base_radius_m)
        assert math.hypot(a.x - s.x, a.y - s.y) <= sure_reach_m(scene.robot) + 1e-9
        # The pose faces the object.
        assert math.atan2(s.y - a.y, s.x - a.x) == pytest.approx(a.theta)
    # The kitchen counter stands against the north wall: the robot comes from the south
    # or the east.
    assert {sp.side for sp in spots if sp.source.table == "kitchen counter"} <= {"south",
                                                                                 "east"}


def test_too_many_settings_are_named_in_one_line(scene: Scene, catalog: Catalog) -> None:
    many = for_diners(items_from_names(("dinner plate", "mug", "bread", "napkin"),
                                       catalog), 7)
    with pytest.raises(Infeasible) as err:
        prepare_episode(scene, many, 0)
    text = str(err.value)
    assert "\n" not in text
    assert text.startswith("the supply tables hold ")
    assert " of the 28 objects: " in text
    assert ("no free spot within the arm's sure reach (0.595 m) of the open sides of "
            "'kitchen counter' (south, east), 'side table' (north, west), 'sideboard' "
            "(south, north, west)") in text


def test_a_table_too_small_or_shut_in_is_named(catalog: Catalog) -> None:
    room = replace(two_table_room(), sources=(), source_tables=("counter", "shelf"),
                   tables=(SceneTable("dining table", Box(3.0, 2.0, 0.9, 0.6)),
                           SceneTable("counter", Box(0.4, 2.0, 0.3, 0.3)),
                           SceneTable("shelf", Box(5.85, 3.85, 0.3, 0.3))))
    with pytest.raises(Infeasible) as err:
        prepare_episode(room, _items(catalog, "dinner plate"), 0)
    assert str(err.value) == (
        "the supply tables hold 0 of the 1 objects: 'dinner plate' does not fit: 'counter' "
        "is too small for it; 'shelf' is too small for it")
    with pytest.raises(Infeasible) as err:
        prepare_episode(room, _items(catalog, "mug", "mug", "mug"), 0)
    assert "'shelf' has no side where the base (radius 0.3 m) fits" in str(err.value)


def test_a_pinned_object_out_of_reach_is_named(catalog: Catalog) -> None:
    room = two_table_room(sources=(ObjectSource("mug", "counter", 0.2, 2.0),))
    with pytest.raises(Infeasible) as err:
        prepare_episode(room, _items(catalog, "mug", "bread"), 0)
    assert str(err.value) == (
        "the supply tables hold 1 of the 2 objects: 'mug' starts at (0.2, 2) on 'counter', "
        "beyond the arm's sure reach (0.595 m) of every free standing position at its open "
        "sides")


def test_piles_respect_the_catalog_stack(scene: Scene, catalog: Catalog) -> None:
    bowls = _items(catalog, *["fruit bowl"] * 6)
    episode = prepare_episode(scene, bowls, 0)
    bottoms = [s for s in episode.sources if s.on is None]
    assert catalog.resolve("fruit bowl").stack == 4
    assert [s.object for s in bottoms] == ["fruit bowl", "fruit bowl 5"]
    mugs = prepare_episode(scene, _items(catalog, "mug", "mug"), 0)
    assert all(s.on is None for s in mugs.sources)


def test_a_pinned_pile_is_kept_and_read_back(catalog: Catalog) -> None:
    room = two_table_room(sources=(ObjectSource("dinner plate", "counter", 0.45, 2.1),
                                   ObjectSource("dinner plate 2", "counter", 0.45, 2.1,
                                                "dinner plate")))
    episode = prepare_episode(room, _items(catalog, *["dinner plate"] * 3), 0)
    assert [(s.object, s.x, s.y, s.on) for s in episode.sources] == [
        ("dinner plate", 0.45, 2.1, None), ("dinner plate 2", 0.45, 2.1, "dinner plate"),
        ("dinner plate 3", 0.45, 2.1, "dinner plate 2")]
    assert parse_scene(yaml.dump(scene_to_dict(episode)), "run json") == episode
