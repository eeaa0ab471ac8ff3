"""LLM-guided positions (paper §III-B) and the geometric meaning of relations."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from llm_grop.arrangement.geometry import DEFAULT_GAP_M, choose_origin, guided_layout
from llm_grop.arrangement.layout import (
    ACROSS_SIGMA_M,
    FREE_SIGMA_M,
    GAP_SIGMA_M,
    STACK_SIGMA_M,
)
from llm_grop.arrangement.predicates import (
    Footprint,
    clear_of,
    in_center,
    inside_table,
    pair_relation_holds,
    stacked_pairs,
)
from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import CONVERSE, DIRECTION, STACKING, Relation
from llm_grop.world.table import Table

CATALOG = Catalog.load(use_env=False)
TABLE = Table(0.9, 0.6)
DIRECTIONS = sorted(r for r in DIRECTION if r not in STACKING)


def items(*names: str) -> list[Item]:
    """Items named after catalog kinds; ``"dinner fork 2"`` is a second dinner fork."""
    out = []
    for name in names:
        kind = name.rstrip(" 0123456789")
        spec = CATALOG.lookup(kind)
        assert spec is not None, kind
        out.append(Item(name, spec))
    return out


def rel(subject: str, relation: str, reference: str | None = None) -> Relation:
    return Relation(subject, relation, reference)


# --- guided positions --------------------------------------------------------------------

def test_fork_left_of_plate_is_a_gap_between_edges() -> None:
    fork = rel("dinner fork", "to the left of", "dinner plate")
    lay = guided_layout(items("dinner plate", "dinner fork"), [fork], {fork.key(): 0.02}, TABLE)
    assert lay.origin == "dinner plate"
    assert lay.positions["dinner plate"] == (0.0, 0.0)
    x, y = lay.positions["dinner fork"]
    assert x == pytest.approx(-(0.02 + 0.135 + 0.0125))
    assert y == 0.0
    assert lay.sigma["dinner fork"] == (GAP_SIGMA_M, ACROSS_SIGMA_M)
    assert lay.sigma["dinner plate"] == FREE_SIGMA_M


@pytest.mark.parametrize(("relation", "sx", "sy"), [
    ("above and to the right of", 1, 1), ("above and to the left of", -1, 1),
    ("below and to the right of", 1, -1), ("below and to the left of", -1, -1),
])
def test_diagonals_move_on_both_axes_by_the_same_gap(relation: str, sx: int, sy: int) -> None:
    r = rel("mug", relation, "dinner plate")
    lay = guided_layout(items("dinner plate", "mug"), [r], {r.key(): 0.03}, TABLE)
    assert lay.positions["mug"] == pytest.approx((sx * (0.03 + 0.045 + 0.135),
                                                  sy * (0.03 + 0.045 + 0.135)))
    assert lay.sigma["mug"] == (GAP_SIGMA_M, GAP_SIGMA_M)


def test_above_moves_on_y_only() -> None:
    r = rel("water cup", "above", "dinner plate")
    lay = guided_layout(items("dinner plate", "water cup"), [r], {r.key(): 0.01}, TABLE)
    assert lay.positions["water cup"] == pytest.approx((0.0, 0.01 + 0.04 + 0.135))
    assert lay.sigma["water cup"] == (ACROSS_SIGMA_M, GAP_SIGMA_M)


def test_relations_are_walked_backwards_as_their_converse() -> None:
    # The origin (the plate, at the centre) is the *subject*: the cup goes below it.
    r = rel("dinner plate", "above", "water cup")
    lay = guided_layout(items("dinner plate", "water cup"),
                        [rel("dinner plate", "center"), r], {r.key(): 0.04}, TABLE)
    assert lay.origin == "dinner plate"
    assert lay.positions["water cup"] == pytest.approx((0.0, -(0.04 + 0.04 + 0.135)))
    assert lay.sigma["water cup"] == (ACROSS_SIGMA_M, GAP_SIGMA_M)


def test_chain_of_relations_accumulates_and_missing_gap_defaults() -> None:
    knife = rel("dinner knife", "to the right of", "dinner plate")
    spoon = rel("teaspoon", "to the right of", "dinner knife")
    lay = guided_layout(items("dinner plate", "dinner knife", "teaspoon"), [knife, spoon],
                        {knife.key(): 0.02}, TABLE)
    kx = 0.02 + 0.135 + 0.01
    assert lay.positions["dinner knife"] == pytest.approx((kx, 0.0))
    assert lay.positions["teaspoon"] == pytest.approx((kx + DEFAULT_GAP_M + 0.01 + 0.015, 0.0))
    assert lay.order == ("dinner plate", "dinner knife", "teaspoon")


def test_two_objects_on_the_same_side_are_pushed_apart() -> None:
    rels = [rel("dinner fork", "to the left of", "dinner plate"),
            rel("salad fork", "to the left of", "dinner plate")]
    lay = guided_layout(items("dinner plate", "dinner fork", "salad fork"), rels, {}, TABLE)
    (fx, fy), (sx, sy) = lay.positions["dinner fork"], lay.positions["salad fork"]
    assert fy == sy == 0.0
    assert sx < fx
    assert clear_of(fx, fy, Footprint("box", 0.0125, 0.1), sx, sy, Footprint("box", 0.0125, 0.085))


# --- origin ------------------------------------------------------------------------------

def test_origin_is_the_center_subject() -> None:
    its = items("dinner plate", "mug")
    assert choose_origin(its, [rel("mug", "center")]) == "mug"
    lay = guided_layout(its, [rel("mug", "center"), rel("dinner plate", "below", "mug")],
                        {}, Table(1.2, 0.9))
    assert lay.origin == "mug"
    assert lay.positions["mug"] == (0.0, 0.0)
    assert lay.order[0] == "mug"


def test_origin_is_otherwise_the_largest_footprint() -> None:
    assert choose_origin(items("dinner fork", "bread plate", "dinner plate"), []) == "dinner plate"
    # A tie goes to the first listed.
    assert choose_origin(items("water cup", "wine glass"), []) == "water cup"
    assert choose_origin(items("wine glass", "water cup"), []) == "wine glass"


def test_no_items_is_bad_input() -> None:
    with pytest.raises(BadInput, match="no objects"):
        choose_origin([], [])


# --- stacking ----------------------------------------------------------------------------

def test_stack_shares_one_place_and_supports_come_first() -> None:
    rels = [rel("mug lid", "on top of", "mug"), rel("mug", "on top of", "mug mat"),
            rel("mug mat", "above and to the right of", "dinner plate")]
    lay = guided_layout(items("mug lid", "mug", "dinner plate", "mug mat"), rels, {}, TABLE)
    assert lay.origin == "dinner plate"
    pos = lay.positions
    assert pos["mug lid"] == pos["mug"] == pos["mug mat"]
    assert pos["mug mat"][0] > 0 and pos["mug mat"][1] > 0
    assert lay.support == {"mug lid": "mug", "mug": "mug mat", "dinner plate": None,
                           "mug mat": None}
    order = lay.order
    assert order.index("mug mat") < order.index("mug") < order.index("mug lid")
    assert lay.sigma["mug"] == lay.sigma["mug lid"] == STACK_SIGMA_M


def test_under_makes_the_reference_rest_on_the_subject() -> None:
    # The origin rests on something: its support is sampled first and carries it.
    rels = [rel("mug", "center"), rel("mug mat", "under", "mug")]
    lay = guided_layout(items("mug", "mug mat"), rels, {}, TABLE)
    assert lay.origin == "mug"
    assert lay.support == {"mug": "mug mat", "mug mat": None}
    assert lay.order == ("mug mat", "mug")
    assert lay.positions["mug"] == lay.positions["mug mat"] == (0.0, 0.0)
    assert lay.sigma["mug mat"] == FREE_SIGMA_M
    assert lay.sigma["mug"] == STACK_SIGMA_M


def test_a_loop_of_supports_is_broken() -> None:
    rels = [rel("mug", "on top of", "mug mat"), rel("mug mat", "on top of", "mug")]
    lay = guided_layout(items("mug", "mug mat"), rels, {}, TABLE)
    assert lay.support == {"mug": "mug mat", "mug mat": None}


# --- unconnected objects and the final shift ---------------------------------------------

def test_unconnected_objects_go_in_a_row_above_the_rest() -> None:
    fork = rel("dinner fork", "to the left of", "dinner plate")
    lay = guided_layout(items("dinner plate", "dinner fork", "strawberry", "water cup"),
                        [fork], {}, Table(1.2, 0.9))
    plate_top = lay.positions["dinner plate"][1] + 0.135
    for name, r in (("strawberry", 0.0175), ("water cup", 0.04)):
        x, y = lay.positions[name]
        assert y - r >= plate_top + DEFAULT_GAP_M - 1e-9
        assert lay.sigma[name] == FREE_SIGMA_M
    assert lay.positions["strawberry"][0] < lay.positions["water cup"][0]
    assert lay.order[:2] == ("dinner plate", "dinner fork")


def test_layout_is_shifted_just_enough_to_fit_the_table() -> None:
    fork = rel("dinner fork", "to the left of", "dinner plate")
    lay = guided_layout(items("dinner plate", "dinner fork"), [rel("dinner plate", "center"), fork],
                        {fork.key(): 0.30}, TABLE)
    fx, _ = lay.positions["dinner fork"]
    assert fx - 0.0125 == pytest.approx(-0.45)
    assert lay.positions["dinner plate"][0] == pytest.approx(0.01)


def test_layout_that_cannot_fit_is_not_shifted() -> None:
    rels = [rel("dinner fork", "to the left of", "dinner plate"),
            rel("dinner knife", "to the right of", "dinner plate")]
    lay = guided_layout(items("dinner plate", "dinner fork", "dinner knife"), rels,
                        {r.key(): 0.5 for r in rels}, TABLE)
    assert lay.positions["dinner plate"] == (0.0, 0.0)


@pytest.mark.parametrize(("rels", "message"), [
    ([rel("spoon", "to the left of", "dinner plate")], "'spoon' is not an object"),
    ([rel("dinner plate", "above", "dinner plate")], "cannot relate to itself"),
])
def test_bad_relations_are_bad_input(rels: list[Relation], message: str) -> None:
    with pytest.raises(BadInput, match=message):
        guided_layout(items("dinner plate", "dinner fork"), rels, {}, TABLE)


def test_duplicate_names_are_bad_input() -> None:
    with pytest.raises(BadInput, match="used twice"):
        guided_layout(items("mug", "mug"), [], {}, TABLE)


# --- predicates ----------------------------------------------------------------------------

PLATE = Footprint("circle", 0.135, 0.135)
FORK = Footprint("box", 0.0125, 0.1)

coords = st.floats(-0.5, 0.5, allow_nan=False)


@settings(derandomize=True, max_examples=300)
@given(coords, coords, coords, coords)
def test_each_pair_is_in_exactly_one_direction_or_aligned_on_both(
        xs: float, ys: float, xr: float, yr: float) -> None:
    holding = [r for r in DIRECTIONS if pair_relation_holds(r, xs, ys, FORK, xr, yr, PLATE)]
    both_aligned = abs(xs - xr) <= 0.135 and abs(ys - yr) <= 0.135
    assert len(holding) == (0 if both_aligned else 1)
    for r in holding:  # the converse holds seen from the other side
        assert pair_relation_holds(CONVERSE[r], xr, yr, PLATE, xs, ys, FORK)


def test_axis_boundaries_use_the_larger_half_extent() -> None:
    # Aligned up to max(hx) = 0.135 inclusive, strictly left beyond it.
    assert pair_relation_holds("above", 0.135, 0.2, FORK, 0.0, 0.0, PLATE)
    assert not pair_relation_holds("above", 0.1351, 0.2, FORK, 0.0, 0.0, PLATE)
    assert pair_relation_holds("to the left of", -0.1351, 0.0, FORK, 0.0, 0.0, PLATE)
    assert not pair_relation_holds("to the left of", -0.135, 0.0, FORK, 0.0, 0.0, PLATE)
    assert pair_relation_holds("below and to the left of", -0.2, -0.2, FORK, 0.0, 0.0, PLATE)
    assert not pair_relation_holds("below and to the left of", -0.2, -0.1, FORK, 0.0, 0.0, PLATE)


def test_predicates_are_vectorised() -> None:
    xs = np.array([[-0.3, 0.0], [0.3, -0.2]])
    got = pair_relation_holds("to the left of", xs, 0.0, FORK, 0.0, 0.0, PLATE)
    assert got.tolist() == [[True, False], [False, True]]


def test_on_top_of_is_centre_within_the_supports_footprint() -> None:
    mug = Footprint("circle", 0.045, 0.045)
    assert pair_relation_holds("on top of", 0.03, 0.03, mug, 0.0, 0.0, PLATE)
    assert not pair_relation_holds("on top of", 0.1, 0.1, mug, 0.0, 0.0, PLATE)  # 0.141 > r
    assert pair_relation_holds("under", 0.0, 0.0, PLATE, 0.1, 0.05, mug)
    assert pair_relation_holds("on top of", 0.0120, 0.099, mug, 0.0, 0.0, FORK)
    assert not pair_relation_holds("on top of", 0.0130, 0.0, mug, 0.0, 0.0, FORK)


def test_center_and_table_bounds() -> None:
    assert in_center(0.225, -0.15, TABLE)
    assert not in_center(0.226, 0.0, TABLE)
    assert inside_table(0.45 - 0.135, 0.0, PLATE, TABLE)
    assert not inside_table(0.45 - 0.134, 0.0, PLATE, TABLE)


def test_overlap_uses_true_shapes_inflated_by_five_percent() -> None:
    mug = Footprint("circle", 0.045, 0.045)
    # Circles: 0.18 apart, radii sum 0.18 -> overlap only once inflated.
    assert not clear_of(0.0, 0.0, PLATE, 0.18, 0.0, mug)
    assert clear_of(0.0, 0.0, PLATE, 1.06 * 0.18, 0.0, mug)
    # A circle by a box's corner: the bounding boxes overlap, the shapes do not.
    assert clear_of(0.045, 0.045, Footprint("circle", 0.03, 0.03), 0.0, 0.0,
                    Footprint("box", 0.02, 0.02))
    assert not clear_of(0.05, 0.0, Footprint("circle", 0.03, 0.03), 0.0, 0.0,
                        Footprint("box", 0.02, 0.02))
    # Boxes compare bounding boxes on each axis.
    assert not clear_of(0.0, 0.0, FORK, 0.025, 0.0, FORK)
    assert clear_of(0.0, 0.0, FORK, 0.0, 0.25, FORK)


def test_stacked_pairs_are_transitive_but_siblings_are_not() -> None:
    pairs = stacked_pairs([("mug lid", "mug"), ("mug", "mug mat"), ("bread", "bread plate"),
                           ("strawberry", "bread plate")])
    assert frozenset(("mug lid", "mug mat")) in pairs
    assert frozenset(("mug lid", "mug")) in pairs
    assert frozenset(("bread", "strawberry")) not in pairs
