"""Episode set-up: objects' starts on the supply tables and chairs around the target table."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import yaml
from shapely.geometry import Point, Polygon
from shapely.geometry import box as rect

from llm_grop.errors import BadInput, Infeasible
from llm_grop.files.scene_file import load_scene, parse_scene, scene_to_dict
from llm_grop.simulation.scenario import prepare_episode
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Box
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
    with pytest.raises(Infeasible, match="cannot fit 'mug 2' on the supply tables"):
        prepare_episode(room, _items(catalog, "mug", "mug"), 0)


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
