"""GROP's choice with a fidelity weight: utility minus seconds per centimetre of infidelity."""

from __future__ import annotations

import pytest

from llm_grop.planning.grop import choose, evaluate
from llm_grop.planning.utility import GropOptions, PlanningContext
from llm_grop.world.catalog import Catalog
from llm_grop.world.fidelity import Fidelity
from llm_grop.world.request import items_from_names
from scenes import config, placement, two_table_room

FORK = (0.025, 0.2)


def _configs():
    # The faithful setting sits in front of the diner (-y edge, x = 0); the other one has
    # slid 0.25 m west, towards the counter the objects come from, so it is cheaper.
    faithful = config(placement("dinner plate", 0.0, -0.15),
                      placement("dinner fork", -0.17, -0.15, "box", FORK))
    cheaper = config(placement("dinner plate", -0.25, -0.15),
                     placement("dinner fork", -0.42 + 0.01, -0.15, "box", FORK))
    return (faithful, cheaper), (Fidelity(origin="dinner plate"),
                                 Fidelity(origin="dinner plate", origin_shift_m=0.25))


def _ctx(weight: float) -> PlanningContext:
    items = items_from_names(["dinner plate", "dinner fork"], Catalog.load(use_env=False))
    return PlanningContext(two_table_room(), items,
                           options=GropOptions(fidelity_w_s_per_cm=weight))


def test_the_least_costly_configuration_is_not_the_most_faithful() -> None:
    ctx = _ctx(0.0)
    (faithful, cheaper), _ = _configs()
    a, b = evaluate(ctx, faithful, 0), evaluate(ctx, cheaper, 1)
    assert not isinstance(a, str) and not isinstance(b, str)
    assert b.utility > a.utility


@pytest.mark.parametrize("weight", [0.0, 0.01, 0.1, 1.0, 10.0])
def test_the_choice_follows_the_documented_weight(weight: float) -> None:
    configs, fidelity = _configs()
    ctx = _ctx(weight)
    utilities = [evaluate(ctx, c, i).utility for i, c in enumerate(configs)]  # type: ignore[union-attr]
    scores = [u - weight * 100 * f.infidelity_m for u, f in zip(utilities, fidelity, strict=True)]
    cand = choose(ctx, configs, fidelity=fidelity)
    assert cand.index == max(range(2), key=lambda i: scores[i])
    assert cand.score == pytest.approx(scores[cand.index])
    assert [c.index for c in cand.considered] == [0, 1]
    assert cand.considered[1].fidelity.origin_shift_m == 0.25
    # Both sides of the break-even weight are exercised by the parameters.
    break_even = (utilities[1] - utilities[0]) / 25
    assert 0.01 < break_even < 10.0


def test_the_weight_must_be_finite_and_not_negative() -> None:
    from llm_grop.errors import BadInput
    for bad in (-1.0, float("inf"), float("nan")):
        with pytest.raises(BadInput, match="^fidelity_weight: must be"):
            GropOptions(fidelity_w_s_per_cm=bad)
