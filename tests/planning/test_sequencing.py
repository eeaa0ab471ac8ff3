"""The task level: exact and bounded search for the order of objects."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from llm_grop.errors import Infeasible
from llm_grop.planning.sequencing import best_order, lower_bound, refine, supports_before


def _brute(first, edge, end, before):  # type: ignore[no-untyped-def]
    best = (np.inf, ())
    for perm in itertools.permutations(range(len(first))):
        pos = {j: i for i, j in enumerate(perm)}
        if any(pos[a] > pos[b] for a, b in before):
            continue
        c = first[perm[0]] + end[perm[-1]] + sum(edge[a, b] for a, b in
                                             zip(perm, perm[1:], strict=False))
        best = min(best, (c, perm))
    return best


@pytest.mark.parametrize("seed", range(6))
def test_exact_matches_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 6
    first, end = rng.uniform(0, 10, n), rng.uniform(0, 10, n)
    edge = rng.uniform(0, 10, (n, n))
    before = [(0, 3), (3, 5)] if seed % 2 else []
    got = best_order(first, edge, end, before)
    cost, _ = _brute(first, edge, end, before)
    assert got.optimal and got.cost == pytest.approx(cost)
    pos = {j: i for i, j in enumerate(got.order)}
    assert all(pos[a] < pos[b] for a, b in before)


def test_branch_and_bound_matches_exact() -> None:
    rng = np.random.default_rng(3)
    n = 9
    pts = rng.uniform(0, 5, (n, 2))
    edge = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
    first, end = np.hypot(*pts.T), np.zeros(n)
    before = [(1, 2), (4, 7)]
    exact = best_order(first, edge, end, before)
    bnb = best_order(first, edge, end, before, exact_limit=0, node_budget=10**6)
    assert bnb.optimal and bnb.cost == pytest.approx(exact.cost)


def test_twenty_objects_keep_precedence_within_budget() -> None:
    rng = np.random.default_rng(1)
    n = 20
    pts = rng.uniform(0, 5, (n, 2))
    edge = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
    before = [(0, 1), (1, 2), (5, 6)]
    got = best_order(np.hypot(*pts.T), edge, np.zeros(n), before, node_budget=5000)
    assert sorted(got.order) == list(range(n)) and got.expanded <= 5001
    pos = {j: i for i, j in enumerate(got.order)}
    assert pos[0] < pos[1] < pos[2] and pos[5] < pos[6]


def test_supports_before_and_cycles() -> None:
    names = ["mug lid", "mug", "mug mat"]
    pairs = supports_before(names, {"mug lid": "mug", "mug": "mug mat", "mug mat": None})
    assert sorted(pairs) == [(1, 0), (2, 1)]
    with pytest.raises(Infeasible, match="cycle"):
        best_order(np.zeros(2), np.zeros((2, 2)), np.zeros(2), [(0, 1), (1, 0)],
                   names=["a", "b"])


@pytest.mark.parametrize("seed", range(4))
def test_local_search_states_a_true_bound(seed: int) -> None:
    # Beyond the exact limit the order is local search's; its bound never exceeds the
    # optimum, and refining keeps precedence and never costs more.
    rng = np.random.default_rng(seed)
    n = 9
    pts, pick = rng.uniform(0, 5, (n, 2)), rng.uniform(0, 5, (n, 2))
    edge = np.hypot(*(pts[:, None] - pick[None]).transpose(2, 0, 1)) - rng.uniform(0, 3, (n, 1))
    first, end = np.hypot(*pick.T), np.zeros(n)
    before = [(0, 4), (4, 7)]
    exact = best_order(first, edge, end, before)
    local = best_order(first, edge, end, before, exact_limit=0, node_budget=0)
    better = refine(first, edge, end, local, before)
    for got in (local, better):
        pos = {j: i for i, j in enumerate(got.order)}
        assert sorted(got.order) == list(range(n)) and pos[0] < pos[4] < pos[7]
        assert got.bound <= exact.cost + 1e-9 <= got.cost + 2e-9
        assert got.gap == pytest.approx(0.0 if got.optimal else got.cost - got.bound)
    assert better.cost <= local.cost + 1e-12


def test_lower_bound_is_the_assignment_relaxation() -> None:
    # Two far clusters: the relaxation may not close the tour, but never exceeds it.
    first, end = np.array([0.0, 10.0, 10.0]), np.zeros(3)
    edge = np.array([[np.inf, 10.0, 10.0], [10.0, np.inf, 1.0], [10.0, 1.0, np.inf]])
    assert lower_bound(first, edge, end) <= best_order(first, edge, end).cost
    assert lower_bound(np.zeros(1), np.full((1, 1), np.inf), np.zeros(1)) == 0.0
