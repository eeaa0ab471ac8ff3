"""The baselines' random arrangement: a truncated Gaussian around each diner's place
centre, on the table and without overlaps, in a grown box when the authors' cannot hold the
objects."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import truncnorm

from llm_grop import seeds
from llm_grop.api import resolve_items, run
from llm_grop.arrangement.random_placement import (
    AUTHORS_BOX,
    SIGMA_M,
    TRUNCATION_M,
    VARIANCE_M2,
    DrawBox,
    grown_box,
    random_configurations,
)
from llm_grop.arrangement.sampling import violations
from llm_grop.errors import Infeasible
from llm_grop.geometry.places import default_seats, places
from llm_grop.world.arrangement import Configuration, Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import for_diners, items_from_names
from llm_grop.world.table import Table

CATALOG = Catalog.load(use_env=False)
TASK_8 = items_from_names(["dinner plate", "dinner fork", "dinner knife", "mug", "mug lid"],
                          CATALOG)
SETTING = items_from_names(["dinner plate", "dinner fork", "dinner knife"], CATALOG)
#: The 20 objects of benchmarks/planning_time.py, more than the authors' box holds.
TWENTY = ("set the table with a dinner plate, a bread plate, a salad plate, two dinner forks, "
          "a salad fork, two dinner knives, a butter knife, a soup spoon, two teaspoons, "
          "a water cup, a wine glass, a mug, a mug mat, a mug lid, a strawberry, bread "
          "and a napkin")
#: Slack, metres, for a position that went through the place frame and back.
ROUND_OFF_M = 1e-9


def _check(configs: tuple[Configuration, ...], items: tuple[Item, ...], table: Table) -> None:
    """Every object on the table, none overlapping another, each within the truncation of
    its diner's place centre along that place's axes."""
    seated = places(table, table.seats)
    for c in configs:
        assert [p.name for p in c.placements] == [it.name for it in items]
        assert violations(c, [], table) == []
        for p in c.placements:
            u, v = seated[p.diner or 0].to_place(p.x, p.y)
            assert abs(float(u)) <= TRUNCATION_M + ROUND_OFF_M, p
            assert abs(float(v)) <= TRUNCATION_M + ROUND_OFF_M, p


def test_the_numbers_are_the_authors() -> None:
    assert VARIANCE_M2 == 0.03
    assert abs(SIGMA_M - 0.1732) < 1e-4
    assert TRUNCATION_M == 0.225


@pytest.mark.parametrize("table", [Table(), Table(1.2, 0.8), Table.circle(0.9)],
                         ids=lambda t: t.text)
def test_one_diner_draws_around_the_table_centre_on_the_table_without_overlaps(
        table: Table) -> None:
    configs = random_configurations(TASK_8, table, np.random.default_rng(0), m=50)
    assert len(configs) == 50
    _check(configs, TASK_8, table)
    # One diner's place centre is the table's centre (the authors' root).
    assert places(table, table.seats)[0].origin == (0.0, 0.0)


def test_the_spread_is_the_truncated_gaussians() -> None:
    # A small object on a top large enough that only the truncation limits the draw.
    table = Table(2.0, 2.0)
    lid = items_from_names(["mug lid"], CATALOG)
    configs = random_configurations(lid, table, np.random.default_rng(1), m=4000)
    xy = np.array([(c.placements[0].x, c.placements[0].y) for c in configs])
    bound = TRUNCATION_M / SIGMA_M
    expected = truncnorm(-bound, bound, scale=SIGMA_M).std()  # about 0.116 m
    assert np.all(np.abs(xy) <= TRUNCATION_M)
    for axis in (0, 1):
        assert abs(xy[:, axis].mean()) < 0.01
        # The sample std's own error is about 1 %; a uniform draw over the truncation box
        # (0.130 m) or the untruncated Gaussian (0.173 m) would be far outside 5 %.
        assert xy[:, axis].std() == pytest.approx(expected, rel=0.05)


def test_the_draw_stays_within_the_place_even_where_the_table_is_larger() -> None:
    table = Table(1.8, 0.9)
    configs = random_configurations(TASK_8, table, np.random.default_rng(2), m=100)
    _check(configs, TASK_8, table)
    xs = [p.x for c in configs for p in c.placements]
    assert max(abs(x) for x in xs) <= TRUNCATION_M < table.width / 2


@pytest.mark.parametrize(("table", "count"), [
    (Table(1.8, 0.9), 2), (Table(1.8, 0.9), 4), (Table.circle(1.2), 3)],
    ids=["1.8x0.9, 2 diners", "1.8x0.9, 4 diners", "round 1.2, 3 diners"])
def test_several_diners_each_item_near_its_own_diners_place(table: Table, count: int) -> None:
    seated_table = table.with_diners(default_seats(table, count))
    items = for_diners(SETTING, count)
    configs = random_configurations(items, seated_table, np.random.default_rng(3), m=30)
    _check(configs, items, seated_table)
    centres = np.array([p.origin for p in places(seated_table, seated_table.seats)])
    assert all(p.diner is not None for c in configs for p in c.placements)
    # Over many draws each diner's objects gather round their own place centre, nearer it
    # than any other diner's.
    for k, centre in enumerate(centres):
        mine = np.array([(p.x, p.y) for c in configs for p in c.placements if p.diner == k])
        d = np.hypot(*(mine.mean(axis=0)[:, None] - centres.T))
        assert d[k] < 0.1
        assert int(np.argmin(d)) == k, (k, centre, d)


def test_the_same_seed_gives_the_same_configurations() -> None:
    a = random_configurations(TASK_8, Table(), seeds.stream(7, "random_arrangement"))
    b = random_configurations(TASK_8, Table(), seeds.stream(7, "random_arrangement"))
    c = random_configurations(TASK_8, Table(), seeds.stream(8, "random_arrangement"))
    assert a == b
    assert a != c
    assert len(set(a)) == len(a)  # the 25 configurations differ


def test_an_object_larger_than_the_table_is_infeasible() -> None:
    plate = items_from_names(["dinner plate"], CATALOG)
    with pytest.raises(Infeasible, match="does not fit"):
        random_configurations(plate, Table(0.2, 0.2), np.random.default_rng(0), m=1)


def test_more_than_the_table_holds_is_infeasible() -> None:
    # Ten dinner plates (0.57 m²) cannot lie on a 0.9 x 0.6 m top (0.54 m²), whichever box.
    plates = items_from_names(["dinner plate"] * 10, CATALOG)
    with pytest.raises(Infeasible, match="without overlaps .* nor in each diner's whole place"):
        random_configurations(plates, Table(0.9, 0.6), np.random.default_rng(0), m=1)


def test_the_box_grows_to_the_diners_share_of_the_table() -> None:
    (place,) = places(Table(1.8, 0.9), Table(1.8, 0.9).seats)
    assert grown_box(place) == DrawBox((4 * SIGMA_M, 2 * SIGMA_M), (0.9, 0.45))
    # A place no larger than the authors' box along an axis keeps that axis as it is.
    (small,) = places(Table(0.4, 0.9), Table(0.4, 0.9).seats)
    assert grown_box(small) == DrawBox((SIGMA_M, 2 * SIGMA_M), (TRUNCATION_M, 0.45))
    (tiny,) = places(Table(0.4, 0.4), Table(0.4, 0.4).seats)
    assert grown_box(tiny) == AUTHORS_BOX


def test_more_than_the_authors_box_holds_is_drawn_in_the_grown_box() -> None:
    # Ten dinner plates (0.57 m²) cannot lie within the 0.72 m square that centres drawn
    # at most 0.225 m from the table's centre reach; the whole 2 x 2 m top holds them.
    table = Table(2.0, 2.0)
    plates = items_from_names(["dinner plate"] * 10, CATALOG)
    configs = random_configurations(plates, table, seeds.stream(0, "random_arrangement"), m=5)
    assert len(configs) == 5
    for c in configs:
        assert violations(c, [], table) == []
    assert max(max(abs(p.x), abs(p.y)) for c in configs for p in c.placements) > TRUNCATION_M
    again = random_configurations(plates, table, seeds.stream(0, "random_arrangement"), m=5)
    assert again == configs  # deterministic for the seed


def test_twenty_objects_on_a_long_table_are_placed_and_planned() -> None:
    # benchmarks/planning_time.py's 20-object case, which the authors' box cannot hold.
    table = Table(1.8, 0.9)
    _, items = resolve_items(TWENTY, None, CATALOG)
    assert len(items) == 20
    configs = random_configurations(items, table, seeds.stream(0, "random_arrangement"), m=25)
    assert len(configs) == 25
    for c in configs:
        assert violations(c, [], table) == []
    result = run(TWENTY, method="grop", table=table, seed=0, chairs=1)
    assert len(result.plan.configuration) == 20
